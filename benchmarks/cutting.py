"""What a cut costs: a bar of 30,000 tets fixed at its top is cut through once; prints
the time of the cut (crossing test, node splitting, model rebuild, stable-step estimate), the
steps per second before and after it (best of three runs each), and the step's change
(docs/cutting.md). Not a test.

    python benchmarks/cutting.py                 # 10 × 10 × 50 cells (30,000 tets)
    python benchmarks/cutting.py --cells 6 6 30  # quicker
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import pliant as pl
from pliant.mesh import box_tets


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cells", type=int, nargs=3, default=[10, 10, 50])
    ap.add_argument("--steps", type=int, default=2000)
    args = ap.parse_args()
    size = (0.02, 0.02, 0.1)
    X, T = box_tets(size, args.cells)
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(pl.NeoHookean(E=1e4, nu=0.4), density=1000.0)
    b.fix(np.nonzero(X[:, 2] > size[2] - 1e-9)[0])  # at rest, no load: a step costs the same
    sim = pl.Simulation(b.finalize("float32"))

    def rate() -> float:
        """Steps per second: the best of three runs (this machine's noise is ±10 %)."""
        sim.run(steps=50)  # warm up
        best = 0.0
        for _ in range(3):
            t0 = time.perf_counter()
            sim.run(steps=args.steps)
            best = max(best, args.steps / (time.perf_counter() - t0))
        return best

    before, dt0 = rate(), sim.dt
    z = 0.5 * size[2] + 0.3 * size[2] / args.cells[2]  # through the middle of a layer of cells
    tri = np.array([[[-1, -1, z], [1, -1, z], [1, 1, z]], [[-1, -1, z], [1, 1, z], [-1, 1, z]]])
    t0 = time.perf_counter()
    res = sim.cut(tri)
    cut_s = time.perf_counter() - t0
    after = rate()
    print(f"{sim.model.n_elements:,} tets, {res.crossed} faces crossed, {len(res.parent)} nodes split")
    print(f"cut: {cut_s * 1e3:.0f} ms (model rebuild and stable-step estimate included)")
    print(f"steps/s: {before:,.0f} before, {after:,.0f} after ({after / before:.2f}x)")
    print(f"dt: {dt0:.4g} s before, {sim.dt:.4g} s after")


if __name__ == "__main__":
    main()
