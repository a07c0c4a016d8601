"""A sweep's fields as one machine-learning dataset: OUT/dataset.h5 (HDF5) with the mesh once and
each run's final fields, chunked one run per chunk:

- ``/mesh/points`` reference positions [m], shape (N, 3); ``/mesh/tets`` node ids, shape (E, 4)
- ``/displacement`` [m], shape (R, N, 3); ``/von_mises`` [Pa] and ``/J``, shape (R, E)
- ``/parameters`` shape (R, D), with the key paths in its ``names`` attribute; ``/ok`` shape (R,)
  (False: the run failed and its rows are NaN)

Runs whose mesh differs from the first run's (a varied mesh resolution) cannot share one mesh:
the export is refused, naming the run; their fields stay in OUT/runs/NNNNN/."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import InputError
from ..io.files import atomic_write

__all__ = ["write_dataset"]


def write_dataset(out, records: list[dict], keys: list[str]) -> Path:
    """Gather OUT/runs/NNNNN/fields.npz of the ``records`` into OUT/dataset.h5."""
    import h5py

    out = Path(out)
    fields = [out / "runs" / f"{r['run']:05d}" / "fields.npz" for r in records]
    have = [f for f in fields if f.is_file()]
    if not have:
        raise InputError(f"{out}: no run left fields to export (all failed?)")
    with np.load(have[0]) as first:
        X, T = first["points"], first["tets"]
    R, N, E = len(records), len(X), len(T)

    def write(tmp):
        with h5py.File(tmp, "w") as h:
            h["mesh/points"], h["mesh/tets"] = X, T
            u = h.create_dataset("displacement", (R, N, 3), "f8", chunks=(1, N, 3), fillvalue=np.nan)
            vm = h.create_dataset("von_mises", (R, E), "f8", chunks=(1, E), fillvalue=np.nan)
            J = h.create_dataset("J", (R, E), "f8", chunks=(1, E), fillvalue=np.nan)
            ok = np.zeros(R, bool)
            for k, f in enumerate(fields):
                if not f.is_file():
                    continue
                with np.load(f) as d:
                    if d["points"].shape != X.shape or not np.array_equal(d["tets"], T):
                        raise InputError(
                            f"{f}: run {records[k]['run']} has another mesh than run "
                            f"{records[0]['run']}; a dataset holds one mesh (fields "
                            "stay in the per-run folders)"
                        )
                    u[k], vm[k], J[k] = d["displacement"], d["von_mises"], d["J"]
                    ok[k] = True
            h["ok"] = ok
            P = h.create_dataset(
                "parameters",
                data=np.array([[_number(r.get(key)) for key in keys] for r in records], dtype="f8"),
            )
            P.attrs["names"] = keys

    return atomic_write(out / "dataset.h5", write, "dataset")


def _number(v) -> float:
    """A parameter as a number (NaN for one that is not: a vector value)."""
    try:
        return float(v)
    except (TypeError, ValueError):
        return float("nan")
