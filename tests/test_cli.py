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
    r = runner.invoke(app, ["demo", "-o", str(out), "--duration", "0.1", "--no-progress"])
    assert r.exit_code == 0, r.output
    summary = json.loads((out / "summary.json").read_text())
    pvd = (out / "result.pvd").read_text()
    assert pvd.count("<DataSet") == summary["frames"] == 21
    assert (out / "result.png").stat().st_size > 10_000
    last = meshio.read(out / "frame_00020.vtu")
    u, X, T = last.point_data["displacement"], last.points, last.cells_dict["tetra"]
    assert np.all(np.isfinite(u)) and T.shape[0] == summary["elements"] > 5000
    # The tool patch (surface nodes within 2 cm of (0, -0.055, 0.1)) follows its prescribed
    # SmoothRamp: 15 mm × (10τ³ − 15τ⁴ + 6τ⁵), τ = t / 0.5 (data/demo.toml).
    faces = np.sort(np.concatenate([T[:, [0, 1, 2]], T[:, [0, 1, 3]], T[:, [0, 2, 3]],
                                    T[:, [1, 2, 3]]]), axis=1)
    uniq, count = np.unique(faces, axis=0, return_counts=True)
    surface = np.unique(uniq[count == 1])
    patch = surface[np.linalg.norm(X[surface] - [0.0, -0.055, 0.1], axis=1) <= 0.02]
    assert patch.size > 5
    tau = summary["simulated_time"] / 0.5
    expected = 0.015 * tau**3 * (10 - 15 * tau + 6 * tau**2)
    assert np.allclose(-u[patch, 2], expected, rtol=0, atol=1e-5 * 0.015)  # float32 state
    # The feet (z <= 3 mm) are fixed.
    assert np.abs(u[X[:, 2] <= 0.003]).max() == 0.0
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
