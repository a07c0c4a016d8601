"""Sensitivity of a sweep's outputs to its parameters: first-order (S1) and total (ST) Sobol
indices (Sobol' 2001; estimators of Saltelli et al. 2010 and Jansen 1999, as SALib implements
them, with bootstrap 95 % confidence intervals) from a Saltelli design's runs.

Writes OUT/sensitivity.csv (output, parameter, S1, S1_conf, ST, ST_conf) and OUT/sensitivity.png
(one bar chart per output)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputError
from ..io.files import atomic_write
from .design import salib_problem
from .spec import Design, Parameter

__all__ = ["sobol_indices", "analyzable_outputs", "write_sensitivity"]

# Columns that describe a run rather than its physics: never analysed.
_BOOKKEEPING = {"run", "status", "error", "wall_time", "steps", "dt", "simulated_time"}


def analyzable_outputs(table, parameters: list[Parameter]) -> list[str]:
    """Numeric scalar output columns of the results table (not parameters, not bookkeeping)."""
    keys = {p.key for p in parameters}
    return [
        c
        for c in table.columns
        if c not in keys
        and c not in _BOOKKEEPING
        and not c.endswith(".node")
        and np.issubdtype(table[c].dtype, np.number)
    ]


def sobol_indices(
    table, parameters: list[Parameter], design: Design, outputs: list[str] | None = None
) -> tuple[Any, list[str]]:
    """Sobol indices of each output: a DataFrame (output, parameter, S1, S1_conf, ST, ST_conf)
    and notes on the outputs left out (failed runs, no variance). InputError for a design that
    is not Saltelli's."""
    import pandas as pd
    from SALib.analyze import sobol as salib_sobol

    if design.type != "saltelli":
        raise InputError(
            f"Sobol indices need a 'saltelli' design (this sweep's is "
            f"'{design.type}'); expected [design] type = \"saltelli\""
        )
    problem = salib_problem(parameters)
    rows, notes = [], []
    for name in outputs or analyzable_outputs(table, parameters):
        Y = table.sort_values("run")[name].to_numpy(dtype=np.float64)
        bad = np.flatnonzero(~np.isfinite(Y))
        if len(bad):
            notes.append(
                f"{name}: left out, runs {bad[:5].tolist()}{'...' if len(bad) > 5 else ''} "
                "have no value (failed)"
            )
            continue
        if np.ptp(Y) == 0:
            notes.append(f"{name}: left out, the same in every run")
            continue
        S = salib_sobol.analyze(problem, Y, calc_second_order=False, seed=design.seed)
        for j, p in enumerate(parameters):
            rows.append(
                {
                    "output": name,
                    "parameter": p.key,
                    "S1": S["S1"][j],
                    "S1_conf": S["S1_conf"][j],
                    "ST": S["ST"][j],
                    "ST_conf": S["ST_conf"][j],
                }
            )
    return pd.DataFrame(rows, columns=["output", "parameter", "S1", "S1_conf", "ST", "ST_conf"]), notes


def write_sensitivity(indices, out) -> list[str]:
    """OUT/sensitivity.csv and OUT/sensitivity.png; the names of the files written."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = Path(out)
    atomic_write(out / "sensitivity.csv", lambda tmp: indices.to_csv(tmp, index=False), "sensitivity table")
    names = list(dict.fromkeys(indices["output"]))
    if not names:
        return ["sensitivity.csv"]
    fig, axes = plt.subplots(len(names), 1, figsize=(7, 2.2 * len(names) + 0.6), squeeze=False)
    for ax, name in zip(axes[:, 0], names):
        sub = indices[indices["output"] == name]
        x = np.arange(len(sub))
        ax.bar(x - 0.2, sub["S1"], 0.4, yerr=sub["S1_conf"], label="first order S1", capsize=3)
        ax.bar(x + 0.2, sub["ST"], 0.4, yerr=sub["ST_conf"], label="total ST", capsize=3)
        ax.set_xticks(x, sub["parameter"], fontsize=8)
        ax.set_title(name, fontsize=9)
        ax.set_ylim(min(0.0, float(sub["S1"].min()) - 0.05), 1.05)
    axes[0, 0].legend(fontsize=8)
    fig.tight_layout()
    atomic_write(
        out / "sensitivity.png", lambda tmp: fig.savefig(tmp, dpi=110, format="png"), "sensitivity chart"
    )
    plt.close(fig)
    return ["sensitivity.csv", "sensitivity.png"]
