"""Running a sweep's runs on Dask (a LocalCluster sized to the machine, or an existing scheduler),
resumably: each finished run is a record OUT/runs/NNNNN.json written atomically as it arrives;
OUT/results.parquet (one row per run) is made from the records; OUT/sweep.json fingerprints the
sweep so that a re-run skips the finished runs only when they still hold.

A run that fails (instability, a bad value) is recorded with its error and the others go on; a
task whose worker died is retried by Dask on another worker (``distributed.scheduler.allowed-
failures`` times) before it is recorded as failed.
"""

from __future__ import annotations

import contextlib
import json
import logging
import os
import time
import warnings
from pathlib import Path
from typing import Any, Callable

from ..errors import InputError, PliantError
from ..guard import one_line
from ..io.files import atomic_write, atomic_write_text, make_output_dir

__all__ = ["SweepError", "execute", "run_one", "machine_cores", "records_table"]


class SweepError(InputError):
    """A sweep that cannot start or resume (its output folder holds another sweep, a bad
    scheduler address...)."""


def machine_cores() -> int:
    """CPU cores this process may use."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover (not Linux)
        return os.cpu_count() or 1


def run_one(case: Callable, index: int, params: dict[str, Any], run_dir: str | None) -> dict:
    """A worker's task: run ``case(params, run_dir)`` and return its record (status 'ok' with the
    outputs, or 'failed' with the error in one line). A bug's exception is recorded with its type
    so that one bad run cannot stop the sweep; interruption propagates."""
    t0 = time.perf_counter()
    rec: dict[str, Any] = {"run": index, "status": "ok", "error": ""}
    try:
        if run_dir is not None:
            Path(run_dir).mkdir(parents=True, exist_ok=True)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # a warning per run would drown the progress bar
            rec.update(case(params, None if run_dir is None else Path(run_dir)))
    except PliantError as e:
        rec.update(status="failed", error=one_line(str(e)))
    except Exception as e:  # noqa: BLE001 (recorded, named: a bug in the case, not the sweep)
        rec.update(status="failed", error=one_line(f"{type(e).__name__}: {e}"))
    rec["wall_time"] = time.perf_counter() - t0
    return rec


def _check_manifest(out: Path, fingerprint: str, runs: list[dict]) -> None:
    """Write OUT/sweep.json, or check that the one there describes this very sweep."""
    manifest = out / "sweep.json"
    runs = json.loads(json.dumps(runs))  # as the file holds them (tuples become lists)
    mine = {"fingerprint": fingerprint, "runs": runs}
    if manifest.is_file():
        try:
            theirs = json.loads(manifest.read_text())
        except (OSError, ValueError):
            theirs = {}
        if theirs.get("fingerprint") != fingerprint or theirs.get("runs") != runs:
            raise SweepError(
                f"{out}: the folder holds another sweep (its sweep.json differs: the "
                "spec or the base file changed); expected the same sweep to resume, "
                "or a new output folder"
            )
        return
    if any(out.iterdir()):
        raise SweepError(
            f"{out}: the folder is not empty and holds no sweep.json; expected an "
            "empty or new output folder, or one of an earlier run of this sweep"
        )
    atomic_write_text(manifest, json.dumps(mine, indent=1))


def _load_records(out: Path, n: int, retry_failed: bool) -> dict[int, dict]:
    """Finished runs' records by run index (failed ones dropped with ``retry_failed``)."""
    done = {}
    for i in range(n):
        f = out / "runs" / f"{i:05d}.json"
        if f.is_file():
            try:
                rec = json.loads(f.read_text())
            except ValueError:  # cannot happen with atomic writes; a hand-edited file: run again
                continue
            if not (retry_failed and rec.get("status") != "ok"):
                done[i] = rec
    return done


@contextlib.contextmanager
def _client(scheduler: str | None, workers: int | None, threads: int):
    """A Dask client: on ``scheduler`` when given, else on a LocalCluster of ``workers``
    single-task worker processes (default: cores // threads, so workers × threads <= cores)."""
    from distributed import Client, LocalCluster

    if scheduler:
        try:
            client = Client(scheduler, timeout="20s")
        except (OSError, TimeoutError, ValueError) as e:
            raise SweepError(
                f"cannot reach the Dask scheduler {scheduler!r}: {one_line(str(e))}; "
                "expected an address such as tcp://host:8786"
            ) from None
        with client:
            yield client
        return
    n = workers or max(1, machine_cores() // threads)
    with (
        LocalCluster(
            n_workers=n,
            threads_per_worker=1,
            processes=True,
            dashboard_address=None,
            silence_logs=logging.ERROR,
        ) as cluster,
        Client(cluster) as client,
    ):
        yield client


def _submit(
    client,
    case: Callable,
    runs: list[dict],
    todo: list[int],
    out: Path,
    fingerprint: str,
    fields: bool,
    batch: int,
) -> dict:
    """One task per run, or per ``batch`` runs (run together by pliant.sweep.batched)."""
    if batch > 1:
        from .batched import run_batch

        chunks = [todo[i : i + batch] for i in range(0, len(todo), batch)]
        return {
            client.submit(
                run_batch,
                case,
                ids,
                [runs[i] for i in ids],
                key=f"pliant-{fingerprint}-batch-{ids[0]}",
                pure=False,
            ): ids
            for ids in chunks
        }
    return {
        client.submit(
            run_one,
            case,
            i,
            runs[i],
            str(out / "runs" / f"{i:05d}") if fields else None,
            key=f"pliant-{fingerprint}-run-{i}",
            pure=False,
        ): [i]
        for i in todo
    }


def execute(
    runs: list[dict[str, Any]],
    case: Callable,
    out,
    *,
    fingerprint: str = "",
    threads: int = 1,
    fields: bool = False,
    scheduler: str | None = None,
    workers: int | None = None,
    retry_failed: bool = False,
    batch: int = 1,
    on_record: Callable[[dict, int, int], None] | None = None,
) -> list[dict]:
    """Run ``case`` for each of ``runs`` (parameter dicts) on Dask, skipping those recorded in
    ``out`` by an earlier call with the same ``fingerprint``; ``batch`` > 1 runs that many together
    (a SceneCase: one model, pliant.sweep.batched). ``on_record(record, done, total)`` follows
    progress. Returns every run's record, in run order (the parameters included)."""
    out = make_output_dir(out)
    _check_manifest(out, fingerprint, runs)
    (out / "runs").mkdir(exist_ok=True)
    records = _load_records(out, len(runs), retry_failed)
    todo = [i for i in range(len(runs)) if i not in records]
    if on_record:
        on_record({}, len(records), len(runs))
    if todo:
        from distributed import as_completed

        with _client(scheduler, workers, threads) as client:
            futures = _submit(client, case, runs, todo, out, fingerprint, fields, batch)
            for fut in as_completed(futures):
                try:
                    got = fut.result()
                    got = got if isinstance(got, list) else [got]
                except Exception as e:  # noqa: BLE001 (a task Dask gave up on: KilledWorker...)
                    got = [
                        {
                            "run": i,
                            "status": "failed",
                            "wall_time": None,
                            "error": one_line(f"{type(e).__name__}: {e}"),
                        }
                        for i in futures[fut]
                    ]
                for rec in got:
                    i = rec["run"]
                    rec = {"run": i, **runs[i], **rec}
                    atomic_write_text(out / "runs" / f"{i:05d}.json", json.dumps(rec))
                    records[i] = rec
                    if on_record:
                        on_record(rec, len(records), len(runs))
    return [records[i] for i in range(len(runs))]


def records_table(records: list[dict], out) -> Any:
    """OUT/results.parquet from the records (one row per run; columns: run, the parameters,
    status, error, wall_time, the outputs). Returns the pandas DataFrame."""
    import pandas as pd

    table = pd.DataFrame.from_records(records)
    first = ["run"] + [c for c in ("status", "error", "wall_time") if c in table.columns]
    table = table[first + [c for c in table.columns if c not in first]]
    atomic_write(
        Path(out) / "results.parquet", lambda tmp: table.to_parquet(tmp, index=False), "results table"
    )
    return table
