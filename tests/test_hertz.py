"""Hertz indentation: a rigid sphere pressed into a thick elastic block, against the closed form
F = 4/3 E* √R δ^1.5, E* = E / (1 − ν²) (Johnson, Contact Mechanics, 1985, §4.2, eq. 4.22-4.23).

Quarter model (symmetry planes x = 0 and y = 0), frictionless, small-strain linear elasticity,
float64, quasi-static (dynamic relaxation with the sphere's keyframed depth as the load step)."""

import math

import numpy as np
import pytest

import pliant as pl
from pliant.contact import Sphere

R, E, NU = 0.01, 1e4, 0.3          # sphere radius [m], Young's modulus [Pa], Poisson ratio
DEPTHS = np.array([0.0025, 0.005, 0.01]) * R   # δ [m]: contact radius a = √(Rδ) = 0.05–0.1 R


@pytest.fixture(scope="module")
def hertz_forces():
    # Mesh: cells of h = R/100 over the contact zone (a/h = 5, 7 and 10 at the three depths),
    # growing by 1.3 per cell to a block of 8.3 R = 83 a_max each way (196,608 tets).
    xs = pl.mesh.graded_coordinates(R / 100, 0.12 * R, 1.3, 8 * R)
    X, T = pl.mesh.grid_tets(xs, xs, -xs[::-1])
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(pl.LinearElastic(E=E, nu=NU), density=1000.0)
    b.fix(np.nonzero(X[:, 0] == 0.0)[0], "x")   # symmetry planes
    b.fix(np.nonzero(X[:, 1] == 0.0)[0], "y")
    bottom = np.nonzero(X[:, 2] == X[:, 2].min())[0]
    b.fix(bottom, "z")                             # roller: closer to a half-space than clamped
    tool = Sphere(R)                               # frictionless (μs = μk = 0)
    tool.at(0.0, (0.0, 0.0, R))                    # touching the top face z = 0 at the origin
    for k, d in enumerate(DEPTHS):
        tool.at(k + 1.0, (0.0, 0.0, R - d))        # keyframe k + 1: depth δ_k (load steps)
    b.add_tool(tool)
    sim = pl.Simulation(b.finalize("float64"))
    forces, reactions = [], []
    for k in range(len(DEPTHS)):
        # tol: relative out-of-balance force; 1e-4 and 1e-6 gave the same force to 5 digits.
        sim.solver.relax(sim.state, at_time=k + 1.0, tol=1e-5)
        forces.append(4 * sim.contact_report().relaxed[0][0][2])   # quarter model → whole
        f = sim.model.internal_forces(sim.state)
        reactions.append(4 * f[bottom, 2].sum())
        u = sim.displacements
        assert np.all(u[X[:, 0] == 0.0, 0] == 0.0) and np.all(u[X[:, 1] == 0.0, 1] == 0.0), \
            "contact moved a node off its symmetry plane"
        c = sim.positions - np.array([0.0, 0.0, R - DEPTHS[k]])
        assert np.linalg.norm(c, axis=1).min() >= R - 1e-9   # no node inside the sphere
    return np.array(forces), np.array(reactions)


def _hertz(delta):
    return 4.0 / 3.0 * E / (1 - NU ** 2) * math.sqrt(R) * delta ** 1.5


def test_force_matches_hertz_prefactor(hertz_forces):
    F, _ = hertz_forces
    ratio = F / _hertz(DEPTHS)
    # Tolerance 5 % (measured: 1.032, 1.034, 1.042). What separates this model from Hertz's
    # half-space: the finite block (about +0.9 a/L: +0.5 to +1 %); the tool acting on the deformed
    # surface while the linear theory applies the gap on the undeformed one (about +0.15 a/R: +0.4
    # to +1.5 %, measured by scaling R at fixed a/h); linear tets (+2 %, converging slowly: at
    # δ/R = 0.005, cells of R/200 or a grading of 1.2 instead of 1.3 give 1.032, a block twice as
    # large 1.031).
    np.testing.assert_allclose(ratio, 1.0, atol=0.05)


def test_force_grows_as_depth_to_the_three_halves(hertz_forces):
    F, _ = hertz_forces
    exponent = np.polyfit(np.log(DEPTHS), np.log(F), 1)[0]
    # 1.5 ± 0.03: the depth-dependent errors above (a/L and a/R grow with δ, a/h too) tilt the
    # fit by about log(1.02)/log(4) ≈ 0.015.
    assert abs(exponent - 1.5) < 0.03


def test_tool_force_is_what_the_supports_carry(hertz_forces):
    F, reaction = hertz_forces
    # Global equilibrium: the tool's reported force equals the supports' reaction, to the
    # dynamic-relaxation tolerance (1e-5 relative out-of-balance force; measured: 2e-4).
    np.testing.assert_allclose(reaction, F, rtol=2e-3)
