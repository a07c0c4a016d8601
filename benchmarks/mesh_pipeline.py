"""Seconds each mesh-pipeline step takes on real meshes (default: the study's bunny and the liver
in ../shared/meshes). Prints figures; it is not a test.

    python benchmarks/mesh_pipeline.py [MESH.obj ...] [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path

import pliant as pl

HERE = Path(__file__).resolve().parent
DEFAULT = [HERE.parents[1] / "shared" / "meshes" / n for n in ("stanford-bunny.obj", "liver.obj")]


def bench(path: Path) -> dict:
    os.environ["PLIANT_CACHE"] = tempfile.mkdtemp(prefix="pliant-bench-")  # no cached tets
    row = {"mesh": path.name}
    t = time.perf_counter()
    V, F = pl.mesh.read_surface(path)
    row["read_s"] = time.perf_counter() - t
    t = time.perf_counter()
    rep = pl.mesh.check_surface(V, F)
    row["check_s"] = time.perf_counter() - t
    row["problems"] = rep.problems
    t = time.perf_counter()
    Vr, Fr, _ = pl.mesh.repair_surface(V, F)
    row["repair_s"] = time.perf_counter() - t
    t = time.perf_counter()
    Vs, Fs = pl.mesh.simplify(Vr, Fr, ratio=0.1)
    row["simplify_10pct_s"] = time.perf_counter() - t
    t = time.perf_counter()
    pl.mesh.subdivide_loop(Vs, Fs, 2)
    row["subdivide_2_levels_s"] = time.perf_counter() - t
    X, T, info = pl.mesh.surface_to_tets(V, F)
    row["pipeline_s"] = info["seconds"]
    row["tets"], row["nodes"] = info["tets"], info["nodes"]
    t = time.perf_counter()
    pl.mesh.tet_quality(X, T)
    row["quality_s"] = time.perf_counter() - t
    return row


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("meshes", nargs="*", type=Path, default=DEFAULT)
    ap.add_argument("--json", type=Path)
    a = ap.parse_args(argv)
    rows = []
    for m in a.meshes:
        if not m.exists():
            print(f"{m}: not found", file=sys.stderr)
            return 2
        r = bench(m)
        rows.append(r)
        p = r["pipeline_s"]
        print(
            f"{r['mesh']}: check {r['check_s']:.1f} s, repair {r['repair_s']:.1f} s, simplify "
            f"{r['simplify_10pct_s']:.2f} s, subdivide ×2 {r['subdivide_2_levels_s']:.2f} s; "
            f"surface→tets: repair {p['repair']:.1f} s + simplify {p['simplify']:.1f} s + "
            f"tetrahedralize {p['tetrahedralize']:.1f} s = {sum(p.values()):.1f} s → "
            f"{r['tets']:,} tets; quality {r['quality_s']:.2f} s",
            flush=True,
        )
    if a.json:
        a.json.write_text(json.dumps(rows, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
