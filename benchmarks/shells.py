"""Bending sheets against shell and large-deflection references (docs/engine.md, "Bending"): prints
the tip of a cantilever strip (pliant.validate's) against the elastica, a tube pinched by two line
loads against the ring, the Scordelis–Lo roof against 0.3024 m and the pinched cylinder with end
diaphragms against 1.8248e-5 m (Flügge's series, as in MacNeal & Harder 1985), each on a sequence
of meshes, with their errors. The other models are tests/test_shells.py's. Not a test; the finest
meshes take minutes.

    python benchmarks/shells.py            # all four
    python benchmarks/shells.py --quick    # the meshes the tests use
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from test_bending import linear_solve  # noqa: E402  (the tests' models)
from test_shells import pinched_ring, scordelis_lo, tube  # noqa: E402

import pliant as pl  # noqa: E402
from pliant.validate.models import bending_strip_tip  # noqa: E402
from pliant.validate.references import elastica_tip  # noqa: E402


def pinched_cylinder(nx: int, nphi: int) -> float:
    """The pinched cylinder (radius 300, length 600, thickness 3, E = 3e6, ν = 0.3, consistent
    units) on rigid end diaphragms (y and z held at both ends, x at mid-span), two opposite unit
    loads at mid-span: the whole cylinder on nx × nphi cells; the deflection under a load over
    1.8248e-5."""
    R, length = 300.0, 600.0
    X, F = tube(nx, nphi, length, R)
    held = np.zeros(X.shape, bool)
    held[np.isclose(X[:, 0], 0) | np.isclose(X[:, 0], length), 1:] = True
    held[np.isclose(X[:, 0], length / 2), 0] = True
    top = int(np.argmin(np.linalg.norm(X - [length / 2, 0, R], axis=1)))
    bottom = int(np.argmin(np.linalg.norm(X - [length / 2, 0, -R], axis=1)))
    forces = np.zeros(X.shape)
    forces[top, 2], forces[bottom, 2] = -1.0, 1.0
    mat = pl.StVKMembrane(E=3e6, nu=0.3, thickness=3.0, density=1.0, bending=True)
    return -linear_solve(X, F, mat, held, forces)[top, 2] / 1.8248e-5


def row(name: str, value: float, started: float) -> None:
    print(f"  {name:>12}: {value:.4f} ({100 * (value - 1):+.2f} %), {time.perf_counter() - started:.1f} s")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="only the meshes the tests use")
    quick = ap.parse_args().quick
    print("cantilever strip, alpha = P L^2 / EI = 10: tip deflection over the elastica's")
    ref = elastica_tip(10.0)[0]
    for n in (10, 20, 40) if quick else (10, 20, 40, 80):
        t = time.perf_counter()
        row(f"{n} x {n // 5}", bending_strip_tip(10.0, n, n // 5)[0] / ref, t)
    print("tube pinched by line loads: diameter change over the ring's")
    for n in (16, 32, 64, 128, 256):
        t = time.perf_counter()
        row(f"2 x {n}", pinched_ring(n), t)
    print("Scordelis-Lo roof: free edge's deflection over 0.3024")
    for n in (16, 32, 64) if quick else (16, 32, 64, 96, 128):
        t = time.perf_counter()
        row(f"{n} x {n}", scordelis_lo(n), t)
    print("pinched cylinder: deflection under the load over 1.8248e-5")
    for n in (16, 32) if quick else (16, 32, 64, 96, 128):
        t = time.perf_counter()
        row(f"{n} x {2 * n}", pinched_cylinder(n, 2 * n), t)


if __name__ == "__main__":
    main()
