"""Command line: info, demo (smoke test of the embedded default), bench, run --set, and exit code 2."""

import json
from pathlib import Path

import meshio
import numpy as np
import pytest
from typer.testing import CliRunner

from pliant.cli import app

runner = CliRunner()


def test_info_json():
    r = runner.invoke(app, ["info", "--json"])
    assert r.exit_code == 0, r.output
    data = json.loads(r.output)
    assert data["backends"]["cpu"]["compiled"] and data["backends"]["cpu"]["threads"] >= 1


def test_demo_writes_a_readable_series(tmp_path):
    """The embedded demo: Spot on a frictional ground plane under gravity, pressed by a moving
    sphere (data/demo.toml). Checks: readable series, nothing inside the ground or the tool, and
    vertical balance on average: ground force − tool force ≈ weight (momentum change small)."""
    import time

    out = tmp_path / "demo"
    t0 = time.perf_counter()
    r = runner.invoke(app, ["demo", "-o", str(out), "--duration", "0.4", "--no-progress"])
    outside = time.perf_counter() - t0  # this test's own clock around the whole command
    assert r.exit_code == 0, r.output
    summary = json.loads((out / "summary.json").read_text())
    # The real-time factor: 0.4 simulated seconds over at most the wall time measured here (the
    # command's clock runs inside ours), and the line says it.
    rtf = summary["real_time_factor"]
    assert summary["simulated_time"] == pytest.approx(0.4, abs=1e-3)
    assert rtf >= summary["simulated_time"] / outside
    assert f"({rtf:.2g}x real time)" in r.output
    pvd = (out / "result.pvd").read_text()
    assert pvd.count("<DataSet") == summary["frames"] == 21
    assert (out / "result.png").stat().st_size > 10_000
    last = meshio.read(out / "frame_00020.vtu")
    u, X, T = last.point_data["displacement"], last.points, last.cells_dict["tetra"]
    x = X + u
    assert np.all(np.isfinite(u)) and T.shape[0] == summary["elements"] > 2000
    assert x[:, 2].min() >= -1e-6  # float32 positions: nothing below the ground
    # The sphere (radius 15 mm) at t = 0.4 s: between keyframes z = 0.115 (t = 0.2) and 0.0995
    # (t = 0.55), linear.
    zc = 0.115 + (0.0995 - 0.115) * (summary["simulated_time"] - 0.2) / 0.35
    assert np.linalg.norm(x - [0.0, -0.055, zc], axis=1).min() >= 0.015 - 1e-6
    tools = {t["name"]: t for t in summary["tools"]}
    assert tools["tool"]["max_force"] > 0.1 and tools["ground"]["max_force"] > 0
    hist = json.loads((out / "tools.json").read_text())
    t = np.array(hist["ground"]["time"])
    window = t > 0.1
    Fg = np.array(hist["ground"]["force"])[window, 2].mean()
    Ft = np.array(hist["tool"]["force"])[window, 2].mean()
    P = X[T]
    vol = (
        np.abs(np.einsum("ij,ij->i", np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), P[:, 3] - P[:, 0])).sum()
        / 6
    )
    weight = 1000.0 * vol * 9.81
    # The ground receives the weight plus the tool's push (both downward on the ground: −z).
    assert -Fg == pytest.approx(weight - Ft, rel=0.15)
    assert not list(out.glob(".*tmp*"))  # no temporary files left behind
    # The results carry the original Spot surface (embedded): at rest it is the file's surface
    # under the scene's transform (scale 0.1, +90° about x, +0.07368 m in z).
    from pliant.mesh import read_surface
    from pliant.demo import DEMO_SCENE

    V, F = read_surface(DEMO_SCENE.parent / "spot.obj")
    V = 0.1 * V
    V = np.stack([V[:, 0], -V[:, 2], V[:, 1]], axis=1) + [0.0, 0.0, 0.07368]
    s0 = meshio.read(out / "surface_00000.vtu")
    assert s0.cells_dict["triangle"].shape == F.shape
    assert np.allclose(s0.points, V, atol=1e-6)
    assert (out / "surface.pvd").read_text().count("<DataSet") == 21


def test_bench_json(tmp_path):
    f = tmp_path / "b.json"
    r = runner.invoke(
        app, ["bench", "--sizes", "600,7456", "--steps", "20", "--large-steps", "5", "--json", str(f)]
    )
    assert r.exit_code == 0, r.output
    rows = json.loads(f.read_text())["rows"]
    assert [row["tets"] for row in rows] == [600, 7456]
    assert rows[1]["speedup_vs_study_gpu"] > 0 and rows[0]["speedup_vs_study_gpu"] is None
    assert all(row["element_steps_per_second"] > 0 for row in rows)


def test_bench_materials_times_each_case_against_the_reference(tmp_path):
    """`pliant bench --materials`: a row per case (every material, viscoelastic, T4ANP and
    edge-smoothed), each a median of 5 chunk ratios with their range (no timing is asserted)."""
    from pliant.bench import material_cases

    f = tmp_path / "m.json"
    r = runner.invoke(app, ["bench", "--materials", "--steps", "10", "--json", str(f)])
    assert r.exit_code == 0, r.output
    rows = json.loads(f.read_text())["materials"]
    assert [row["material"] for row in rows] == [c[0] for c in material_cases()]
    for row in rows:
        assert 0 < row["relative_min"] <= row["relative"] <= row["relative_max"], row
        assert row["steps"] == 10 and row["ms_per_step"] > 0 and 0 < row["element_share"] < 1
    assert "range" in r.output and "median ratio" in r.output


def test_bench_on_a_device_without_kernel_timings(tmp_path):
    """The emulated GPU's launches are not timed one by one (nor are the GPU's, inside graphs):
    the kernel shares are null in the JSON and "-" in the table, not a made-up 0 %."""
    f = tmp_path / "b.json"
    r = runner.invoke(
        app,
        ["bench", "--backend", "cuda-emulated", "--sizes", "600", "--large-steps", "5", "--json", str(f)],
    )
    assert r.exit_code == 0, r.output
    (row,) = json.loads(f.read_text())["rows"]
    assert row["backend"] == "cuda-emulated" and row["element_seconds"] is None
    assert row["threads"] >= 1 and row["element_steps_per_second"] > 0
    row_line = next(ln for ln in r.output.splitlines() if ln.startswith("│") and "600" in ln)
    cells = [c.strip() for c in row_line.split("│")[1:-1]]
    assert cells[5] == "-"  # kernel 1 %


def test_bench_contact_cases_run_on_every_backend(backend, monkeypatch):
    """`pliant bench --contact`'s two tool-contact cases (run from the repository root, where the
    liver example lives), a few steps each: every case runs, and its kernel shares are measured
    on the CPU and null elsewhere (not timed one by one)."""
    from pliant.bench import bench_contact

    monkeypatch.chdir(Path(__file__).resolve().parents[1])
    rows = bench_contact(steps=20, echo=lambda r: None, backend=backend)
    assert [r["case"] for r in rows] == ["demo: Spot + ground + sphere", "liver + capsule"]
    for r in rows:
        assert r["tets"] > 0 and r["contact_nodes"] > 0 and r["tools"] >= 1 and r["seconds"] > 0
        assert (r["contact_share"] is None) == (backend != "cpu")


@pytest.mark.parametrize("sizes", ["abc", "3,,4", "600,", ""])
def test_bad_option_exits_2(sizes):
    r = runner.invoke(app, ["bench", "--sizes", sizes])
    assert r.exit_code == 2
    assert "expected comma-separated integers" in r.output


def test_version_comes_from_pyproject():
    import sys
    from pathlib import Path

    if sys.version_info >= (3, 11):
        import tomllib
    else:
        import tomli as tomllib
    want = tomllib.loads((Path(__file__).parents[1] / "pyproject.toml").read_text())["project"]["version"]
    r = runner.invoke(app, ["--version"])
    assert r.exit_code == 0 and r.output.strip() == f"pliant {want}"


def test_more_frames_than_steps_warns_and_writes_one_per_step(tmp_path):
    """frames = 10⁸ (a typo's worth) on a run of a few dozen steps: one frame per step, said in a
    warning and in summary.json, not a silent gigabyte."""
    scene = tmp_path / "s.toml"
    scene.write_text(
        "[mesh]\nprimitive = 'box'\nsize = [0.02, 0.01, 0.01]\ncells = [2, 1, 1]\n"
        "[[material]]\ntype = 'neo-hookean'\nE = 1e4\nnu = 0.3\ndensity = 1000.0\n"
        "[solver]\nduration = 1e-3\n[output]\nframes = 100000000\n"
    )
    r = runner.invoke(app, ["run", str(scene), "-o", str(tmp_path / "o"), "--no-progress"])
    assert r.exit_code == 0, r.output
    summary = json.loads((tmp_path / "o" / "summary.json").read_text())
    assert summary["frames"] == summary["steps"] + 1 < 1000
    assert any("a frame every step" in w for w in summary["warnings"]), summary["warnings"]


def test_run_set_overrides_scene_keys_and_niftysim_paths(tmp_path):
    """`pliant run --set KEY=VALUE`: a scene key and a NiftySim element path are set before loading
    (the run ends at the duration set: steps × Δt); a malformed item or an unknown key exits 2
    naming it."""
    root = Path(__file__).resolve().parents[1]
    cases = [
        (root / "examples" / "cantilever.toml", ["solver.duration=0.002", "solver.dt=1e-5"], 0.002, 200),
        (root / "tests" / "data" / "niftysim_ball_ball.xml", ["SystemParams.TimeStep=5e-5"], 1.0, 20000),
    ]
    for k, (path, sets, duration, steps) in enumerate(cases):
        out = tmp_path / f"o{k}"
        args = ["run", str(path), "-o", str(out), "--no-progress"]
        r = runner.invoke(app, args + [a for s in sets for a in ("--set", s)])
        assert r.exit_code == 0, r.output
        summary = json.loads((out / "summary.json").read_text())
        assert summary["steps"] == steps and abs(summary["simulated_time"] - duration) < 1e-12
    scene = str(root / "examples" / "cantilever.toml")
    for item, says in [("solver.duration", "expected KEY=VALUE"), ("solver.durationx=1", "durationx")]:
        r = runner.invoke(app, ["run", scene, "-o", str(tmp_path / "bad"), "--set", item])
        assert r.exit_code == 2 and says in r.output and "Traceback" not in r.output


def test_run_set_refuses_what_a_niftysim_path_cannot_hold(tmp_path):
    """`--set` on a NiftySim model with a value its element cannot take exits 2 naming the path and
    what was expected, never a traceback: a word where a number belongs (the import names the
    element), a table, a date or a nested list, and an element of elements (whose text NiftySim
    never reads: the set would have been ignored). Before, a word crashed the command (exit 3) and
    an element of elements took the value silently."""
    model = str(Path(__file__).resolve().parents[1] / "tests" / "data" / "niftysim_ball_ball.xml")
    cases = [
        ("SystemParams.TimeStep=abc", "'abc': expected a number"),
        ("SystemParams.TimeStep={a=1}", "expected a number, a word or a list of numbers"),
        ("SystemParams.TimeStep=2000-01-01", "expected a number, a word or a list of numbers"),
        ("SystemParams.TimeStep=[[1e-4]]", "expected a number, a word or a list of numbers"),
        ("SystemParams=1", "<SystemParams> holds elements"),
    ]
    for item, says in cases:
        r = runner.invoke(app, ["run", model, "-o", str(tmp_path / "bad"), "--no-progress", "--set", item])
        assert r.exit_code == 2, (item, r.output)
        assert says in r.output and "Traceback" not in r.output, (item, r.output)
