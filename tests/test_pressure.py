"""Follower pressure on surface triangles against closed forms: hydrostatic compression of every
material (a homogeneous state, which linear tets represent exactly) and uniaxial compression by a
pressure that follows the shrinking or growing loaded face."""

import numpy as np
import pytest
from scipy.optimize import brentq

import pliant as pl
from pliant.errors import InputError
from pliant.mesh.topology import boundary_faces
from pliant.validate.references import UNIAXIAL, nominal, uniaxial_reference

L, TOL = 1.0, 1e-9


def _cube(material, dtype="float64"):
    """Jittered tet cube [0, L]³ with symmetry planes x = 0, y = 0, z = 0."""
    X, T = pl.mesh.box_tets((L, L, L), (3, 3, 3), jitter=0.25, seed=1)
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(material, density=1000.0)
    for d in range(3):
        b.fix(np.nonzero(X[:, d] < TOL)[0], "xyz"[d])
    B, _ = boundary_faces(T)
    on = [B[np.all(X[B][:, :, d] > L - TOL, axis=1)] for d in range(3)]  # faces x = L, y = L, z = L
    return X, b, on


@pytest.mark.parametrize("name", list(UNIAXIAL))
def test_hydrostatic_pressure_gives_the_closed_form_volume(name):
    """p on the three outer faces: σ = −p I, a uniform stretch λ with σ = P(λ, λ, λ)/λ² = −p, P the
    nominal stress ∂W/∂λ of the strain energy (test_uniaxial), independent of the engine's code."""
    material, W, _ = UNIAXIAL[name]
    p = 300.0  # Pa: 30 % of μ, a volume change of a few percent
    X, b, on = _cube(material)
    b.add_pressure(np.vstack(on), p, curve=pl.Ramp(1.0))
    sim = pl.Simulation(b.finalize("float64"))
    sim.relax(tol=1e-9, increments=4)
    lam_ref = brentq(lambda s: nominal(W, (s, s, s), 0) / s**2 + p, 0.5, 1.0, xtol=1e-14)
    corner = np.argmax(X.sum(axis=1))
    # 1e-7: the relaxation tolerance (1e-9) far below it; the state is exact in the FE space.
    np.testing.assert_allclose(1 + sim.displacements[corner] / L, lam_ref, rtol=1e-7)


@pytest.mark.parametrize("p", [300.0, -300.0])
def test_pressure_follows_the_loaded_face(p):
    """p on the face x = L only (compression, or suction for p < 0): the Cauchy stress there is
    −p on the deformed area, P_x / λ_lat² = −p with the uniaxial closed form. A dead load (p on
    the reference area, P_x = −p) would be off by the area change, 7–15 % here."""
    material, W, _ = UNIAXIAL["NeoHookean"]
    X, b, on = _cube(material)
    b.add_pressure(on[0], p, curve=pl.Ramp(1.0))
    sim = pl.Simulation(b.finalize("float64"))
    sim.relax(tol=1e-9, increments=4)

    def cauchy_plus_p(stretch):
        P, lt = uniaxial_reference(W, stretch)
        return P / lt**2 + p

    lam = brentq(cauchy_plus_p, 0.5, 1.8, xtol=1e-12)
    dead = brentq(lambda s: uniaxial_reference(W, s)[0] + p, 0.5, 1.8, xtol=1e-12)
    right = X[:, 0] > L - TOL
    got = 1 + sim.displacements[right, 0].mean() / L
    assert abs(dead - lam) > 0.02 * abs(lam - 1)  # the test can tell the two apart
    # 1e-6: numerical differentiation in the reference (h = 1e-6) and the relaxation tolerance.
    assert abs(got - lam) <= 1e-6, (got, lam, dead)


def test_pressure_float32_and_bad_faces():
    material = UNIAXIAL["NeoHookean"][0]
    X, b, on = _cube(material)
    b.add_pressure(np.vstack(on), 300.0, curve=pl.Ramp(1.0))
    s64 = pl.Simulation(b.finalize("float64"))
    s64.relax(tol=1e-9, increments=4)
    s32 = pl.Simulation(b.finalize("float32"))
    s32.relax(tol=1e-5, increments=4)
    # float32 relaxed to a 1e-5 residual: displacement errors of a few 1e-4 of the largest one
    # (measured 3e-4), the residual amplified by the stiffness spread of the jittered cube.
    np.testing.assert_allclose(
        s32.displacements, s64.displacements, atol=1e-3 * np.abs(s64.displacements).max()
    )
    interior = np.array([[0, 1, 2]])  # not a boundary triangle of the cube
    with pytest.raises(InputError, match="face 0 .* not on the mesh boundary"):
        b.add_pressure(interior, 1.0)
    with pytest.raises(InputError, match=r"pressure = \[1.0, 1.0, 1.0\] \(shape \(3,\)\)"):
        b.add_pressure(on[0], np.ones(3))
    with pytest.raises(InputError, match="pressure = True"):
        b.add_pressure(on[0], True)


def test_hydrostatic_pressure_with_average_nodal_pressure():
    """T4ANP on a homogeneous state changes nothing: the same stretch, and every element's
    reported Cauchy stress (computed with the averaged pressure the forces see) is −p I."""
    material, W, _ = UNIAXIAL["NeoHookean"]
    p = 300.0
    X, b, on = _cube(material)
    b.nodal_pressure = True
    b.add_pressure(np.vstack(on), p, curve=pl.Ramp(1.0))
    model = b.finalize("float64")
    sim = pl.Simulation(model)
    sim.relax(tol=1e-10, increments=4)
    lam_ref = brentq(lambda s: nominal(W, (s, s, s), 0) / s**2 + p, 0.5, 1.0, xtol=1e-14)
    corner = np.argmax(X.sum(axis=1))
    np.testing.assert_allclose(1 + sim.displacements[corner] / L, lam_ref, rtol=1e-7)
    sigma = model.element_results(sim.state)["cauchy"]
    # 1e-5 p: the relaxation tolerance (1e-10 of the loads) amplified by the element stiffness.
    np.testing.assert_allclose(sigma[:, :3], -p, atol=1e-5 * p)
    np.testing.assert_allclose(sigma[:, 3:], 0.0, atol=1e-5 * p)
