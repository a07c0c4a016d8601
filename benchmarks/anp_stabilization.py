"""The T4ANP stabilization's trade on Lamé's thick-walled sphere (a = 2 cm, b = 4 cm, E = 3 kPa,
internal pressure 30 Pa, fTetWild mesh of about 18,500 tets; tests/test_t4anp.py's case): for each
mix γ of the element's own pressure, the RMS error of the radial displacement (relative to its
largest exact value) and the spread of element J (1st–99th percentile of J − 1, relative to the
strain p/E). Two ways to choose γ: as a fixed fraction, and scaled to the shear modulus, γ = c μ/K,
which resists an element's deviation from its nodal-average volume with a stiffness of about c μ
whatever the bulk modulus. Prints a Markdown table (docs/engine.md); about 30 s.

    python benchmarks/anp_stabilization.py
    python benchmarks/anp_stabilization.py --shear 0.5 1 2 --fraction 0.05
"""

from __future__ import annotations

import argparse

import numpy as np

from pliant.validate.models import hollow_sphere, lame_solve

E, P = 3.0e3, 30.0  # Pa, Pa (lame_solve's defaults)


def _spread(dJ: np.ndarray) -> float:
    lo, hi = np.percentile(dJ, [1, 99])
    return float(hi - lo) / (P / E)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--nu", type=float, nargs="+", default=[0.49, 0.499])
    ap.add_argument("--shear", type=float, nargs="+", default=[1.0, 2.0, 4.0], help="c in γ = c μ/K")
    ap.add_argument("--fraction", type=float, nargs="+", default=[0.05], help="fixed γ")
    args = ap.parse_args()
    shell = hollow_sphere()
    print(f"{len(shell[1]):,} tets")
    print("| ν | γ | chosen as | u_r error | J spread |")
    print("|---|---|---|---|---|")
    for nu in args.nu:
        mu_over_k = 3 * (1 - 2 * nu) / (2 * (1 + nu))  # μ/K of an isotropic material
        rows = [(0.0, "plain T4ANP")]
        rows += [(g, "fraction") for g in args.fraction]
        rows += [(min(1.0, c * mu_over_k), f"{c:g} μ/K") for c in args.shear]
        for gamma, how in rows:
            err, dJ = lame_solve(shell, nu, True, gamma)
            print(f"| {nu} | {gamma:.4g} | {how} | {100 * err:.2f} % | {_spread(dJ):.3f} |", flush=True)


if __name__ == "__main__":
    main()
