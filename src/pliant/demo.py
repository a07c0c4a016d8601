"""The embedded default job (`pliant demo`): Spot the cow (CC0, shipped in the package),
tetrahedralized, standing on the ground under gravity and indented on its back by a tool
(``data/demo.toml``: the ground and the tool are rigid contact tools). Writes a ParaView series,
summary.json and result.png."""

from __future__ import annotations

import math
from pathlib import Path

from .errors import InputError
from .runner import run_scene
from .scene import load_scene

DEMO_SCENE = Path(__file__).parent / "data" / "demo.toml"


def run_demo(out_dir, duration: float | None = None, threads=None, progress: bool = True, echo=print) -> dict:
    scene = load_scene(DEMO_SCENE)
    if duration is not None:
        if not (math.isfinite(duration) and duration > 0):
            raise InputError(f"--duration {duration}: expected a finite time > 0 [s]")
        scene.duration = float(duration)
    echo(
        f"demo: {DEMO_SCENE.name} ({scene.title}); mesh {scene.builder.n_elements:,} tets, "
        f"{scene.builder.n_nodes:,} nodes"
    )
    return run_scene(scene, out_dir, progress=progress, threads=threads, echo=echo)
