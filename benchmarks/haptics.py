"""Does the haptic loop keep up? The scripted device of tests/test_haptics.py presses a 1 cm probe
4 mm into a 2,400-tet block at 1,200 reads per second for ``--seconds`` of wall time while the
simulation runs in its own thread, paced to the wall clock; prints reads per second, simulation
updates, the simulation's real-time factor and the largest jump of the rendered force
(docs/haptics.md). Not a test.

    python benchmarks/haptics.py
    python benchmarks/haptics.py --seconds 5 --rate 2000
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

import pliant as pl
from pliant.haptics import HapticLoop, VirtualDevice

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from test_haptics import _block_with_a_probe, _press  # noqa: E402  (the test's model and path)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seconds", type=float, default=2.0)
    ap.add_argument("--rate", type=float, default=1200.0)
    args = ap.parse_args()
    sim = pl.Simulation(_block_with_a_probe(), history_steps=1000)
    loop = HapticLoop(sim, tool=0)
    with loop:
        log = VirtualDevice(loop, _press, args.rate).run(args.seconds)
    jumps = np.linalg.norm(np.diff(log.forces, axis=0), axis=1)
    print(f"{sim.model.n_elements:,} tets, dt = {sim.dt:.4g} s, {loop.steps_per_update} steps per update")
    print(f"reads per second: {log.reads_per_second:,.0f} (asked {args.rate:,.0f})")
    print(f"simulation updates: {loop.updates:,}; real-time factor {loop.real_time_factor:.3f}")
    peak = np.linalg.norm(log.forces, axis=1).max()
    print(f"largest force jump per read: {jumps.max():.3g} N of peak {peak:.3g} N")


if __name__ == "__main__":
    main()
