"""Viscoelastic (Prony series) materials against the closed form of linear viscoelasticity."""

import math

import numpy as np
import pytest

import pliant as pl
from pliant.validate.references import K, MU, W_nh, nominal, uniaxial_reference


SERIES = {  # Prony series (α_i, τ_i [s]), each on the isochoric and the volumetric stress alike
    "one term": [(0.4, 0.05)],
    "one term split in three": [(0.4 / 3, 0.05)] * 3,
    "four terms": [(0.1, 0.01), (0.1, 0.03), (0.1, 0.05), (0.1, 0.1)],  # 8 in all: the most
}


@pytest.mark.parametrize("smoothing", ["element", "edge"])
@pytest.mark.parametrize("series", SERIES)
def test_stress_relaxation_after_a_ramp_follows_the_prony_series(smoothing, series):
    """Uniaxial stretch 1.001 ramped in t_r = 2 ms, then held. With the same Prony series on the
    isochoric and the volumetric stress, every stress component relaxes by the same factor, so the
    held deformation stays homogeneous and the nominal stress is P_e − Σ D_i:
    D_i(t) = α_i P_e [1 − (τ_i/t_r)(e^(−(t−t_r)/τ_i) − e^(−t/τ_i))] for t > t_r (the Prony convolution
    of the ramp; NiftySim user guide App. A.2, eq. 9). P_e: the elastic (instantaneous) response.
    With edge-smoothed strain the Prony state lives on the edges: the same closed form. Series: one
    term; the same term split into three equal ones (α/3 each: the same series, 6 terms in all);
    four distinct ones on each part (8 terms, the most a material takes)."""
    terms, t_r, stretch, L = SERIES[series], 0.002, 1.001, 0.01
    material = pl.Viscoelastic(pl.NeoHookean(mu=MU, K=K), iso=terms, vol=terms)
    sim = pl.Simulation(_cube(material, stretch, L, t_r, smoothing), dt=2e-6)
    P_e = uniaxial_reference(W_nh, stretch)[0] * L * L  # [N] on the face of area L²
    for t in (0.03, 0.05, 0.1, 0.2):
        sim.run(until=t)
        F = sim.model.internal_forces(sim.state)[_right(sim), 0].sum()
        tt = sim.time
        D = sum(
            a * P_e * (1 - tau / t_r * (math.exp(-(tt - t_r) / tau) - math.exp(-tt / tau)))
            for a, tau in terms
        )
        # 1 %: backward-Euler integration of the state (Δt/τ ≤ 2e-4), the elastic waves left by
        # the ramp (damped by α_d = 1000/s: e^(−15) by 0.03 s) and the nonlinearity at strain 1e-3.
        assert abs(F - (P_e - D)) <= 0.01 * P_e, (tt, F, P_e - D)


def _cube(material, stretch, L, t_r, smoothing="element"):
    X, T = pl.mesh.box_tets((L, L, L), (3, 3, 3), jitter=0.25, seed=1)
    b = pl.ModelBuilder()
    b.strain_smoothing = smoothing
    b.add_mesh(X, T)
    b.set_material(material, density=1000.0)
    for d in range(3):
        b.fix(np.nonzero(X[:, d] < 1e-9 * L)[0], "xyz"[d])
    b.prescribe(np.nonzero(X[:, 0] > L * (1 - 1e-9))[0], (stretch - 1) * L, "x", curve=pl.Ramp(t_r))
    b.damping = 1000.0  # about critical for the slowest mode (ω ≈ πc/(2L) ≈ 500/s)
    return b.finalize("float64")


def _right(sim):
    X = sim.model.reference_positions
    return np.nonzero(X[:, 0] > X[:, 0].max() * (1 - 1e-9))[0]


@pytest.mark.parametrize("smoothing", ["element", "edge"])
def test_quasi_static_solution_is_the_fully_relaxed_one_and_state_round_trips(tmp_path, smoothing):
    """Dynamic relaxation is infinitely slow loading: the stress is the long-term one, (1 − α) P_e
    with the same α on both parts; the stored viscous state is then the relaxed one, so a dynamic
    run continuing from it stays put; save/load carries the state (same bits after more steps)."""
    alpha, stretch, L = 0.3, 1.001, 0.01
    material = pl.Viscoelastic(pl.NeoHookean(mu=MU, K=K), iso=[(alpha, 0.05)], vol=[(alpha, 0.05)])
    sim = pl.Simulation(_cube(material, stretch, L, 0.002, smoothing), dt=2e-6)
    sim.relax(tol=1e-10)
    P_e = uniaxial_reference(W_nh, stretch)[0] * L * L
    F = sim.model.internal_forces(sim.state)[_right(sim), 0].sum()
    assert abs(F - (1 - alpha) * P_e) <= 1e-6 * P_e  # relaxation tolerance, exact FE space
    sim.run(steps=2000)
    F2 = sim.model.internal_forces(sim.state)[_right(sim), 0].sum()
    assert abs(F2 - F) <= 1e-6 * P_e
    sim.state.save(tmp_path / "s.npz")
    sim.run(steps=500)
    u_ref = sim.displacements.copy()
    other = pl.Simulation(sim.model, dt=2e-6)
    other.state.load(tmp_path / "s.npz")
    other.run(steps=500)
    assert np.array_equal(other.displacements, u_ref)


def _ramp_relaxation(t, tau, t_r):
    """g(t) of a Prony term τ after a linear ramp of t_r held from then on (t > t_r)."""
    return 1 - tau / t_r * (math.exp(-(t - t_r) / tau) - math.exp(-t / tau))


def _held_stretch(stretch, L, X):
    """The Neo-Hookean's isochoric and volumetric face forces P_iso, P_vol [N] of the stretch
    (λ, 1, 1) on a face of area L² (∂W/∂λ of each part, differentiated numerically), and the nodes
    of X on that face (x = L)."""
    lam = (stretch, 1.0, 1.0)
    P_iso = nominal(lambda s: W_nh(s, k=0.0), lam, 0) * L * L
    P_vol = nominal(lambda s: W_nh(s, mu=0.0), lam, 0) * L * L
    return P_iso, P_vol, np.nonzero(X[:, 0] > L * (1 - 1e-9))[0]


@pytest.mark.parametrize("smoothing", ["element", "edge"])
@pytest.mark.parametrize("terms", [1, 3])
def test_isochoric_relaxation_of_a_held_homogeneous_stretch(backend, terms, smoothing):
    """Every node prescribed (u = (λ − 1) X along x, ramped in t_r, then held): the deformation is
    homogeneous at all times and only the isochoric stress relaxes, P_x = P_iso (1 − α g(t)) + P_vol
    with g(t) = 1 − (τ/t_r)(e^(−(t−t_r)/τ) − e^(−t/τ)) (the ramp's Prony convolution, as above).
    P_iso and P_vol: ∂W/∂λ of the Neo-Hookean's two parts, differentiated numerically. One term α,
    or three of α/3 with the same τ (the same series)."""
    alpha, tau, t_r, stretch, L = 0.45, 0.02, 0.002, 1.001, 0.01
    iso = [(alpha / terms, tau)] * terms
    material = pl.Viscoelastic(pl.NeoHookean(mu=MU, K=K), iso=iso)
    X, T = pl.mesh.box_tets((L, L, L), (2, 2, 2), jitter=0.25, seed=2)
    b = pl.ModelBuilder()
    b.strain_smoothing = smoothing
    b.add_mesh(X, T)
    b.set_material(material, density=1000.0)
    u = np.zeros_like(X)
    u[:, 0] = (stretch - 1) * X[:, 0]
    b.prescribe(np.arange(len(X)), u, "xyz", curve=pl.Ramp(t_r))
    sim = pl.Simulation(b.finalize("float64", backend=backend), dt=2e-6)
    P_iso, P_vol, right = _held_stretch(stretch, L, X)
    for t in (0.005, 0.02, 0.06):
        sim.run(until=t)
        F = sim.model.internal_forces(sim.state)[right, 0].sum()
        tt = sim.time
        g = _ramp_relaxation(tt, tau, t_r)
        # 0.2 % of P_iso: the ramp's stress is linear in t only to the strain's order (1e-3),
        # backward Euler's error is of order Δt/τ = 1e-4, the numerical derivative 1e-9.
        assert abs(F - (P_iso * (1 - alpha * g) + P_vol)) <= 2e-3 * P_iso, (tt, F, P_iso, P_vol)


@pytest.mark.parametrize("smoothing", ["element", "edge"])
def test_materials_with_as_many_terms_split_differently_relax_by_their_own_series(backend, smoothing):
    """Two cubes in one model, both with two Prony terms: A's both isochoric, B's one isochoric and
    one volumetric (a launch runs the isochoric terms, then the volumetric ones, so groups whose
    counts differ in that split must not share one). Each cube held at a homogeneous stretch (as
    above): A's face force P_iso (1 − α1 g1 − α2 g2) + P_vol, B's P_iso (1 − α1 g1) + P_vol (1 − β g2)."""
    (a1, tau1), (a2, tau2), t_r, stretch, L = (0.3, 0.01), (0.2, 0.04), 0.002, 1.001, 0.01
    nh = pl.NeoHookean(mu=MU, K=K)
    cubes = (
        pl.Viscoelastic(nh, iso=[(a1, tau1), (a2, tau2)]),
        pl.Viscoelastic(nh, iso=[(a1, tau1)], vol=[(a2, tau2)]),
    )
    X, T = pl.mesh.box_tets((L, L, L), (2, 2, 2), jitter=0.25, seed=2)
    b = pl.ModelBuilder()
    b.strain_smoothing = smoothing
    u = np.zeros_like(X)
    u[:, 0] = (stretch - 1) * X[:, 0]
    for k, material in enumerate(cubes):
        cube = b.add_mesh(X + (2 * L * k, 0.0, 0.0), T)
        b.set_material(material, density=1000.0, elements=cube)
        b.prescribe(k * len(X) + np.arange(len(X)), u, "xyz", curve=pl.Ramp(t_r))
    sim = pl.Simulation(b.finalize("float64", backend=backend), dt=2e-6)
    P_iso, P_vol, right = _held_stretch(stretch, L, X)
    for t in (0.005, 0.02, 0.06):
        sim.run(until=t)
        f = sim.model.internal_forces(sim.state)[:, 0]
        g1, g2 = _ramp_relaxation(sim.time, tau1, t_r), _ramp_relaxation(sim.time, tau2, t_r)
        expected = (P_iso * (1 - a1 * g1 - a2 * g2) + P_vol, P_iso * (1 - a1 * g1) + P_vol * (1 - a2 * g2))
        for k in (0, 1):
            F = f[k * len(X) + right].sum()
            # 0.2 % of the elastic force, as above (the ramp's nonlinearity, backward Euler's Δt/τ).
            assert abs(F - expected[k]) <= 2e-3 * (P_iso + P_vol), (k, sim.time, F, expected[k])


def test_viscoelastic_inputs_are_checked():
    nh = pl.NeoHookean(mu=MU, K=K)
    with pytest.raises(pl.MaterialError, match="decoupled"):
        pl.Viscoelastic(pl.StVenantKirchhoff(mu=MU, lam=K), iso=[(0.3, 0.1)])
    with pytest.raises(pl.MaterialError, match="sum"):
        pl.Viscoelastic(nh, iso=[(0.6, 0.1), (0.5, 1.0)])
    with pytest.raises(pl.MaterialError, match="tau"):
        pl.Viscoelastic(nh, vol=[(0.2, 0.0)])
    X, T = pl.mesh.box_tets((L0 := 0.01, L0, L0), (2, 2, 2))
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(pl.Viscoelastic(nh, iso=[(0.3, 0.1)]), density=1000.0)
    b.nodal_pressure = True
    with pytest.raises(pl.MaterialError, match="cannot be combined"):
        b.finalize()
