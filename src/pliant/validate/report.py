"""``pliant validate``: run the verification cases, write OUT/report.md, OUT/results.json and PNG
plots; every row passes or fails against its stated tolerance."""

from __future__ import annotations

import json
import platform
import time
from pathlib import Path
from typing import Callable

from .. import __version__, _core
from ..checks import flag
from ..io.files import atomic_write, atomic_write_text, make_output_dir
from .cases import CASES, Check
from .niftysim_cross import find_niftysim, run_cross_checks
from .peers import run_peers

__all__ = ["run_validation"]


def run_validation(
    out, quick: bool = False, echo: Callable[[str], None] = print, niftysim: str | Path | None = None
) -> list[Check]:
    """Run every case (``quick``: the CI subset, under two minutes on two cores) and write the
    report; ``niftysim``: a NiftySim executable that runs the cross-check models afresh (else its
    stored results are used). Returns the rows; the caller decides the exit code (1 when one
    failed)."""
    quick = flag(quick, "quick")
    if niftysim is not None:
        niftysim = find_niftysim(niftysim)  # before the other cases run
    out = make_output_dir(out)
    rows: list[Check] = []
    figures: dict = {}
    timings = {}
    left_out: list[str] = []  # cases with no rows in a quick run
    t0 = time.perf_counter()  # first: a NiftySim executable that fails stops the run early
    got, cross = run_cross_checks(niftysim)
    timings["niftysim"] = time.perf_counter() - t0
    rows += got
    echo(f"niftysim: {sum(r.passed for r in got)}/{len(got)} passed in {timings['niftysim']:.1f} s")
    for name, case in CASES.items():
        t0 = time.perf_counter()
        got, figs = case(quick)
        timings[name] = time.perf_counter() - t0
        rows += got
        figures.update(figs)
        bad = sum(not r.passed for r in got)
        if quick and not got:
            left_out.append(name)
            echo(f"{name}: full run only (not in --quick)")
        else:
            echo(f"{name}: {len(got) - bad}/{len(got)} passed in {timings[name]:.1f} s")
    t0 = time.perf_counter()
    got, peers = run_peers(quick)
    timings["peers"] = time.perf_counter() - t0
    rows += got
    ran = ", ".join(p["peer"] for p in peers if p["ran"])
    echo(f"peers ({ran}): {sum(r.passed for r in got)}/{len(got)} passed in {timings['peers']:.1f} s")
    files = _plots(out, figures)
    atomic_write_text(
        out / "results.json",
        json.dumps(
            {
                "pliant": __version__,
                "quick": quick,
                "left_out": left_out,
                "isa": _core.isa,
                "seconds": timings,
                "rows": [r.as_dict() for r in rows],
                "peers": peers,
                "niftysim": cross,
            },
            indent=2,
        ),
        "validation results",
    )
    atomic_write_text(
        out / "report.md", _markdown(rows, files, timings, quick, peers, cross, left_out), "validation report"
    )
    return rows


PLOTS = ("uniaxial.png", "cantilever.png", "torsion.png")  # every plot a report may have


def _plots(out: Path, figures: dict) -> list[str]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    files = []
    if "uniaxial" in figures:
        fig, ax = plt.subplots(figsize=(6.5, 4.2))
        for name, pts in figures["uniaxial"].items():
            pts = sorted(pts)
            (line,) = ax.plot([p[0] for p in pts], [p[2] for p in pts], "-", lw=1)
            ax.plot([p[0] for p in pts], [p[1] for p in pts], "o", color=line.get_color(), label=name)
        ax.set_xlabel("stretch λ")
        ax.set_ylabel("nominal stress P_x [Pa]")
        ax.set_title("uniaxial stress: pliant (dots) and ∂W/∂λ (lines)", fontsize=9)
        ax.legend(fontsize=7)
        files.append(_save(fig, out / "uniaxial.png"))
    if "cantilever" in figures:
        c = figures["cantilever"]
        fig, ax = plt.subplots(figsize=(5, 4))
        ax.loglog(c["levels"], c["errors"], "o-", label="pliant, linear tets")
        if "edge" in c:
            ax.loglog(c["levels"], c["edge"], "s-", label="pliant, edge-smoothed (|error|)")
        e0 = c["errors"][-1]
        ax.loglog(c["levels"], [e0 * (c["levels"][-1] / n) ** 2 for n in c["levels"]], "--", label="O(h²)")
        ax.set_xticks(c["levels"], [str(n) for n in c["levels"]])
        ax.minorticks_off()
        ax.set_xlabel("elements through the depth")
        ax.set_ylabel("tip deflection error vs Timoshenko")
        ax.legend(fontsize=8)
        files.append(_save(fig, out / "cantilever.png"))
    if "torsion" in figures:
        files.append(_torsion_plot(plt, figures["torsion"], out / "torsion.png"))
    plt.close("all")
    if (out / "results.json").exists():  # an earlier report here: its plots this one lacks go
        for name in set(PLOTS) - set(files):
            (out / name).unlink(missing_ok=True)
    return files


def _torsion_plot(plt, c: dict, path: Path) -> str:
    """The twisted cylinder's torque and axial force errors against Rivlin's, log-log over the
    cells across, with an O(h²) line."""
    fig, ax = plt.subplots(figsize=(5, 4))
    n = c["levels"]
    torque = [abs(m / c["torque_exact"] - 1) for m in c["torque"]]
    axial = [abs(f / c["axial_exact"] - 1) for f in c["axial"]]
    ax.loglog(n, torque, "o-", label="torque")
    ax.loglog(n, axial, "s-", label="Poynting axial force")
    ax.loglog(n, [torque[-1] * (n[-1] / k) ** 2 for k in n], "--", label="O(h²)")
    ax.set_xticks(n, [str(k) for k in n])
    ax.minorticks_off()
    ax.set_xlabel("cells across the cylinder")
    ax.set_ylabel("error vs Rivlin (T4ANP, ν = 0.499)")
    ax.legend(fontsize=8)
    return _save(fig, path)


def _save(fig, path: Path) -> str:
    fig.tight_layout()
    atomic_write(path, lambda tmp: fig.savefig(tmp, dpi=110, format="png"), "plot")
    return path.name


def _markdown(
    rows: list[Check],
    files: list[str],
    timings: dict,
    quick: bool,
    peers: list[dict],
    cross: list[dict],
    left_out: list[str],
) -> str:
    failed = [r for r in rows if not r.passed]
    lines = [
        f"# pliant {__version__} validation{' (quick)' if quick else ''}",
        "",
        f"{len(rows) - len(failed)} of {len(rows)} checks passed; {platform.machine()}, "
        f"engine path {_core.isa}, {sum(timings.values()):.0f} s.",
        "",
        *(
            [f"Left out of the quick run (the full run has them): {', '.join(left_out)}.", ""]
            if left_out
            else []
        ),
        "| case | quantity | pliant | reference | error | tolerance | result |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        tol = {
            "match": f"{r.tolerance:.2g}",
            "at most": f"≤ {r.reference:.3g}",
            "at least": f"≥ {r.reference:.3g}",
        }[r.kind]
        unit = "" if r.unit == "1" else f" {r.unit}"  # "1": a ratio, shown bare
        ref = f"{r.reference:.6g}{unit}" if r.kind == "match" else "(bound)"
        err = f"{r.error:.2e}" if r.kind == "match" else ""
        lines.append(
            f"| {r.case} | {r.quantity} | {r.value:.6g}{unit if r.kind == 'match' else ''} | "
            f"{ref} | {err} | {tol} | {'pass' if r.passed else '**FAIL**'} |"
        )
    lines += ["", "Tolerances and bounds, and why:", ""]
    lines += [f"- {r.case}, {r.quantity}: {r.why}." for r in rows]
    lines += ["", *[f"![{f}]({f})" for f in files], "", "## NiftySim cross-checks", ""]
    lines += [
        "NiftySim's models of pliant.validate.niftysim_cross (a 3 × 3 × 6 box, base fixed, one per",
        "material and per load), imported and run by pliant, against NiftySim's displacements at its",
        "four output frames:",
        "",
        "| case | material | elements | load | largest ‖u‖ (m) | largest deviation / largest ‖u‖ |",
        "|---|---|---|---|---|---|",
    ]
    lines += [
        f"| {c['case']} | {c['material']} | {c['elements']} | {c['load']} | {c['u_max']:.4g} | "
        f"{c['deviation']:.2e} |"
        for c in cross
    ]
    lines += ["", "## Peers", ""]
    lines += [
        "The cantilever of pliant.validate.peers (0.1 × 0.02 × 0.02 m, E = 100 MPa, ν = 0.3, sagging",
        "under gravity) on the same tets in each simulator, the same Δt and damping, until it settles:",
        "tip deflection over Timoshenko's, and simulated seconds per wall second.",
        "",
        "| simulator | tip / closed form | simulated s per wall s | note |",
        "|---|---|---|---|",
    ]
    for p in peers:
        ratio, speed = (f"{p['ratio']:.4f}", f"{p['speed']:.3g}") if p["ran"] else ("not run", "")
        lines.append(f"| {p['peer']} | {ratio} | {speed} | {p['note']} |")
    return "\n".join(lines) + "\n"
