"""The T4ANP stabilization's trade on Lamé's thick-walled sphere (a = 2 cm, b = 4 cm, E = 3 kPa,
internal pressure 30 Pa, fTetWild mesh of about 18,500 tets; tests/test_t4anp.py's case): for each
mix γ of the element's own pressure, the RMS error of the radial displacement (relative to its
largest exact value), the spread of element J (1st–99th percentile of J − 1, relative to the
strain p/E) and its checkerboard (the RMS of each inner element's J less the mean J of its four
face neighbours, relative to p/E: the element-to-element part of the spread, which a smooth field
hardly has). Two ways to choose γ: as a fixed fraction, and scaled to the shear modulus, γ = c μ/K,
which resists an element's deviation from its nodal-average volume with a stiffness of about c μ
whatever the bulk modulus. Prints a Markdown table (docs/engine.md); about 30 s.

``--liver`` runs examples/liver_pressure.toml (the solid liver, 24,687 tets, 26 mm under 300 Pa) to t = 0.5 s
instead, with T4, plain T4ANP, "shear" and the fixed γ: element J (1st–99th percentile), the
checkerboard (RMS of J less its face neighbours' mean) and the spread of that neighbour mean (the
smooth part); about a minute a row.

    python benchmarks/anp_stabilization.py
    python benchmarks/anp_stabilization.py --shear 0.5 1 2 --fraction 0.05
    python benchmarks/anp_stabilization.py --liver --fraction 0.1
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from pliant.cutting.split import interior_faces
from pliant.validate.models import hollow_sphere, lame_solve

E, P = 3.0e3, 30.0  # Pa, Pa (lame_solve's defaults)
LIVER = Path(__file__).resolve().parents[1] / "examples" / "liver_pressure.toml"


def _spread(dJ: np.ndarray) -> float:
    lo, hi = np.percentile(dJ, [1, 99])
    return float(hi - lo) / (P / E)


def _neighbour_mean(T: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(mean of v over each element's face neighbours, mask of the elements with four of them)."""
    a, b = interior_faces(T)[1].T
    n = len(T)
    count = np.bincount(a, minlength=n) + np.bincount(b, minlength=n)
    total = np.bincount(a, v[b], n) + np.bincount(b, v[a], n)
    return total / np.maximum(count, 1), count == 4


def _checker(T: np.ndarray, v: np.ndarray) -> float:
    mean, inner = _neighbour_mean(T, v)
    return float(np.sqrt(np.mean((v - mean)[inner] ** 2)))


def _sphere(args) -> None:
    shell = hollow_sphere()
    T = np.asarray(shell[1])
    print(f"{len(T):,} tets")
    print("| ν | γ | chosen as | u_r error | J spread | J checkerboard |")
    print("|---|---|---|---|---|---|")
    for nu in args.nu:
        mu_over_k = 3 * (1 - 2 * nu) / (2 * (1 + nu))  # μ/K of an isotropic material
        rows = [(None, "T4"), (0.0, "plain T4ANP")]
        rows += [(g, "fraction") for g in args.fraction]
        rows += [(min(1.0, c * mu_over_k), f"{c:g} μ/K") for c in args.shear]
        for gamma, how in rows:
            err, dJ = lame_solve(shell, nu, gamma is not None, gamma or 0.0)
            shown = "–" if gamma is None else f"{gamma:.4g}"
            print(
                f"| {nu} | {shown} | {how} | {100 * err:.2f} % | {_spread(dJ):.3f} | "
                f"{_checker(T, dJ) / (P / E):.3f} |",
                flush=True,
            )


def _liver(args) -> None:
    import pliant as pl
    from pliant.scene import load_scene

    print("| option | element J, 1st–99th % | checkerboard RMS | neighbour mean, 1st–99th % | max |u| [mm] |")
    print("|---|---|---|---|---|")
    for option in ["T4", 0.0, "shear", *args.fraction]:
        scene = load_scene(LIVER)
        b = scene.builder
        if option == "T4":
            b.nodal_pressure = False
        else:
            b.nodal_pressure_stabilization = option
        sim = pl.Simulation(b.finalize(scene.dtype), dt=scene.dt)
        sim.run(until=scene.duration)
        J = sim.element_results()["J"]
        mean, inner = _neighbour_mean(np.asarray(b.tets), J)
        lo, hi = np.percentile(J, [1, 99])
        mlo, mhi = np.percentile(mean[inner], [1, 99])
        name = {"T4": "T4", 0.0: "T4ANP"}.get(option, f"T4ANP, γ = {option}")
        print(
            f"| {name} | {lo:.3f}–{hi:.3f} | {_checker(np.asarray(b.tets), J):.4f} | {mlo:.3f}–{mhi:.3f} | "
            f"{1e3 * np.linalg.norm(sim.displacements, axis=1).max():.1f} |",
            flush=True,
        )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--nu", type=float, nargs="+", default=[0.49, 0.499])
    ap.add_argument("--shear", type=float, nargs="+", default=[1.0, 2.0, 4.0], help="c in γ = c μ/K")
    ap.add_argument("--fraction", type=float, nargs="+", default=[0.05], help="fixed γ")
    ap.add_argument("--liver", action="store_true", help="examples/liver_pressure.toml instead")
    args = ap.parse_args()
    (_liver if args.liver else _sphere)(args)


if __name__ == "__main__":
    main()
