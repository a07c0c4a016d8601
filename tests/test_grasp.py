"""Grasping: a tool that closes holds the surface nodes within its reach and moves them with it.

References: a block held still hangs in equilibrium, so the grasp force equals its weight ρ V g
(statics); once released it falls freely (its centre of mass at g: the internal forces of a
free body sum to zero, and central differences integrate a constant acceleration exactly)."""

from __future__ import annotations

import numpy as np
import pytest

import pliant as pl
from pliant.contact import Box, Plane
from pliant.mesh import box_tets

L, RHO, G = 0.02, 1000.0, 9.81  # block edge [m], density [kg/m³], gravity [m/s²]
TOP = (L / 2, L / 2, L + 0.003)  # the grasper's centre when its lower face touches the top
LIFT, T_LIFT, T_RELEASE = 0.02, 0.25, 0.3


def grasped_block(backend="cpu", threads=None, damping=0.0):
    """A 2 cm block on the ground; a 12 × 12 × 6 mm grasper closes on its top at t = 0, lifts it
    2 cm by t = 0.25 s, releases it at 0.3 s and moves up out of its way."""
    X, T = box_tets((L, L, L), (4, 4, 4))
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(pl.NeoHookean(E=5e4, nu=0.4), density=RHO)
    b.set_gravity((0, 0, -G))
    b.damping = damping
    b.add_tool(Plane(point=(0, 0, 0)))
    jaws = Box((0.006, 0.006, 0.003), position=TOP, name="grasper")
    up = (TOP[0], TOP[1], TOP[2] + LIFT)
    jaws.at(0.0, TOP).at(0.05, TOP).at(T_LIFT, up).at(T_RELEASE, up).at(
        T_RELEASE + 0.002, (up[0], up[1], up[2] + 0.01)
    )
    jaws.grasp(0.0, reach=1e-3).release(T_RELEASE)
    b.add_tool(jaws)
    return b.finalize("float64", threads=threads, backend=backend)


def test_the_grasped_block_hangs_from_the_grasper_with_its_weight(backend):
    sim = pl.Simulation(grasped_block(backend, damping=30.0))
    sim.run(until=0.28)
    held = sim.state.held
    top = np.nonzero(np.abs(sim.model.reference_positions[:, 2] - L) < 1e-9)[0]
    # The 3 × 3 top nodes under the jaws (12 mm square over a 5 mm grid), and only they.
    under = top[np.all(np.abs(sim.model.reference_positions[top, :2] - L / 2) <= 0.006, axis=1)]
    assert sorted(held) == sorted(under.tolist()) and set(held.values()) == {1}
    sim.relax(at_time=0.28, tol=1e-7)
    force, _ = sim.tool_force(1)
    weight = RHO * L**3 * G
    # Statics: the grasp carries the weight; 1e-5 from the relaxation's residual (tol 1e-7 of the
    # load scale) and the float64 sums.
    assert force == pytest.approx([0.0, 0.0, -weight], abs=1e-5 * weight)
    assert sim.positions[:, 2].min() > 0.01  # lifted off the ground
    assert sim.tool_force(0)[0] == pytest.approx([0, 0, 0], abs=1e-12)


def test_a_released_block_falls_freely(backend):
    sim = pl.Simulation(grasped_block(backend))
    sim.run(until=T_RELEASE + 0.004)
    assert sim.state.held == {}
    m = sim.model.mass

    def com():
        return m @ sim.positions[:, 2] / m.sum()

    z, t = [], []
    for _ in range(3):
        sim.run(steps=20)
        z.append(com())
        t.append(sim.time)
    assert sim.positions[:, 2].min() > 0.001  # not yet on the ground
    acc = np.polyfit(t, z, 2)[0] * 2
    # 1e-6: float64 round-off of the weighted sums, differenced twice over 20-step intervals.
    assert acc == pytest.approx(-G, rel=1e-6)


def test_grasping_is_deterministic_and_survives_save_and_restore(tmp_path):
    a = pl.Simulation(grasped_block(threads=1))
    b = pl.Simulation(grasped_block(threads=2))
    a.run(until=0.15)
    b.run(until=0.15)
    assert np.array_equal(a.displacements, b.displacements) and a.state.held == b.state.held
    a.save(tmp_path / "held.npz")
    c = pl.Simulation(a.model)
    c.load(tmp_path / "held.npz")
    assert c.state.held == a.state.held
    a.run(steps=100)
    c.run(steps=100)
    assert np.array_equal(a.displacements, c.displacements)


def test_grasp_and_release_from_python_now():
    """Simulation.grasp / release act from the next step (an interactive tool, a haptic device)."""
    X, T = box_tets((L, L, L), (2, 2, 2))
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(pl.NeoHookean(E=5e4, nu=0.4), density=RHO)
    b.add_tool(Box((0.004, 0.004, 0.003), position=TOP))
    sim = pl.Simulation(b.finalize("float64"))
    sim.run(steps=2)
    assert sim.state.held == {}
    sim.grasp(0, reach=1e-3)
    sim.run(steps=1)
    assert list(sim.state.held) == [int(np.argmin(np.linalg.norm(X - [L / 2, L / 2, L], axis=1)))]
    sim.release(0)
    sim.run(steps=1)
    assert sim.state.held == {}


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda t: t.grasp(0.1, reach=-1.0), "reach"),
        (lambda t: t.grasp(0.1).grasp(0.2), "already closed"),
        (lambda t: t.release(0.1), "not closed"),
        (lambda t: t.grasp(0.2).release(0.1), "after"),
        (lambda t: t.grasp(float("nan")), "grasp time"),
    ],
)
def test_bad_grasps_are_refused(call, match):
    with pytest.raises(pl.InputError, match=match):
        call(Box((0.01, 0.01, 0.01)))


SCENE = """
[mesh]
primitive = "box"
size = [0.02, 0.02, 0.02]
cells = [2, 2, 2]
[[material]]
type = "neo-hookean"
E = 2e4
nu = 0.4
density = 1000.0
[[tool]]
type = "{kind}"
{shape}
{extra}
"""


@pytest.mark.parametrize(
    "kind, extra, match",
    [
        ("box", "grip = [0.5, 0.2]", "expected a time after 0.5"),
        ("box", 'grip = ["a"]', r"tool\[0\]\.grip\[0\]"),
        ("box", "grip = [0.1]\nreach = -1", "reach"),
        ("box", "reach = -1", "reach"),
        ("box", "grip = [nan]", "finite"),
        ("blade", "grip = [0.1]", "does not grasp"),
    ],
)
def test_bad_grasps_in_a_scene_are_refused_naming_file_and_tool(tmp_path, kind, extra, match):
    from pliant.scene import load_scene

    shape = "half_extents = [0.01, 0.01, 0.01]" if kind == "box" else "length = 0.01"
    f = tmp_path / "s.toml"
    f.write_text(SCENE.format(kind=kind, shape=shape, extra=extra))
    with pytest.raises(pl.InputError, match=match) as e:
        load_scene(f)
    assert str(f) in str(e.value) and "tool[0]" in str(e.value)
