"""Every example scene loads and runs (few steps: a smoke test; the examples double as
benchmarks at full length with `pliant run`)."""

import json
import math
from pathlib import Path

import numpy as np
import pytest

from pliant.runner import run_scene
from pliant.scene import load_scene

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
    dt = scene.dt or scene.safety * model.dt_critical
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
