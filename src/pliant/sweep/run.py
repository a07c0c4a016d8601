"""``pliant sweep``: a sweep file's runs on Dask with a progress bar, the results table, the
optional dataset and the optional sensitivity analysis."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..checks import flag
from .case import SceneCase
from .design import design_runs
from .execute import execute, records_table
from .spec import SweepSpec

__all__ = ["SweepResult", "run_sweep"]


@dataclass
class SweepResult:
    """What a sweep left: the results ``table`` (pandas DataFrame, one row per run), the files
    written in the output folder, and notes (outputs left out of the analysis...)."""

    table: Any
    files: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)

    @property
    def failed(self) -> Any:
        """The failed runs' rows."""
        return self.table[self.table["status"] != "ok"]


def _progress_bar(enabled: bool):
    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        Progress,
        TextColumn,
        TimeElapsedColumn,
        TimeRemainingColumn,
    )

    return Progress(
        TextColumn("runs"),
        BarColumn(),
        MofNCompleteColumn(),
        TextColumn("{task.fields[failed]} failed"),
        TimeElapsedColumn(),
        TextColumn("ETA"),
        TimeRemainingColumn(),
        disable=not enabled,
        transient=False,
    )


def run_sweep(
    spec: SweepSpec,
    out,
    *,
    scheduler: str | None = None,
    workers: int | None = None,
    retry_failed: bool = False,
    analyze: bool = False,
    progress: bool = True,
) -> SweepResult:
    """Run (or resume) the sweep ``spec`` into ``out``: OUT/results.parquet, OUT/runs/, with
    fields OUT/dataset.h5, with ``analyze`` OUT/sensitivity.csv and .png."""
    retry_failed, analyze = flag(retry_failed, "retry_failed"), flag(analyze, "analyze")
    progress = flag(progress, "progress")
    runs = design_runs(spec.parameters, spec.design)
    failed = 0
    with _progress_bar(progress) as bar:
        task = bar.add_task("sweep", total=len(runs), failed=0)

        def follow(rec: dict, done: int, total: int):
            nonlocal failed
            failed += rec.get("status", "ok") != "ok"
            bar.update(task, completed=done, failed=failed)

        records = execute(
            runs,
            SceneCase.from_spec(spec),
            out,
            fingerprint=spec.fingerprint(),
            threads=spec.threads,
            fields=spec.outputs.fields,
            scheduler=scheduler,
            workers=workers,
            retry_failed=retry_failed,
            batch=spec.batch,
            on_record=follow,
        )
    result = SweepResult(records_table(records, out), ["results.parquet", "runs/", "sweep.json"])
    if spec.outputs.fields:
        from .dataset import write_dataset

        write_dataset(out, records, [p.key for p in spec.parameters])
        result.files.append("dataset.h5")
    if analyze:
        from .analyze import sobol_indices, write_sensitivity

        indices, result.notes = sobol_indices(result.table, spec.parameters, spec.design)
        result.files += write_sensitivity(indices, Path(out))
    return result
