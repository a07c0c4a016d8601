"""Bending accuracy of each element option: a cantilever (L/H = 10, Neo-Hookean, E = 1 MPa) under
a small tip load, against Timoshenko (κ = 5/6), at 2, 4 and 8 elements through the depth, for
ν = 0.3 and 0.49, with plain linear tets (T4), the average nodal pressure tet (T4ANP), edge-smoothed
strain (ES) and both (ES + T4ANP), and the observed convergence rates (theory: 2). Prints a
Markdown table (docs/engine.md); not a test (the 8-element runs take minutes).

    python benchmarks/cantilever_options.py                 # 2, 4, 8 elements
    python benchmarks/cantilever_options.py --levels 2 4    # quicker
"""

from __future__ import annotations

import argparse
import math
import time

import pliant as pl
from pliant.validate.models import cantilever_tip_deflection
from pliant.validate.references import timoshenko_tip_deflection

L, H, E, P = 1.0, 0.1, 1.0e6, 1.0e-2  # m, m, Pa, N (geometrically linear: δ/L ≈ 4e-5)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--levels", type=int, nargs="+", default=[2, 4, 8])
    ap.add_argument("--nu", type=float, nargs="+", default=[0.3, 0.49])
    args = ap.parse_args()
    print(
        "| ν | element | " + " | ".join(f"error at {n}" for n in args.levels) + " | observed rates | time |"
    )
    print("|---|---|" + "---|" * len(args.levels) + "---|---|")
    for nu in args.nu:
        ref = timoshenko_tip_deflection(P, L, H, E, nu)
        options = (("T4", False, "element"), ("T4ANP", True, "element"), ("ES", False, "edge"))
        for name, anp, smoothing in options + (("ES + T4ANP", True, "edge"),):
            t0 = time.perf_counter()
            material = pl.NeoHookean(E=E, nu=nu)
            errors = [
                abs(cantilever_tip_deflection(n, material, nodal_pressure=anp, smoothing=smoothing) - ref)
                / ref
                for n in args.levels
            ]
            rates = [
                math.log(a / b) / math.log(m / n)
                for a, b, n, m in zip(errors, errors[1:], args.levels, args.levels[1:])
            ]
            cells = " | ".join(f"{e:.1%}" for e in errors)
            shown = ", ".join(f"{r:.2f}" for r in rates)
            print(f"| {nu} | {name} | {cells} | {shown} | {time.perf_counter() - t0:.0f} s |", flush=True)


if __name__ == "__main__":
    main()
