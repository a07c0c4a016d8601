"""Every example scene loads and runs (few steps: a smoke test; the examples double as
benchmarks at full length with `pliant run`)."""

import json
from pathlib import Path

import numpy as np
import pytest

from pliant.runner import run_scene
from pliant.scene import load_scene

EXAMPLES = sorted((Path(__file__).parents[1] / "examples").glob("*.toml"))


def test_there_are_examples():
    assert {p.stem for p in EXAMPLES} >= {"cantilever", "liver_indentation", "kidney_hanging", "torus"}


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.stem)
def test_example_runs(path, tmp_path):
    scene = load_scene(path)
    model = scene.builder.finalize(scene.dtype)
    dt = scene.dt or scene.safety * model.dt_critical
    scene.duration = 40 * dt  # a smoke test: 40 steps
    scene.frames = 2
    s = run_scene(scene, tmp_path, progress=False)
    assert s["steps"] == 40 and s["error"] is None and not s["interrupted"]
    assert np.isfinite(s["max_displacement"]) and s["max_displacement"] > 0
    assert json.loads((tmp_path / "summary.json").read_text())["frames"] == 3
    assert (tmp_path / "result.png").exists()
