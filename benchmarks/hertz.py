"""Hertz indentation convergence study: F / F_Hertz of a rigid sphere pressed into a quarter block
(the set-up of tests/test_hertz.py) for other mesh sizes, gradings and block sizes. Prints
figures; it is not a test. Lengths in sphere radii R.

    python benchmarks/hertz.py                        # the test's mesh, three depths
    python benchmarks/hertz.py --h 0.005 --fine 0.09  # cells of R/200 over the contact
    python benchmarks/hertz.py --ratio 1.2 --depths 0.005 --dtype float32
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

import pliant as pl
from pliant.contact import Sphere

R, E, NU = 0.01, 1e4, 0.3  # sphere radius [m], Young's modulus [Pa], Poisson ratio


def hertz(delta: float) -> float:
    """F = 4/3 E* √R δ^1.5 [N] (Johnson, Contact Mechanics, eq. 4.23)."""
    return 4.0 / 3.0 * E / (1 - NU**2) * math.sqrt(R) * delta**1.5


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--h", type=float, default=0.01, help="cell size over the contact [R]")
    ap.add_argument("--fine", type=float, default=0.12, help="extent of the uniform cells [R]")
    ap.add_argument("--ratio", type=float, default=1.3, help="growth of the cells beyond it")
    ap.add_argument("--size", type=float, default=8.0, help="block size [R]")
    ap.add_argument("--depths", default="0.0025,0.005,0.01", help="indentation depths [R]")
    ap.add_argument("--dtype", default="float64")
    ap.add_argument("--tol", type=float, default=1e-5, help="dynamic-relaxation tolerance")
    a = ap.parse_args()
    depths = np.array([float(d) for d in a.depths.split(",")]) * R
    t0 = time.perf_counter()
    xs = pl.mesh.graded_coordinates(a.h * R, a.fine * R, a.ratio, a.size * R)
    X, T = pl.mesh.grid_tets(xs, xs, -xs[::-1])
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(pl.LinearElastic(E=E, nu=NU), density=1000.0)
    b.fix(np.nonzero(X[:, 0] == 0.0)[0], "x")
    b.fix(np.nonzero(X[:, 1] == 0.0)[0], "y")
    b.fix(np.nonzero(X[:, 2] == X[:, 2].min())[0], "z")
    tool = Sphere(R)
    tool.at(0.0, (0.0, 0.0, R))
    for k, d in enumerate(depths):
        tool.at(k + 1.0, (0.0, 0.0, R - d))
    b.add_tool(tool)
    sim = pl.Simulation(b.finalize(a.dtype))
    print(
        f"{len(T):,} tets, {len(xs) - 1} cells per side, block {xs[-1] / R:.2f} R, "
        f"{a.dtype}; built in {time.perf_counter() - t0:.1f} s"
    )
    forces = []
    for k, d in enumerate(depths):
        t = time.perf_counter()
        info = sim.solver.relax(sim.state, at_time=k + 1.0, tol=a.tol, strict=False)
        F = 4 * sim.contact_report().relaxed[0][0][2]
        forces.append(F)
        a_c = math.sqrt(R * d)
        print(
            f"  δ/R = {d / R:.4f}  a/h = {a_c / (a.h * R):4.1f}  F/F_Hertz = {F / hertz(d):.4f}  "
            f"({info.steps} steps, residual {info.residual:.1e}, {time.perf_counter() - t:.1f} s)"
        )
    if len(depths) > 1:
        print(f"  fitted exponent {np.polyfit(np.log(depths), np.log(forces), 1)[0]:.4f} (Hertz 1.5)")


if __name__ == "__main__":
    main()
