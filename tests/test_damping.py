"""Stiffness-proportional (Rayleigh β) damping against closed forms: it spares rigid motion (free
fall and Coulomb sliding keep their exact accelerations), damps a bending mode at the rate
β ω²/2 that C = βK gives it, and shrinks the stable step as Belytschko's bound says."""

from __future__ import annotations

import math

import numpy as np
import pytest

import pliant as pl
from pliant.contact import Plane
from pliant.validate.models import decay_of_first_mode, ringing_cantilever

G = 9.81


def _block(size=(0.02, 0.02, 0.02), cells=(4, 4, 4), E=2e6, nu=0.3, beta=0.0):
    X, T = pl.mesh.box_tets(size, cells, origin=(-size[0] / 2, -size[1] / 2, 0.0))
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(pl.NeoHookean(E=E, nu=nu), density=1000.0)
    b.stiffness_damping = beta
    return X, b


def test_free_fall_is_not_damped(backend):
    """A free body under gravity: no strain rate, no damping force; u_n = g Δt² n(n + 1)/2, the
    central-difference solution of ü = g from rest, to round-off, and the same bits as β = 0."""
    runs = []
    for beta in (0.0, 1e-4):
        X, b = _block(beta=beta)
        b.set_gravity((0.0, 0.0, -G))
        sim = pl.Simulation(b.finalize("float64", backend=backend), dt=1e-5)
        sim.run(steps=500)
        runs.append(sim.displacements)
    assert np.array_equal(runs[0], runs[1])
    n = 500
    assert np.allclose(runs[1][:, 2], -G * 1e-10 * n * (n + 1) / 2, rtol=1e-12, atol=0)


def test_sliding_keeps_coulomb_acceleration():
    """A block sliding down a frictional incline with β damping (its first mode damped about 4 %):
    a = g (sin θ − μk cos θ), as without damping (tests/test_contact.py); mass-proportional damping
    α would brake it towards a terminal velocity instead."""
    theta, mu_k = math.atan(0.5), 0.2
    X, b = _block(beta=2e-5)
    b.set_gravity((G * math.sin(theta), 0.0, -G * math.cos(theta)))
    b.add_tool(Plane((0, 0, 0), (0, 0, 1), mu_s=0.5, mu_k=mu_k))
    model = b.finalize("float64")
    sim = pl.Simulation(model)
    t, x = [], []
    for k in range(30):
        sim.run(until=0.3 * (k + 1) / 30)
        t.append(sim.time)
        x.append(np.sum(model.mass * sim.positions[:, 0]) / model.mass.sum())
    a = 2 * np.polyfit(t[5:], x[5:], 2)[0]  # after the first contact transient
    # Elastic ringing rides on the rigid-body motion, as in test_contact: 3 %.
    assert a == pytest.approx(G * (math.sin(theta) - mu_k * math.cos(theta)), rel=0.03)


def test_first_bending_mode_decays_at_beta_omega_squared_over_two():
    """Released from its static deflection, the tip rings at the first bending frequency ω and
    decays as exp(−σt) with σ = ζω = β ω²/2 (C = βK: ζ = βω/2 in every mode; Chopra, Dynamics of
    Structures, §11.4). ω is measured from the zero crossings (the prediction then holds for the
    discrete beam, whatever its stiffness error); σ from a log fit of the peaks after the first
    two periods (higher modes decay (ω_n/ω)² faster and are gone by then). Tolerance 2 %: the
    half-step velocity's lag and peak sampling (T/400) each err below 0.1 %; what is left is the
    fit over five peaks of a signal that carries a little of other modes (1.0 % here)."""
    beta = 4e-4
    model, tip = ringing_cantilever(beta=beta)
    omega, sigma = decay_of_first_mode(model, tip)
    assert 0.005 < beta * omega / 2 < 0.1  # a damping ratio that the test can measure (0.9 %)
    assert sigma == pytest.approx(beta * omega**2 / 2, rel=0.02)


def test_stable_step_shrinks_with_beta():
    """Δt_cr = (2/ω_max)(√(1 + ξ²) − ξ), ξ = β ω_max/2 (Belytschko, Liu & Moran 2000, eq. 6.3.18):
    the model says so, a run at the default 0.8 Δt_cr stays bounded (0.9 Δt_cr is 1.8 % above the
    exact damped limit the solver computes, and refused), and a step 3 Δt_cr (stable without β)
    blows up with it."""
    beta = 5e-4
    plain = ringing_cantilever()[0]
    model = ringing_cantilever(beta=beta)[0]
    dt0 = plain.dt_critical
    xi = beta / dt0
    assert model.dt_critical == pytest.approx(dt0 * (math.sqrt(1 + xi * xi) - xi), rel=1e-12)
    assert model.dt_critical < 0.1 * dt0
    stable = pl.Simulation(model, dt=0.8 * model.dt_critical)
    stable.run(steps=4000)
    assert np.abs(stable.displacements).max() < 1e-3
    undamped = pl.Simulation(plain, dt=3 * model.dt_critical)
    undamped.run(steps=4000)
    assert np.abs(undamped.displacements).max() < 1e-3
    with pytest.raises(pl.InstabilityError):
        pl.Simulation(model, dt=3 * model.dt_critical, allow_unstable=True).run(steps=4000)
