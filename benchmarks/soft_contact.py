"""What share of the step does soft contact take? Runs NiftySim's ball_ball.xml (two balls driven
into each other, DoDeformableCollision) from t = 0.5 s to 1 s and examples/organs_contact.toml (a
liver and a kidney pressed onto it) from 0.25 s to 0.5 s after running each to the start, and prints
the element, node and contact seconds of the step (RunInfo) and the contact share (docs/contact.md,
"Cost"). Not a test. On the GPU the kernels are not timed one by one (they run inside graphs):
it prints the wall time per step (benchmarks/gpu_kernels.py reads the kernels' times).

    python benchmarks/soft_contact.py               # 2 threads
    python benchmarks/soft_contact.py --threads 1
    python benchmarks/soft_contact.py --backend cuda
"""

from __future__ import annotations

import argparse
import time
import warnings
from pathlib import Path

import pliant as pl
from pliant.bench import kernel_timed
from pliant.io.niftysim import load_niftysim
from pliant.scene import load_scene

ROOT = Path(__file__).resolve().parents[1]


def share(name: str, sim: pl.Simulation, t0: float, t1: float) -> None:
    sim.run(until=t0)
    wall = time.perf_counter()
    info = sim.run(until=t1)
    wall = time.perf_counter() - wall
    head = f"{name}: {sim.model.n_elements:,} tets, {info.steps:,} steps in {wall:.2f} s"
    if not kernel_timed(sim.model.backend):
        print(f"{head} ({1e6 * wall / info.steps:.0f} µs per step; {sim.model.backend}: kernels not timed)")
        return
    total = info.element_seconds + info.node_seconds + info.contact_seconds
    print(
        f"{head}; elements {info.element_seconds:.3f} s, nodes {info.node_seconds:.3f} s, contact "
        f"{info.contact_seconds:.3f} s: contact share {info.contact_seconds / total:.0%}"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--backend", default="cpu", help="cpu, cuda or cuda-emulated")
    args = ap.parse_args()
    on = dict(threads=args.threads, backend=args.backend)
    warnings.simplefilter("ignore")  # the ball mesh's slow-element warning
    balls = load_niftysim(ROOT / "tests" / "data" / "niftysim_ball_ball.xml")
    share(
        "ball_ball.xml",
        pl.Simulation(balls.builder.finalize("float32", **on), dt=balls.dt),
        0.5,
        1.0,
    )
    organs = load_scene(ROOT / "examples" / "organs_contact.toml")
    model = organs.builder.finalize(organs.dtype, **on)
    share("organs_contact.toml", pl.Simulation(model), 0.25, 0.5)


if __name__ == "__main__":
    main()
