"""Command line: info, demo (smoke test of the embedded default), bench, and exit code 2."""

import json

import meshio
import numpy as np
from typer.testing import CliRunner

from pliant.cli import app

runner = CliRunner()


def test_info_json():
    r = runner.invoke(app, ["info", "--json"])
    assert r.exit_code == 0, r.output
    data = json.loads(r.output)
    assert data["backends"]["cpu"]["compiled"] and data["backends"]["cpu"]["threads"] >= 1


def test_demo_writes_a_readable_series(tmp_path):
    out = tmp_path / "demo"
    r = runner.invoke(app, ["demo", "-o", str(out), "--duration", "0.06"])
    assert r.exit_code == 0, r.output
    summary = json.loads((out / "summary.json").read_text())
    pvd = (out / "result.pvd").read_text()
    assert pvd.count("<DataSet") == summary["frames"] == 13
    last = meshio.read(out / "frame_00012.vtu")
    u = last.point_data["displacement"]
    assert np.all(np.isfinite(u)) and last.cells_dict["tetra"].shape[0] == summary["elements"]
    # The tool patch follows its prescribed SmoothRamp: 8 mm × (10τ³ − 15τ⁴ + 6τ⁵), τ = t / 0.3.
    tau = summary["simulated_time"] / 0.3
    expected = 0.008 * tau**3 * (10 - 15 * tau + 6 * tau**2)
    X = last.points
    patch = (X[:, 2] > 0.03 - 1e-9) & (np.hypot(X[:, 0] - 0.05, X[:, 1] - 0.03) < 0.012)
    assert patch.sum() > 5
    # float32 state: relative 1e-5 of the 8 mm scale.
    assert np.allclose(-u[patch, 2], expected, rtol=0, atol=1e-5 * 0.008)
    assert not list(out.glob(".*tmp*"))  # no temporary files left behind


def test_bench_json(tmp_path):
    f = tmp_path / "b.json"
    r = runner.invoke(app, ["bench", "--sizes", "600,7456", "--steps", "20", "--large-steps", "5",
                            "--json", str(f)])
    assert r.exit_code == 0, r.output
    rows = json.loads(f.read_text())["rows"]
    assert [row["tets"] for row in rows] == [600, 7456]
    assert rows[1]["speedup_vs_study_gpu"] > 0 and rows[0]["speedup_vs_study_gpu"] is None
    assert all(row["element_steps_per_second"] > 0 for row in rows)


def test_bad_option_exits_2():
    r = runner.invoke(app, ["bench", "--sizes", "abc"])
    assert r.exit_code == 2
    assert "expected comma-separated integers" in r.output
