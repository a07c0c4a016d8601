"""Uniaxial tension/compression of an unstructured tet cube against the closed-form stress–stretch
relation of each hyperelastic material (zero lateral stress), quasi-static by dynamic relaxation.

Reference: principal nominal stress P_i = ∂W/∂λ_i of the strain energy written in principal stretches
(Ogden 1984, §4.3), differentiated numerically in float64 here — independent of the engine's
stress code, which works with C, C⁻¹ and invariants.
"""

import numpy as np
import pytest

import pliant as pl
from pliant.validate.models import cube_with_symmetry_bcs
from pliant.validate.references import K, MU, UNIAXIAL, nominal, uniaxial_reference

MATERIALS = {name: (material, W) for name, (material, W, _) in UNIAXIAL.items()}
# Stretches per material (pliant.validate.references.UNIAXIAL says why some differ).
CASES = [(n, s) for n, (_, _, stretches) in UNIAXIAL.items() for s in stretches]


@pytest.mark.parametrize("name, stretch", CASES)
def test_uniaxial_stress_stretch(name, stretch, dtype):
    material, W = MATERIALS[name]
    X, model, right = cube_with_symmetry_bcs(material, stretch, dtype=dtype)
    sim = pl.Simulation(model)
    # 1e-5 relative residual is 20× below the 0.5 % bound; float32 round-off floors near 4e-6.
    sim.relax(tol=1e-5, increments=10)
    P_ref, lt_ref = uniaxial_reference(W, stretch)
    # Reaction on the loaded face / reference area = nominal stress P_x.
    P = model.internal_forces(sim.state)[right, 0].sum() / 1.0
    assert abs(P - P_ref) <= 5e-3 * abs(P_ref), (P, P_ref)
    top = X[:, 1] > 1 - 1e-9
    lt = 1 + sim.displacements[top, 1].mean()
    assert abs(lt - lt_ref) <= 5e-3 * lt_ref
    # Element stresses: Cauchy σ_xx = P_x λ / J, lateral σ ≈ 0 (relative to σ_xx).
    sig = model.element_results(sim.state)["cauchy"]
    sxx_ref = P_ref * stretch / (stretch * lt_ref**2)
    assert np.allclose(sig[:, 0], sxx_ref, rtol=5e-3)
    assert np.max(np.abs(sig[:, 1:])) <= 5e-3 * abs(sxx_ref)


def test_linear_elastic_small_strain():
    """Small-strain linear elasticity: P_x = E ε, lateral strain −ν ε (Hooke's law)."""
    E, nu, eps = 5e3, 0.3, 1e-3
    X, model, right = cube_with_symmetry_bcs(pl.LinearElastic(E=E, nu=nu), 1 + eps, dtype="float64")
    sim = pl.Simulation(model)
    sim.relax(tol=1e-8)
    P = model.internal_forces(sim.state)[right, 0].sum()
    assert abs(P - E * eps) <= 1e-5 * E * eps  # exact in the FE space; DR tolerance 1e-8
    top = X[:, 1] > 1 - 1e-9
    assert np.allclose(sim.displacements[top, 1], -nu * eps, rtol=1e-5)


# Small-strain limit of every isotropic material above: Hooke's law with its own μ and K.
E0, NU0 = 9 * K * MU / (3 * K + MU), (3 * K - 2 * MU) / (6 * K + 2 * MU)
SMALL = {name: m for name, (m, _) in MATERIALS.items() if name != "TransverselyIsotropic"}
SMALL["LinearElastic"] = pl.LinearElastic(E=E0, nu=NU0)


@pytest.mark.parametrize("name", list(SMALL))
def test_float32_resolves_a_strain_of_1e_6(name):
    """Every material at a strain of 1e-6 in float32 gives Hooke's law, P_x = E ε and lateral
    strain −ν ε. Stresses are formed from H = ∇u, not from F − I: F − I in float32 carries an
    absolute error of 6e-8, 6 % of this strain."""
    material = SMALL[name]
    E, nu = (
        9 * material.bulk_modulus * material.mu / (3 * material.bulk_modulus + material.mu),
        (3 * material.bulk_modulus - 2 * material.mu) / (6 * material.bulk_modulus + 2 * material.mu),
    )
    eps = 1e-6
    X, model, right = cube_with_symmetry_bcs(material, 1 + eps, dtype="float32")
    sim = pl.Simulation(model)
    sim.relax(tol=1e-5)
    P = model.internal_forces(sim.state)[right, 0].sum()
    # 1e-3: the residual tolerance (1e-5) and float32 rounding of u (1e-7 relative) are far
    # below it; the nonlinear terms are O(ε) = 1e-6.
    assert abs(P - E * eps) <= 1e-3 * E * eps, (P, E * eps)
    top = X[:, 1] > 1 - 1e-9
    assert np.allclose(sim.displacements[top, 1], -nu * eps, rtol=1e-3)


def test_transversely_isotropic_fibres_across_the_load():
    """Fibres along y, stretch 1.2 along x: the two lateral stretches differ (stiff along the
    fibres); reference from P_y = P_z = 0 of W in principal stretches (fibres on a principal axis)."""
    from scipy.optimize import fsolve

    eta = 2 * MU

    def W(l):
        J = l[0] * l[1] * l[2]
        I1b = J ** (-2 / 3) * sum(x * x for x in l)
        return MU / 2 * (I1b - 3) + eta / 2 * (J ** (-2 / 3) * l[1] ** 2 - 1) ** 2 + K / 2 * (J - 1) ** 2

    s = 1.2
    ty, tz = fsolve(
        lambda t: [nominal(W, (s, t[0], t[1]), 1), nominal(W, (s, t[0], t[1]), 2)], [0.95, 0.9], xtol=1e-13
    )
    X, model, right = cube_with_symmetry_bcs(
        pl.TransverselyIsotropic(MU, K, eta, (0, 3, 0)), s, dtype="float64"
    )
    sim = pl.Simulation(model)
    sim.relax(tol=1e-8, increments=10)
    P = model.internal_forces(sim.state)[right, 0].sum()
    assert abs(P - nominal(W, (s, ty, tz), 0)) <= 1e-5 * abs(P)  # exact in the FE space
    u = sim.displacements
    assert np.isclose(1 + u[X[:, 1] > 1 - 1e-9, 1].mean(), ty, rtol=1e-6)
    assert np.isclose(1 + u[X[:, 2] > 1 - 1e-9, 2].mean(), tz, rtol=1e-6)
    assert ty > tz + 0.01  # the fibres resist the lateral contraction along y
