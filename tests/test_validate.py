"""`pliant validate`: the quick run passes every check and writes its report; a failing check
makes the command exit 1 naming it."""

from __future__ import annotations

import json

from typer.testing import CliRunner

import pliant.validate.cases as cases
from pliant.cli import app
from pliant.validate import Check
from pliant.validate.peers import _mujoco_missing, _newton_missing


def test_quick_validation_passes_and_reports(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # nothing but the report lands in the working folder
    r = CliRunner().invoke(app, ["validate", "--quick", "-o", str(tmp_path / "out")])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]  # no MUJOCO_LOG.TXT
    tmp_path = tmp_path / "out"
    assert r.exit_code == 0, r.output
    data = json.loads((tmp_path / "results.json").read_text())
    assert data["rows"] and all(row["passed"] for row in data["rows"])
    assert {row["case"] for row in data["rows"]} >= {
        "uniaxial stress",
        "patch test",
        "simple shear",
        "rigid rotation",
        "hexahedra split",
        "NiftySim H8 (user guide §3.1)",
        "cantilever bending",
        "bending sheets",
        "finite torsion (Rivlin)",
        "Lamé sphere (T4ANP)",
        "damped decay",
    }
    report = (tmp_path / "report.md").read_text()
    assert f"{len(data['rows'])} of {len(data['rows'])} checks passed" in report
    # The cases the full run alone has are named as left out, not counted as "0/0 passed".
    assert data["left_out"] == ["elastica", "hertz", "hertz_soft"]
    assert "Left out of the quick run (the full run has them): elastica, hertz, hertz_soft." in report
    assert "elastica: full run only (not in --quick)" in r.output and "0/0" not in r.output
    for png in ("uniaxial.png", "cantilever.png", "torsion.png"):
        assert (tmp_path / png).stat().st_size > 5000 and f"]({png})" in report
    peers = {p["peer"].split()[0]: p for p in data["peers"]}
    assert peers["pliant"]["ran"] and 0.4 < peers["pliant"]["ratio"] < 1.0  # locked linear tets
    for name, case, missing in (
        ("mujoco", "peers: MuJoCo flex, same mesh", _mujoco_missing),
        ("newton", "peers: Newton semi-implicit, same mesh", _newton_missing),
    ):
        peer = peers[name]
        if not missing():  # the test extras install it
            assert peer["ran"] and case in {r["case"] for r in data["rows"]}
            assert f"| {peer['peer']} | {peer['ratio']:.4f} |" in report
        else:
            assert not peer["ran"] and peer["note"] == missing()


def test_a_failing_check_exits_1_naming_it(tmp_path, monkeypatch):
    wrong = Check("made up", "two against one", 2.0, 1.0, "1", "a check that must fail", 0.1)
    monkeypatch.setattr(cases, "CASES", {"bad": lambda quick: ([wrong], {})})
    monkeypatch.setattr("pliant.validate.report.CASES", cases.CASES)
    # Nor NiftySim's models nor the peers: the quick run above runs them (here they cost 30 s).
    monkeypatch.setattr("pliant.validate.report.run_cross_checks", lambda niftysim: ([], []))
    monkeypatch.setattr("pliant.validate.report.run_peers", lambda quick: ([], []))
    # An earlier report in the folder: its plot goes (this run has none), other files stay.
    for name in ("results.json", "cantilever.png", "notes.txt"):
        (tmp_path / name).write_text("earlier")
    r = CliRunner().invoke(app, ["validate", "--quick", "-o", str(tmp_path)])
    assert r.exit_code == 1
    assert not (tmp_path / "cantilever.png").exists() and (tmp_path / "notes.txt").exists()
    assert "made up, two against one" in r.output
    assert "**FAIL**" in (tmp_path / "report.md").read_text()
