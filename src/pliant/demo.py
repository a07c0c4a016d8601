"""The embedded default job (`pliant demo`): a soft-tissue slab (10 × 6 × 3 cm, Neo-Hookean,
E = 6 kPa, ν = 0.45) lying on a table under gravity, indented 8 mm by a flat circular tool
(prescribed displacement of a patch of its top face, smooth ramp). Writes a ParaView series and
summary.json. Replaced by Spot pressed by a spherical tool once contact and the mesh pipeline land.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np

from .io import ResultWriter, atomic_write_text
from .materials import NeoHookean
from .mesh import box_tets
from .tled import ModelBuilder, SmoothRamp, Solver


def build_demo_model(threads=None, cells=(30, 18, 9)):
    size = (0.10, 0.06, 0.03)
    X, T = box_tets(size, cells, jitter=0.15, seed=0)
    b = ModelBuilder()
    b.add_mesh(X, T, source="demo slab")
    b.set_material(NeoHookean(E=6.0e3, nu=0.45), density=1050.0, name="tissue")
    b.fix(np.nonzero(X[:, 2] < 1e-9)[0])  # glued to the table
    b.set_gravity((0.0, 0.0, -9.81))
    top = X[:, 2] > size[2] - 1e-9
    r = np.hypot(X[:, 0] - 0.05, X[:, 1] - 0.03)
    tool = np.nonzero(top & (r < 0.012))[0]
    b.prescribe(tool, (0.0, 0.0, -0.008), "xyz", curve=SmoothRamp(0.3))
    b.damping = 20.0
    return b.finalize("float32", threads=threads)


def run_demo(out_dir, duration: float = 0.6, frames: int = 12, threads=None, echo=print) -> dict:
    out = Path(out_dir)
    model = build_demo_model(threads)
    solver = Solver(model)
    state = model.state()
    writer = ResultWriter(out, model)
    writer.write(state)
    n = max(1, int(np.ceil(duration / solver.dt / frames)))
    echo(f"demo: {model.n_elements:,} tets, {model.n_nodes:,} nodes, dt = {solver.dt:.3g} s, "
         f"{frames * n:,} steps on {model.threads} thread(s)")
    t0 = time.perf_counter()
    for _ in range(frames):
        solver.run(state, steps=n)
        writer.write(state)
    wall = time.perf_counter() - t0
    res = model.element_results(state)
    summary = {
        "steps": state.steps, "dt": solver.dt, "simulated_time": state.time, "wall_time": wall,
        "backend": "cpu", "threads": model.threads, "elements": model.n_elements,
        "nodes": model.n_nodes, "max_displacement": float(np.linalg.norm(state.displacements,
                                                                          axis=1).max()),
        "max_von_mises": float(res["von_mises"].max()),
        "kinetic_energy": model.kinetic_energy(state), "strain_energy": model.strain_energy(state),
        "frames": len(writer.frames), "warnings": [],
    }
    atomic_write_text(out / "summary.json", json.dumps(summary, indent=2))
    return summary
