"""Support reactions: Model.external_forces, Model.reactions and Model.support_reactions (the force
each fix / prescribe call's nodes receive from their support, f − r over its DOFs), and their file,
reactions.json, from `pliant run`. References: statics (a body's weight and the loads on it are
carried by its supports), and the uniaxial nominal stress of the strain energy in principal
stretches (Ogden 1984, §4.3), computed apart from the engine's stress code."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import pliant as pl
from pliant.mesh import box_tets
from pliant.validate.models import cube_with_symmetry_bcs
from pliant.validate.references import UNIAXIAL, uniaxial_reference

RHO, G = 1000.0, 9.81


def _hanging_block(backend: str, dtype: str = "float64"):
    """A 4 × 2 × 2 cm block, fixed at its top face, hanging under gravity with a 0.05 N point load
    on its bottom face (along −z and +x), relaxed: (model, state, top ids, bottom ids)."""
    X, T = box_tets((0.04, 0.02, 0.02), (4, 2, 2), jitter=0.2, seed=4)
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(pl.NeoHookean(E=2e4, nu=0.4), density=RHO)
    b.set_gravity((0.0, 0.0, -G))
    top = np.nonzero(X[:, 2] > 0.02 - 1e-9)[0]
    bottom = np.nonzero(X[:, 2] < 1e-9)[0]
    b.fix(top, name="ceiling")
    b.add_force(bottom, np.array([0.01, 0.0, -0.05]) / len(bottom))
    sim = pl.Simulation(b.finalize(dtype, backend=backend))
    sim.relax(tol=1e-9)
    return sim.model, sim.state, top, bottom


def test_a_hanging_block_hangs_from_its_support_by_its_weight_and_load(backend):
    """The ceiling holds the block's weight ρ V g and the point load: (−0.01, 0, 0.05 + ρ V g) N.
    Tolerance 1e-7 of the weight: the relaxation's residual (1e-9 of the loads and reactions) and
    float64 sums."""
    model, state, top, _ = _hanging_block(backend)
    weight = RHO * 0.04 * 0.02 * 0.02 * G
    expected = np.array([-0.01, 0.0, 0.05 + weight])
    reaction = model.support_reactions(state)["ceiling"]
    np.testing.assert_allclose(reaction, expected, rtol=0, atol=1e-7 * weight)
    np.testing.assert_array_equal(model.reactions(state, top), reaction)
    # Along z only: the other components left out.
    assert model.reactions(state, top, "z")[:2].tolist() == [0.0, 0.0]


def test_the_external_forces_are_the_weight_and_the_loads(backend):
    """Σ r = m g + the point loads (gravity is m_a g on each node, with the lumped masses, whose
    sum is ρ V); 1e-12 relative, float64 sums."""
    model, state, _, bottom = _hanging_block(backend)
    r = model.external_forces(state)
    weight = RHO * 0.04 * 0.02 * 0.02 * G
    np.testing.assert_allclose(r.sum(axis=0), [0.01, 0.0, -0.05 - weight], rtol=0, atol=1e-12 * weight)
    np.testing.assert_allclose(
        r[:, 2], -model.mass * G - np.isin(np.arange(len(r)), bottom) * 0.05 / len(bottom)
    )


def test_a_stretched_cube_meets_the_nominal_stress_at_both_ends(backend):
    """A unit cube of Neo-Hookean stretched 20 % along x between symmetry planes: the support that
    pulls it (x = 1) holds P_x · 1 m² along x, the plane x = 0 as much back (Ogden's ∂W/∂λ with the
    lateral stretch that frees the sides). Tolerance 5e-3 of P, as the validation's uniaxial rows
    (relaxation residual 1e-8, the reference's finite difference)."""
    material, W, _ = UNIAXIAL["NeoHookean"]
    _, model, right = cube_with_symmetry_bcs(material, 1.2, dtype="float64")
    sim = pl.Simulation(model, backend=backend)
    sim.relax(tol=1e-8, increments=10)
    P_ref, _ = uniaxial_reference(W, 1.2)
    by_name = model.support_reactions(sim.state)
    pulled = next(name for name, ids, _ in model.supports if np.array_equal(np.sort(ids), np.sort(right)))
    assert by_name[pulled][0] == pytest.approx(P_ref, rel=5e-3)
    assert by_name[pulled][1:].tolist() == [0.0, 0.0]
    assert by_name["support 0"][0] == pytest.approx(-P_ref, rel=5e-3)  # the plane x = 0, fixed first


def test_support_names_are_unique_and_follow_a_cut():
    """Unnamed supports are numbered, a repeated name gets "(2)"; after node splitting (a cut) the
    copies of a support's nodes are the support's too (they keep its constraints)."""
    X, T = box_tets((0.02, 0.01, 0.01), (2, 1, 1))
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    b.fix([0, 1], "z")
    b.fix([2], name="clamp")
    b.prescribe([3], 0.001, "x", name="clamp")
    assert [(n, ids.tolist(), d) for n, ids, d in b.supports] == [
        ("support 0", [0, 1], "z"),
        ("clamp", [2], "xyz"),
        ("clamp (2)", [3], "x"),
    ]
    n = len(X)
    split = b.split(T, np.array([1, 5]))  # node n copies 1, node n + 1 copies 5
    assert split.supports[0][1].tolist() == [0, 1, n]
    assert split.supports[1][1].tolist() == [2]


SCENE = """
title = "hanging block"
[mesh]
primitive = "box"
size = [0.04, 0.02, 0.02]
cells = [4, 2, 2]
[[material]]
type = "neo-hookean"
E = 2.0e4
nu = 0.4
density = 1000.0
[solver]
duration = 0.1
static = true
tol = 1e-9
dtype = "float64"
[[constraint]]
type = "fix"
name = "ceiling"
nodes = { plane = { point = [0, 0, 0.01], normal = [0, 0, 1] } }
[[constraint]]
type = "fix"
dofs = "z"
nodes = { plane = { point = [0, 0, 0.01], normal = [0, 0, 1] } }
[[load]]
type = "gravity"
"""


def test_a_run_writes_each_supports_reaction(tmp_path):
    """`pliant run` writes reactions.json (per support: DOFs, node count, the force at each frame)
    and the last one in summary.json; a support's name is its 'name', else constraint[i]. The
    static block's ceiling holds its weight (tolerance as above), and so does the second support,
    the same nodes held along z only (each support sums its own nodes' f − r)."""
    from typer.testing import CliRunner

    from pliant.cli import app

    scene = tmp_path / "block.toml"
    scene.write_text(SCENE)
    out = tmp_path / "out"
    res = CliRunner().invoke(app, ["run", str(scene), "-o", str(out), "--no-progress"])
    assert res.exit_code == 0, res.output
    kept = json.loads((out / "reactions.json").read_text())
    assert sorted(kept) == ["ceiling", "constraint[1]"]
    weight = RHO * 0.04 * 0.02 * 0.02 * G
    ceiling = kept["ceiling"]
    assert ceiling["dofs"] == "xyz" and ceiling["nodes"] == 15
    assert len(ceiling["time"]) == len(ceiling["force"]) == 2  # frame 0 and the solution
    np.testing.assert_allclose(ceiling["force"][-1], [0.0, 0.0, weight], rtol=0, atol=1e-7 * weight)
    np.testing.assert_allclose(
        kept["constraint[1]"]["force"][-1], [0.0, 0.0, weight], rtol=0, atol=1e-7 * weight
    )
    summary = json.loads((out / "summary.json").read_text())
    assert "reactions.json" in summary["files"]
    assert summary["reactions"][0] == {
        "name": "ceiling",
        "dofs": "xyz",
        "nodes": 15,
        "force": ceiling["force"][-1],
    }


def test_a_sweep_collects_each_supports_reaction(tmp_path):
    """A sweep's run (SceneCase, what each Dask task calls) has reaction.NAME.fx|fy|fz at the end:
    the static block's ceiling holds its weight (tolerance as above)."""
    from pliant.sweep.case import SceneCase

    scene = tmp_path / "block.toml"
    scene.write_text(SCENE)
    row = SceneCase(str(scene))({})
    weight = RHO * 0.04 * 0.02 * 0.02 * G
    assert row["reaction.ceiling.fz"] == pytest.approx(weight, rel=1e-7)
    assert abs(row["reaction.ceiling.fx"]) < 1e-7 * weight
    assert row["reaction.constraint[1].fz"] == pytest.approx(weight, rel=1e-7)


CUBE = """
title = "stretched cube"
[mesh]
primitive = "box"
size = [1.0, 1.0, 1.0]
cells = [3, 3, 3]
translate = [0.5, 0.5, 0.5]
[[material]]
type = "neo-hookean"
mu = 1.0e3
K = 1.0e4
density = 1000.0
[solver]
duration = 1.0
static = true
tol = 1e-10
increments = 5
dtype = "float64"
[[constraint]]
type = "fix"
dofs = "x"
nodes = { plane = { point = [0, 0, 0], normal = [1, 0, 0] } }
[[constraint]]
type = "fix"
dofs = "y"
nodes = { plane = { point = [0, 0, 0], normal = [0, 1, 0] } }
[[constraint]]
type = "fix"
dofs = "z"
nodes = { plane = { point = [0, 0, 0], normal = [0, 0, 1] } }
[[constraint]]
type = "displacement"
name = "pull"
dofs = "x"
value = 0.2
curve = "ramp"
nodes = { plane = { point = [1, 0, 0], normal = [1, 0, 0] } }
[output]
points = { corner = [1.0, 1.0, 1.0], origin = [0.01, 0.0, -0.01] }
"""


def test_a_runs_output_points_and_pull_follow_uniaxial_stress(tmp_path):
    """A unit cube (μ = 1 kPa, K = 10 kPa) pulled 20 % along x between symmetry planes, as a
    scene: points.json gives the displacement of the node nearest each [output] point at every
    frame, and reactions.json the pull. The far corner moves (λ − 1, λ_t − 1, λ_t − 1) m with the
    lateral stretch λ_t of Ogden's uniaxial stress (the homogeneous field, which linear tets hold
    exactly: 1e-6, the relaxation's residual 1e-10 and the reference's finite difference); the
    origin (the nearest node to a point 1.4 cm off it) does not move; the pull's reaction is the
    nominal stress times 1 m² (5e-3, as the uniaxial validation)."""
    from typer.testing import CliRunner

    from pliant.cli import app
    from pliant.validate.references import W_nh

    scene = tmp_path / "cube.toml"
    scene.write_text(CUBE)
    out = tmp_path / "out"
    res = CliRunner().invoke(app, ["run", str(scene), "-o", str(out), "--no-progress"])
    assert res.exit_code == 0, res.output
    P_ref, lt = uniaxial_reference(W_nh, 1.2)
    points = json.loads((out / "points.json").read_text())
    corner, origin = points["corner"], points["origin"]
    assert corner["position"] == [1.0, 1.0, 1.0] and origin["position"] == [0.0, 0.0, 0.0]
    assert corner["time"] == [0.0, 1.0] and corner["displacement"][0] == [0.0, 0.0, 0.0]
    np.testing.assert_allclose(corner["displacement"][-1], [0.2, lt - 1, lt - 1], rtol=1e-6)
    assert origin["displacement"][-1] == [0.0, 0.0, 0.0]
    pull = json.loads((out / "reactions.json").read_text())["pull"]
    assert pull["force"][-1][0] == pytest.approx(P_ref, rel=5e-3)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["points"][0] == {
        "name": "corner",
        "node": corner["node"],
        "displacement": corner["displacement"][-1],
    }


def test_an_output_point_far_from_the_mesh_is_warned_of(tmp_path):
    """Its displacement is the nearest node's: a point given in millimetres (1000 for 1 m) is named,
    with its distance, and the run goes on."""
    from pliant.errors import PliantWarning
    from pliant.scene import load_scene

    scene = tmp_path / "cube.toml"
    text = CUBE.replace("corner = [1.0, 1.0, 1.0]", "corner = [1000.0, 1000.0, 1000.0]")
    scene.write_text(text)
    line = 1 + text.splitlines().index(next(ln for ln in text.splitlines() if "corner = [1000.0" in ln))
    with pytest.warns(
        PliantWarning,
        match=rf"cube.toml:{line} \[output.points.corner\]: \[1000.0, 1000.0, 1000.0\] is 1.73e\+03 m",
    ):
        loaded = load_scene(scene)
    assert loaded.points["corner"] == int(np.argmax(loaded.builder.nodes.sum(axis=1)))
    # Its key where the line is not found (a quoted table name): the file alone, not "cube.toml:None".
    scene.write_text(text.replace("[output]", '["output"]'))
    with pytest.warns(PliantWarning, match=r"cube.toml \[output.points.corner\]"):
        load_scene(scene)


def test_a_block_resting_on_a_held_surface_weighs_on_its_support(backend):
    """A 1 cm block dropped (1 mm) onto a base whose every node is held, in soft contact, damped,
    1 s: the contact presses on held nodes, and the base's support carries the base's weight and
    the block's, ρ (V_base + V_block) g (1e-4: what of the motion the damping has left; measured
    2e-10; the base's alone is 10 % less). Before, a reaction was the internal less the external
    forces alone, and the block's weight, which reaches the support through the contact, was
    missing from it."""
    base_X, base_T = box_tets((0.03, 0.03, 0.01), (3, 3, 1), origin=(-0.015, -0.015, -0.01))
    X, T = box_tets((0.01, 0.01, 0.01), (2, 2, 2), origin=(-0.005, -0.005, 0.001))
    b = pl.ModelBuilder()
    b.add_mesh(base_X, base_T)
    b.add_mesh(X, T)
    b.set_material(pl.NeoHookean(E=2e4, nu=0.3), density=RHO)
    b.set_gravity((0.0, 0.0, -G))
    b.fix(np.arange(len(base_X)), name="base")
    b.set_soft_contact()
    b.damping = 30.0
    sim = pl.Simulation(b.finalize("float64", backend=backend))
    sim.run(until=1.0)
    weight = RHO * (0.03 * 0.03 * 0.01 + 0.01**3) * G
    np.testing.assert_allclose(
        sim.model.support_reactions(sim.state)["base"], [0, 0, weight], rtol=1e-4, atol=1e-9
    )
    # On the base, not through it: a resting node is put back each step after gravity moved it
    # (measured 12 µm below the surface, 1e-3 of the block's side; through it: centimetres).
    assert sim.state.positions[len(base_X) :, 2].min() > -1e-4


@pytest.mark.parametrize("damping", [0.0, 20.0])
def test_a_block_driven_by_its_face_takes_its_whole_mass_times_the_acceleration(damping):
    """A free 1 cm cube (no gravity) whose face x = 0 a prescribed displacement D s(t/T) drives
    along x (s: SmoothRamp, 10τ³ − 15τ⁴ + 6τ⁵; T = 0.1 s; E = 1 GPa): that support's reaction is
    the whole mass times the acceleration, plus the mass damping α M v: M D (s''/T² + α s'/T)
    (Newton's second law) within 2e-3 of its peak. What is left is the block's ringing, set off by
    the jump of the third derivative of s at t = 0, a force of about k s'''(0)/ω³: 4.5e-4 of the
    peak measured (1e-2 at E = 1 MPa). The driven face's own nodes count: their m a and α m v
    (17 % of the mass here) were left out before, 17 % of the peak off."""
    X, T = box_tets((0.01, 0.01, 0.01), (3, 3, 3), jitter=0.2, seed=5)
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(pl.NeoHookean(E=1e9, nu=0.3), density=RHO)
    b.damping = damping
    face = np.nonzero(X[:, 0] < 1e-9)[0]
    D, period = 2e-3, 0.1
    b.prescribe(face, D, "x", curve=pl.SmoothRamp(period), name="driver")
    sim = pl.Simulation(b.finalize("float64"))
    M = RHO * 1e-6
    peak = M * D * 10 / math.sqrt(3) / period**2  # |s''| peaks at 10/√3 (τ = (3 ± √3)/6)
    for t in (0.02, 0.05, 0.07, 0.09):
        sim.run(until=t)
        tau = sim.time / period
        s1 = 30 * tau**2 * (1 - tau) ** 2
        s2 = 60 * tau * (1 - tau) * (1 - 2 * tau)
        exact = M * D * (s2 / period**2 + damping * s1 / period)
        got = sim.model.support_reactions(sim.state)["driver"][0]
        assert abs(got - exact) < 2e-3 * peak, (t, got, exact)


def test_a_bar_pulled_with_stiffness_damping_carries_its_viscous_stress_to_both_supports(backend):
    """A 10 × 2 × 2 cm bar (E = 100 kPa, ν = 0.3, ρ = 1000 kg/m³) with stiffness-proportional
    damping β = 5 ms, held along x at x = 0 and pulled along x at x = L by D s(t/T) (s:
    SmoothRamp, T = 0.12 s, D = 0.1 mm: 1e-3 strain), its sides free. Under uniaxial stress C = βK
    is a Kelvin–Voigt bar whose lateral strain stays −ν ε (the lateral stress g obeys g + β ġ = 0
    from g = 0), so its stress is E (ε + β ε̇), 34 / 16 / 7 % above the elastic one at t/T = 0.3 /
    0.5 / 0.7, which the reactions left out before. The bar's inertia to first order (its
    acceleration linear in x, a the pulled end's): σ(0) = σ̄ − ρ a L / 6 at the held end, σ(L) =
    σ̄ + ρ a L / 3 at the pulled one (σ' = ρ a x / L, mean σ̄ = E (ε + β ε̇)). Tolerance 0.5 % of
    the force: the next order of the inertia (measured 0.14 % at 0.3, where the first order is 5 %)
    and the Neo-Hookean's departure from Hooke's law at 1e-3 strain (0.1 %)."""
    L, A, E, beta, D, period = 0.1, 0.02 * 0.02, 1e5, 5e-3, 1e-4, 0.12
    X, T = box_tets((L, 0.02, 0.02), (10, 2, 2), jitter=0.2, seed=7)
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(pl.NeoHookean(E=E, nu=0.3), density=RHO)
    b.stiffness_damping = beta
    near, far = np.nonzero(X[:, 0] < 1e-9)[0], np.nonzero(X[:, 0] > L - 1e-9)[0]
    corner = near[np.argmin(np.linalg.norm(X[near], axis=1))]
    b.fix(near, "x", name="held")
    b.fix([corner], "yz", name="pin")
    b.fix(near[np.argmax(X[near, 1] - X[near, 2])], "z", name="turn")  # no rotation about x
    b.prescribe(far, D, "x", curve=pl.SmoothRamp(period), name="pulled")
    sim = pl.Simulation(b.finalize("float64", backend=backend))
    mass = RHO * A * L
    for tau in (0.3, 0.5, 0.7):
        sim.run(until=tau * period)
        tau = sim.time / period
        s0 = 10 * tau**3 - 15 * tau**4 + 6 * tau**5
        s1 = 30 * tau**2 * (1 - tau) ** 2
        s2 = 60 * tau * (1 - tau) * (1 - 2 * tau)
        mean = A * E * (D / L) * (s0 + beta * s1 / period)  # A σ̄
        inertia = mass * D * s2 / period**2  # ρ a L A
        reactions = sim.model.support_reactions(sim.state)
        held, pulled = -reactions["held"][0], reactions["pulled"][0]
        assert abs(held - (mean - inertia / 6)) < 5e-3 * mean, (tau, held, mean)
        assert abs(pulled - (mean + inertia / 3)) < 5e-3 * mean, (tau, pulled, mean)
