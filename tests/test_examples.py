"""Every example scene loads and runs (few steps: a smoke test; the examples double as
benchmarks at full length with `pliant run`)."""

import json
import math
from pathlib import Path

import numpy as np
import pytest

from pliant.runner import run_scene
from pliant.scene import load_scene
from pliant.tled.solver import default_step

EXAMPLES = sorted(
    p for p in (Path(__file__).parents[1] / "examples").glob("*.toml") if "sweep" not in p.stem
)  # sweeps: tests/test_sweep.py


def test_there_are_examples():
    assert {p.stem for p in EXAMPLES} >= {"cantilever", "liver_indentation", "kidney_hanging", "torus"}


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.stem)
def test_example_runs(path, tmp_path):
    """The whole scene, to its end (a 40-step smoke test once let the liver example ship with an
    inversion at t = 0.27 s): about 35 s for all of them."""
    scene = load_scene(path)
    model = scene.builder.finalize(scene.dtype)
    dt = scene.dt or default_step(model, scene.safety)  # membranes: their exact limit
    scene.frames = 2
    s = run_scene(scene, tmp_path, progress=False)
    assert s["error"] is None and not s["interrupted"]
    if scene.blades:  # a cut may shorten the step: the run still reaches the duration
        assert s["simulated_time"] >= scene.duration - 1e-9 and s["cuts"] > 0
    else:
        assert s["steps"] == math.ceil(scene.duration / dt - 1e-9)
    assert np.isfinite(s["max_displacement"]) and s["max_displacement"] > 0
    frames = json.loads((tmp_path / "summary.json").read_text())["frames"]
    assert frames == 3 or (scene.blades and frames >= 3)  # a shorter step after a cut: more steps
    assert (tmp_path / "result.png").exists()
    if path.stem == "drape":  # at rest on the ball and the table: they carry its weight ρ h A g
        weight = 1200.0 * 5e-4 * 0.3 * 0.3 * 9.81  # (1e-3: measured 1e-4 at 1.5 s, still settling)
        np.testing.assert_allclose(-sum(t["force"][2] for t in s["tools"]), weight, rtol=1e-3)


def test_the_kidney_passes_its_push_to_the_liver():
    """examples/organs_contact.toml at its end: the kidney, pushed down at its top, is in balance
    (Newton's third law through it): the force its top's support exerts on it (the internal forces
    there, Model.internal_forces) equals the contact force it exerts on the liver (the contact
    report's pair force, summed in the engine's fixed point) plus what its damping still takes, α Σ m v
    over its free nodes. Tolerance 3 % of the force: the kidney's remaining acceleration Σ m a
    (0.5 s is 0.2 s after the push stops, about six damping times 1/α)."""
    import pliant as pl

    scene = load_scene(Path(__file__).parents[1] / "examples" / "organs_contact.toml")
    b = scene.builder
    X, T, body = np.asarray(b.nodes), np.asarray(b.tets), b.bodies()
    model = b.finalize(scene.dtype)
    sim = pl.Simulation(model)
    sim.run(until=scene.duration)
    pair = sim.contact_report().pairs[0]
    assert pair.bodies == (0, 1)  # the liver (the [mesh]) and the kidney (the [[body]])
    on_liver = np.asarray(pair.force)[-1]
    kidney = np.unique(T[body == 1])
    top = kidney[X[kidney, 2] >= 0.16]  # the scene's displacement constraint
    free = np.setdiff1d(kidney, top)
    support = model.internal_forces(sim.state)[top].sum(axis=0)
    damping = b.damping * (model.mass[free, None] * sim.state.velocities[free]).sum(axis=0)
    assert on_liver[2] < -0.05  # the kidney presses down on the liver [N]
    np.testing.assert_allclose(support, on_liver + damping, atol=0.03 * np.linalg.norm(on_liver))
