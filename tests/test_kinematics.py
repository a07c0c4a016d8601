"""Patch test and rigid rotation: consistency of the element formulation."""

import numpy as np
import pytest

import pliant as pl


def _jittered_cube(cells=4):
    return pl.mesh.box_tets((1.0, 1.0, 1.0), (cells,) * 3, jitter=0.3, seed=3)


def test_patch_test_affine_field(dtype):
    """An affine displacement u = A X + c imposed on the boundary is reproduced at interior nodes
    (homogeneous deformation is an exact equilibrium for any material; linear tets represent it)."""
    X, T = _jittered_cube()
    A = np.array([[0.10, 0.05, -0.02], [0.03, -0.06, 0.04], [-0.05, 0.02, 0.08]])
    c = np.array([0.01, -0.02, 0.03])
    u_exact = X @ A.T + c
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(pl.MooneyRivlin(C10=400.0, C01=100.0, K=8e3), density=1000.0)
    boundary = np.nonzero(np.any((X < 1e-9) | (X > 1 - 1e-9), axis=1))[0]
    interior = np.setdiff1d(np.arange(len(X)), boundary)
    assert interior.size > 10
    b.prescribe(boundary, u_exact[boundary], "xyz", curve=pl.Ramp(1.0))
    model = b.finalize(dtype)
    sim = pl.Simulation(model)
    sim.relax(tol=1e-5 if dtype == "float32" else 1e-10, increments=2)
    err = np.abs(sim.displacements[interior] - u_exact[interior]).max()
    # Displacement error ≈ residual × (size of u): 1e-5 relative residual in float32, 1e-10 in float64.
    bound = 2e-5 if dtype == "float32" else 1e-8
    assert err <= bound * np.abs(u_exact).max(), err
    # Uniform stress: every element's Cauchy stress equals the mean one.
    sig = model.element_results(sim.state)["cauchy"]
    scale = np.abs(sig).max()
    assert np.abs(sig - sig.mean(axis=0)).max() <= (1e-3 if dtype == "float32" else 1e-6) * scale


@pytest.mark.parametrize(
    "material",
    [
        pl.NeoHookean(mu=1e3, K=1e4),
        pl.MooneyRivlin(300, 200, 1e4),
        pl.NeoHookeanCoupled(mu=1e3, lam=1e4),
        pl.StVenantKirchhoff(mu=1e3, lam=1e4),
    ],
    ids=lambda m: type(m).__name__,
)
def test_rigid_rotation_is_stress_free(material, dtype):
    """A rigid rotation by 90° about an oblique axis gives zero stress and zero internal force
    (objectivity of the hyperelastic laws)."""
    X, T = _jittered_cube(3)
    axis = np.array([1.0, 2.0, 2.0]) / 3.0
    Kx = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    R = np.eye(3) + Kx + Kx @ Kx  # Rodrigues for θ = 90°: I + sin θ K + (1 − cos θ) K²
    assert np.allclose(R @ R.T, np.eye(3))
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(material, density=1000.0)
    model = b.finalize(dtype)
    s = model.state()
    s.set_displacements(X @ R.T - X)
    res = model.element_results(s)
    eps = np.finfo(dtype).eps
    # Round-off: F has O(1) entries with error ~eps, so stress error ~ 100 eps × modulus.
    assert np.abs(res["cauchy"]).max() <= 100 * eps * 1e4
    assert np.abs(res["J"] - 1).max() <= 100 * eps
    f = model.internal_forces(s)
    assert np.abs(f).max() <= 100 * eps * 1e4 * (1.0 / 3) ** 2


def test_rigid_rotation_linear_elastic_is_not_objective():
    """Small-strain linear elasticity is not objective: a 90° rotation gives spurious stress of the
    order of the modulus. This documents why it is only a small-displacement baseline."""
    X, T = _jittered_cube(2)
    R = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(pl.LinearElastic(E=1e4, nu=0.3), density=1000.0)
    model = b.finalize("float64")
    s = model.state()
    s.set_displacements(X @ R.T - X)
    assert np.abs(model.element_results(s)["cauchy"]).max() > 1e3
