"""Sweeps on Dask: the same numbers as the runs done one by one (bitwise), resume, failures
recorded, a killed worker's run retried, designs with the properties their definitions state, and
Sobol indices of the Ishigami function against its closed form."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from pliant.runner import run_scene
from pliant.scene import load_scene
from pliant.sweep import (
    Design,
    Parameter,
    SweepError,
    design_runs,
    execute,
    load_sweep,
    run_sweep,
    sobol_indices,
)

ROOT = Path(__file__).parents[1]
PLIANT = Path(sys.executable).with_name("pliant")  # the installed program

# A small cantilever (10 × 2 × 2 cells), 0.02 s of loading: a run takes a few tens of ms.
BASE = """title = "bar"
[mesh]
primitive = "box"
size = [0.10, 0.02, 0.02]
cells = [10, 2, 2]
translate = [0.05, 0.0, 0.0]
[[material]]
type = "neo-hookean"
name = "rubber"
E = {E!r}
nu = 0.45
density = 1100.0
[solver]
duration = 0.02
damping = 50.0
[[constraint]]
type = "fix"
nodes = {{ plane = {{ point = [0.0, 0.0, 0.0], normal = [1.0, 0.0, 0.0] }} }}
[[load]]
type = "force"
name = "tip"
total_force = [0.0, 0.0, {F!r}]
nodes = {{ plane = {{ point = [0.1, 0.0, 0.0], normal = [1.0, 0.0, 0.0] }} }}
curve = "ramp"
"""

SWEEP = """base = "base.toml"
[design]
type = "grid"
[[parameter]]
key = "material.rubber.E"
values = {Es}
[[parameter]]
key = "load[0].total_force[2]"
values = [-0.2, -0.4]
[output]
points = {{ tip = [0.1, 0.0, 0.0] }}
"""

ES = [2.0e5, 4.0e5, 8.0e5, 1.6e6]


@pytest.fixture
def bar_sweep(tmp_path):
    (tmp_path / "base.toml").write_text(BASE.format(E=5.0e5, F=-0.5))
    (tmp_path / "sweep.toml").write_text(SWEEP.format(Es=ES))
    return tmp_path / "sweep.toml"


def test_grid_sweep_equals_runs_one_by_one_and_resumes(bar_sweep, tmp_path):
    """8 runs on a 2-worker LocalCluster, against each scene written out by hand and run as
    `pliant run` runs it: same inputs, same bits. A second call finds them all finished."""
    spec = load_sweep(bar_sweep)
    result = run_sweep(spec, tmp_path / "out", workers=2, progress=False)
    table = result.table.sort_values("run")
    assert len(table) == 8 and (table["status"] == "ok").all()
    for _, row in table.iterrows():
        E, F = ES[row["run"] // 2], [-0.2, -0.4][row["run"] % 2]  # grid: first parameter slowest
        assert (row["material.rubber.E"], row["load[0].total_force[2]"]) == (E, F)
        one = tmp_path / f"one_{row['run']}.toml"
        one.write_text(BASE.format(E=E, F=F))
        s = run_scene(load_scene(one), None, progress=False)
        for k in ("max_displacement", "max_von_mises", "strain_energy", "kinetic_energy", "steps"):
            assert row[k] == s[k], k  # bitwise: the same run
    # Stiffer bar, smaller tip deflection; twice the load, about twice the deflection.
    uz = table["point.tip.uz"].to_numpy().reshape(4, 2)
    assert np.all(np.diff(np.abs(uz[:, 1])) < 0) and np.all(uz < 0)
    assert np.allclose(uz[:, 1] / uz[:, 0], 2.0, rtol=0.1)  # nonlinear and dynamic: within 10 %
    stamps = sorted((p.name, p.stat().st_mtime_ns) for p in (tmp_path / "out" / "runs").iterdir())
    again = run_sweep(spec, tmp_path / "out", workers=2, progress=False)
    assert (
        sorted((p.name, p.stat().st_mtime_ns) for p in (tmp_path / "out" / "runs").iterdir()) == stamps
    )  # nothing re-run
    pd.testing.assert_frame_equal(again.table, result.table)
    from_file = pd.read_parquet(tmp_path / "out" / "results.parquet")
    pd.testing.assert_frame_equal(from_file, result.table)


def test_failed_run_is_recorded_and_the_others_complete(bar_sweep, tmp_path):
    """A negative modulus cannot run: its row says why; the rest are done; the CLI exits 1."""
    bar_sweep.write_text(SWEEP.format(Es=[4.0e5, -1.0, 8.0e5]))
    r = subprocess.run(
        [
            str(PLIANT),
            "sweep",
            str(bar_sweep),
            "-o",
            str(tmp_path / "out"),
            "--workers",
            "2",
            "--no-progress",
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert r.returncode == 1, r.stderr
    table = pd.read_parquet(tmp_path / "out" / "results.parquet").sort_values("run")
    assert list(table["status"]) == ["ok", "ok", "failed", "failed", "ok", "ok"]
    assert table["error"].iloc[2].count("material") and "E" in table["error"].iloc[2]
    assert np.isnan(table["max_displacement"].iloc[2]) and table["max_displacement"].iloc[4] > 0
    assert "run 2 failed" in r.stderr and "Traceback" not in r.stderr


def _die_once(params: dict, run_dir) -> dict:
    """A case whose worker process dies the first time it runs run 3 (a node lost mid-sweep)."""
    marker = Path(params["marker"])
    if params["x"] == 3.0 and not marker.exists():
        marker.write_text("died")
        os._exit(1)
    return {"y": params["x"] ** 2}


def test_killed_worker_does_not_lose_runs(tmp_path):
    runs = [{"x": float(i), "marker": str(tmp_path / "marker")} for i in range(8)]
    records = execute(runs, _die_once, tmp_path / "out", workers=2, fingerprint="die")
    assert (tmp_path / "marker").exists()  # the worker did die
    assert [r["status"] for r in records] == ["ok"] * 8
    assert [r["y"] for r in records] == [float(i) ** 2 for i in range(8)]


def _ishigami(params: dict, run_dir) -> dict:
    """Ishigami & Homma (1990), a = 7, b = 0.1, on [-π, π]³."""
    x1, x2, x3 = params["x1"], params["x2"], params["x3"]
    return {"y": math.sin(x1) + 7.0 * math.sin(x2) ** 2 + 0.1 * x3**4 * math.sin(x1)}


def test_sobol_indices_of_ishigami_match_closed_form(tmp_path):
    """First-order and total indices against the closed form (Sobol' & Levitan 1999): with a = 7,
    b = 0.1, V = a²/8 + bπ⁴/5 + b²π⁸/18 + 1/2; V1 = (1 + bπ⁴/5)²/2, V2 = a²/8, V13 = b²π⁸(1/18 −
    1/50). 512 base samples (2,560 runs through the sweep's Dask machinery); tolerance: three
    times the bootstrap 95 % half-width plus 0.02 (the estimators' own bias at this N)."""
    a, b = 7.0, 0.1
    V = a * a / 8 + b * math.pi**4 / 5 + b * b * math.pi**8 / 18 + 0.5
    V1, V2, V13 = (1 + b * math.pi**4 / 5) ** 2 / 2, a * a / 8, b * b * math.pi**8 * (1 / 18 - 1 / 50)
    S1 = [V1 / V, V2 / V, 0.0]
    ST = [(V1 + V13) / V, V2 / V, V13 / V]
    params = [Parameter(k, range=(-math.pi, math.pi)) for k in ("x1", "x2", "x3")]
    design = Design("saltelli", 512, seed=3)
    runs = design_runs(params, design)
    assert len(runs) == 512 * 5
    records = execute(runs, _ishigami, tmp_path / "out", workers=2, fingerprint="ishigami")
    table = pd.DataFrame.from_records(records)
    idx, notes = sobol_indices(table, params, design, outputs=["y"])
    assert not notes
    for j in range(3):
        row = idx.iloc[j]
        assert abs(row["S1"] - S1[j]) < 3 * row["S1_conf"] + 0.02, (j, row["S1"], S1[j])
        assert abs(row["ST"] - ST[j]) < 3 * row["ST_conf"] + 0.02, (j, row["ST"], ST[j])


def test_latin_hypercube_and_sobol_designs():
    """LHS: each of the n equal strata of every axis holds exactly one run (McKay et al. 1979).
    Sobol' (scrambled, 2^k points): every dyadic interval of length 2^-k holds one run per axis
    (a (0, m, 1)-net in each coordinate). Log scale: the strata are equal in log. Same seed, same
    runs; another seed, other runs."""
    p = [Parameter("a", range=(1.0, 3.0)), Parameter("b", range=(1e3, 1e5), scale="log")]
    for kind in ("lhs", "sobol"):
        runs = design_runs(p, Design(kind, 16, seed=5))
        a = np.array([r["a"] for r in runs])
        b = np.array([r["b"] for r in runs])
        assert sorted(np.floor((a - 1.0) / 2.0 * 16).astype(int)) == list(range(16))
        assert sorted(np.floor(np.log10(b / 1e3) / 2.0 * 16).astype(int)) == list(range(16))
        assert design_runs(p, Design(kind, 16, seed=5)) == runs
        assert design_runs(p, Design(kind, 16, seed=6)) != runs


def test_grid_and_list_designs():
    p = [Parameter("a", values=(1, 2, 3)), Parameter("b", values=("x", "y", "z"))]
    assert len(design_runs(p, Design("grid"))) == 9
    assert design_runs(p, Design("grid"))[:2] == [{"a": 1, "b": "x"}, {"a": 1, "b": "y"}]
    assert design_runs(p, Design("list")) == [{"a": 1, "b": "x"}, {"a": 2, "b": "y"}, {"a": 3, "b": "z"}]


def test_resume_refuses_another_sweep(bar_sweep, tmp_path):
    spec = load_sweep(bar_sweep)
    runs = design_runs(spec.parameters, spec.design)[:1]
    execute(runs, _ishigami_free, tmp_path / "out", fingerprint="a", workers=1)
    with pytest.raises(SweepError, match="another sweep"):
        execute(runs, _ishigami_free, tmp_path / "out", fingerprint="b", workers=1)
    (tmp_path / "full").mkdir()
    (tmp_path / "full" / "x.txt").write_text("mine")
    with pytest.raises(SweepError, match="not empty"):
        execute(runs, _ishigami_free, tmp_path / "full", fingerprint="a", workers=1)


def _ishigami_free(params, run_dir):
    return {"y": 1.0}


@pytest.mark.parametrize(
    "text, culprit",
    [
        (
            'base = "base.toml"\n[[parameter]]\nkey = "material.liver.E"\nvalues = [1.0]\n',
            "no entry of material is named 'liver'",
        ),
        ('base = "base.toml"\n[[parameter]]\nkey = "load[3].force"\nvalues = [1.0]\n', "out of range"),
        (
            'base = "base.toml"\n[design]\ntype = "lhs"\nsamples = 4\n[[parameter]]\nkey = "solver.damping"'
            "\nvalues = [1.0]\n",
            "range = [low, high]",
        ),
        (
            'base = "base.toml"\n[design]\ntype = "saltelli"\nsamples = 6\n[[parameter]]\n'
            'key = "solver.damping"\nrange = [1.0, 2.0]\n',
            "power of 2",
        ),
        ('base = "nothere.toml"\n[[parameter]]\nkey = "solver.damping"\nvalues = [1.0]\n', "no such"),
        (  # numpy's generator refused it inside (an internal error, exit 3; found by mutation)
            'base = "base.toml"\n[design]\ntype = "lhs"\nsamples = 4\nseed = -1\n[[parameter]]\n'
            'key = "solver.damping"\nrange = [1.0, 2.0]\n',
            "[design.seed]: seed = -1: expected an integer >= 0",
        ),
        ('base = "base.toml"\n[[parameter]]\nkey = "solver..damping"\nvalues = [1.0]\n', "segment"),
        (
            'base = "base.toml"\n'
            + "".join(f'[[parameter]]\nkey = "solver.x{i}"\nvalues = {list(range(60))}\n' for i in range(8)),
            "expected at most 1,000,000",
        ),  # 60^8 runs
        (
            'base = "base.toml"\n[design]\ntype = "lhs"\nsamples = 1000000000\n[[parameter]]\n'
            'key = "solver.damping"\nrange = [1.0, 2.0]\n',
            "expected at most 1,000,000",
        ),
        (
            'base = "base.toml"\nthreads = 1000000\n[[parameter]]\nkey = "solver.damping"\nvalues = [1.0]\n',
            "threads per run",
        ),
        ('base = "base.toml"\n[[parameter]]\nkey = "solver.damping"\n', "takes explicit values"),
        ('base = "base.toml"\nparameter = 3\n', "parameter"),
        (  # a [set] value the base refuses: every run would fail alike
            'base = "base.toml"\n[set]\n"solver.duration" = -0.2\n[[parameter]]\nkey = "solver.damping"'
            "\nvalues = [1.0]\n",
            "[set]: the base file with the [set] values does not load",
        ),
        (  # a range whose low end the base refuses (E = 0)
            'base = "base.toml"\n[design]\ntype = "lhs"\nsamples = 4\n[[parameter]]\n'
            'key = "material.rubber.E"\nrange = [0.0, 1.0e6]\n',
            "at their first choice or low end does not load",
        ),
    ],
)
def test_bad_sweep_files_exit_2_naming_the_key(tmp_path, text, culprit):
    (tmp_path / "base.toml").write_text(BASE.format(E=5.0e5, F=-0.5))
    (tmp_path / "s.toml").write_text(text)
    r = subprocess.run(
        [str(PLIANT), "sweep", str(tmp_path / "s.toml"), "-o", str(tmp_path / "out"), "--no-progress"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert r.returncode == 2 and culprit in r.stderr and "s.toml" in r.stderr, r.stderr
    assert "Traceback" not in r.stderr and not (tmp_path / "out").exists()


def test_fields_dataset_holds_each_runs_final_frame(bar_sweep, tmp_path):
    """OUT/dataset.h5 against the per-run result files (written by the frame writer, read back
    by meshio): the mesh once, each run's final displacement."""
    import h5py
    import meshio

    bar_sweep.write_text(SWEEP.format(Es=ES[:2]) + "fields = true\n")
    spec = load_sweep(bar_sweep)
    run_sweep(spec, tmp_path / "out", workers=2, progress=False)
    with h5py.File(tmp_path / "out" / "dataset.h5") as h:
        assert h["displacement"].shape[0] == 4 and h["displacement"].chunks[0] == 1
        assert list(h["parameters"].attrs["names"]) == [p.key for p in spec.parameters]
        for k in range(4):
            frames = sorted((tmp_path / "out" / "runs" / f"{k:05d}").glob("frame_*.vtu"))
            last = meshio.read(frames[-1])
            assert np.array_equal(h["mesh/tets"][...], last.cells_dict["tetra"])
            assert np.array_equal(h["displacement"][k], last.point_data["displacement"])
        assert h["ok"][...].all()


def test_example_sweeps_run_and_analyze(tmp_path):
    """Every examples/*sweep*.toml through the CLI, with --analyze for Saltelli designs."""
    examples = sorted((ROOT / "examples").glob("*sweep*.toml"))
    assert examples
    for path in examples:
        saltelli = load_sweep(path).design.type == "saltelli"
        out = tmp_path / path.stem
        r = subprocess.run(
            [str(PLIANT), "sweep", str(path), "-o", str(out), "--no-progress"]
            + (["--analyze"] if saltelli else []),
            capture_output=True,
            text=True,
            timeout=600,
        )
        assert r.returncode == 0, r.stderr
        table = pd.read_parquet(out / "results.parquet")
        assert (table["status"] == "ok").all()
        assert json.loads((out / "sweep.json").read_text())["runs"]
        if saltelli:
            s = pd.read_csv(out / "sensitivity.csv")
            assert set(s["parameter"]) == {p.key for p in load_sweep(path).parameters}
            assert (out / "sensitivity.png").stat().st_size > 1000


def test_niftysim_base_with_element_paths(tmp_path):
    """A sweep over a NiftySim model: the shear modulus (ElasticParams' first number) and the
    damping set by element path give the same bits as the XML edited by hand and run alone."""
    from test_niftysim import _cube_xml

    from pliant.io.niftysim import load_niftysim

    xml = _cube_xml()[-1]
    (tmp_path / "cube.xml").write_text(xml)
    (tmp_path / "s.toml").write_text(
        'base = "cube.xml"\n[[parameter]]\nkey = "ElementSet.Material.ElasticParams[0][0]"\n'
        'values = [500.0, 2000.0]\n[set]\n"SystemParams.DampingCoeff" = 40.0\n'
    )
    table = run_sweep(
        load_sweep(tmp_path / "s.toml"), tmp_path / "out", workers=2, progress=False
    ).table.sort_values("run")
    for mu, (_, row) in zip((500.0, 2000.0), table.iterrows()):
        edited = xml.replace("1000 20000</ElasticParams>", f"{mu!r} 20000</ElasticParams>").replace(
            "<DampingCoeff>20<", "<DampingCoeff>40.0<"
        )
        assert edited != xml
        (tmp_path / "edited.xml").write_text(edited)
        s = run_scene(load_niftysim(tmp_path / "edited.xml"), None, progress=False)
        assert row["status"] == "ok" and row["max_displacement"] == s["max_displacement"]
        assert row["strain_energy"] == s["strain_energy"]
    assert table["strain_energy"].iloc[0] != table["strain_energy"].iloc[1]


def test_batched_sweep_equals_runs_alone(bar_sweep, tmp_path):
    """batch = 3 with a fixed time step: every run's figures equal the unbatched sweep's, bit for
    bit. A refused value (E < 0) fails alone while the rest of its batch runs together; a modulus
    too stiff for the fixed step makes its batch fall back to runs one by one, so that only that
    run fails."""
    grid = SWEEP.format(Es=[4.0e5, -1.0, 1.0e9, 8.0e5]) + '[set]\n"solver.dt" = 1e-5\n'
    bar_sweep.write_text(grid)
    alone = run_sweep(load_sweep(bar_sweep), tmp_path / "alone", workers=2, progress=False).table
    bar_sweep.write_text("batch = 3\n" + grid)
    batched = run_sweep(load_sweep(bar_sweep), tmp_path / "batched", workers=2, progress=False).table
    assert list(batched["status"]) == ["ok", "ok", "failed", "failed", "failed", "failed", "ok", "ok"]
    assert "material" in batched["error"][2] and "time step" in batched["error"][4].lower()
    assert list(batched["batch"].fillna(1)) == [2, 2, 1, 1, 1, 1, 2, 2]
    for col in (
        "max_displacement",
        "max_von_mises",
        "strain_energy",
        "kinetic_energy",
        "steps",
        "point.tip.ux",
        "point.tip.uz",
        "status",
    ):
        pd.testing.assert_series_equal(batched[col], alone[col], check_names=False)
    with pytest.raises(Exception, match="needs each run alone"):
        bar_sweep.write_text("batch = 2\n" + SWEEP.format(Es=ES) + "fields = true\n")
        load_sweep(bar_sweep)


def test_an_output_point_far_from_the_body_is_warned_of(bar_sweep):
    """Its displacement is the nearest node's: a point 5 m from a 10 cm bar (a typo, or millimetres)
    gave the tip's silently. The distance is to the tip node at (0.1, 0, 0): 4.9 m."""
    from pliant.errors import PliantWarning

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        load_sweep(bar_sweep)  # the tip itself: no warning
    bar_sweep.write_text(SWEEP.format(Es=ES).replace("tip = [0.1, 0.0, 0.0]", "tip = [5.0, 0.0, 0.0]"))
    with pytest.warns(
        PliantWarning, match=r"output.points.tip\]: \[5.0, 0.0, 0.0\] is 4.9 m from the nearest"
    ):
        load_sweep(bar_sweep)


def test_existing_scheduler_by_address(bar_sweep, tmp_path):
    """--scheduler: the runs go to a cluster started elsewhere (here a LocalCluster of this test),
    with the same numbers; a malformed address is refused naming it (exit 2)."""
    from distributed import LocalCluster

    spec = load_sweep(bar_sweep)
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None) as c:
        there = run_sweep(spec, tmp_path / "there", scheduler=c.scheduler_address, progress=False).table
    here = run_sweep(spec, tmp_path / "here", workers=2, progress=False).table
    for col in ("max_displacement", "strain_energy", "point.tip.uz"):
        pd.testing.assert_series_equal(there[col], here[col])
    r = subprocess.run(
        [
            str(PLIANT),
            "sweep",
            str(bar_sweep),
            "-o",
            str(tmp_path / "bad"),
            "--scheduler",
            "nonsense://nowhere",
            "--no-progress",
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert r.returncode == 2 and "nonsense://nowhere" in r.stderr and "Traceback" not in r.stderr, r.stderr
