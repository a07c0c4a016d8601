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

import numpy as np

import pliant as pl
from pliant.contact import Sphere
from pliant.haptics import HapticLoop, VirtualDevice

CENTRE = np.array([0.05, 0.05, 0.0505])  # the probe's start: 0.5 mm above the block [m]
DEPTH = 0.004  # [m]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seconds", type=float, default=2.0)
    ap.add_argument("--rate", type=float, default=1200.0)
    args = ap.parse_args()
    X, T = pl.mesh.box_tets((0.1, 0.1, 0.04), (10, 10, 4))
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(pl.NeoHookean(E=5e3, nu=0.4), density=1000.0)
    b.fix(np.nonzero(X[:, 2] < 1e-9)[0])
    b.damping = 30.0
    b.add_tool(Sphere(0.01).at(0.0, tuple(CENTRE)))
    sim = pl.Simulation(b.finalize("float64"), history_steps=1000)
    loop = HapticLoop(sim, tool=0)
    with loop:
        log = VirtualDevice(loop, lambda t: CENTRE - (0, 0, DEPTH * min(t, 1.0)), args.rate).run(args.seconds)
    jumps = np.linalg.norm(np.diff(log.forces, axis=0), axis=1)
    print(f"{sim.model.n_elements:,} tets, dt = {sim.dt:.4g} s, {loop.steps_per_update} steps per update")
    print(f"reads per second: {log.reads_per_second:,.0f} (asked {args.rate:,.0f})")
    print(f"simulation updates: {loop.updates:,}; real-time factor {loop.real_time_factor:.3f}")
    peak = np.linalg.norm(log.forces, axis=1).max()
    print(f"largest force jump per read: {jumps.max():.3g} N of peak {peak:.3g} N")


if __name__ == "__main__":
    main()
