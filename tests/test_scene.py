"""Scene files: validation errors name file, key and line; scenes drive the engine correctly."""

from pathlib import Path
import json
import textwrap

import numpy as np
import pytest
from typer.testing import CliRunner

import pliant as pl
from pliant.cli import app
from pliant.scene import SceneError, load_scene
from pliant.validate.references import UNIAXIAL, uniaxial_reference

runner = CliRunner()

TENSION = """
title = "tension"
[mesh]
primitive = "box"
size = [0.1, 0.1, 0.1]
cells = [3, 3, 3]
jitter = 0.2
translate = [0.05, 0.05, 0.05]

[[material]]
type = "neo-hookean"
mu = 1000.0
K = 10000.0
density = 1000.0

[solver]
static = true
duration = 1.0
increments = 5
dtype = "float64"
tol = 1e-8

[[constraint]]
type = "fix"
dofs = "x"
nodes = { plane = { point = [0, 0, 0], normal = [1, 0, 0] } }
[[constraint]]
type = "fix"
dofs = "y"
nodes = { plane = { point = [0, 0, 0], normal = [0, 1, 0] } }
[[constraint]]
type = "fix"
dofs = "z"
nodes = { plane = { point = [0, 0, 0], normal = [0, 0, 1] } }
[[constraint]]
type = "displacement"
dofs = "x"
value = 0.03
curve = "ramp"
nodes = { plane = { point = [0.1, 0, 0], normal = [1, 0, 0] } }

[output]
png = false
"""


def _write(tmp_path, text, name="s.toml"):
    p = tmp_path / name
    p.write_text(textwrap.dedent(text))
    return p


def test_scene_tension_matches_closed_form(tmp_path):
    """A scene with symmetry planes and a stretched face gives the closed-form uniaxial stress."""
    sc = load_scene(_write(tmp_path, TENSION))
    model = sc.builder.finalize(sc.dtype)
    sim = pl.Simulation(model)
    sim.relax(at_time=sc.duration, tol=sc.tol, increments=sc.increments)
    X = model.reference_positions
    right = np.nonzero(X[:, 0] > 0.1 - 1e-9)[0]
    P = model.internal_forces(sim.state)[right, 0].sum() / 0.01
    P_ref, _ = uniaxial_reference(UNIAXIAL["NeoHookean"][1], 1.3)
    assert P == pytest.approx(P_ref, rel=5e-3)


def test_run_cli_static_scene_outputs(tmp_path):
    out = tmp_path / "out"
    r = runner.invoke(app, ["run", str(_write(tmp_path, TENSION)), "-o", str(out), "--no-progress"])
    assert r.exit_code == 0, r.output
    s = json.loads((out / "summary.json").read_text())
    assert s["mode"] == "static" and s["converged"] and s["frames"] == 2
    # The stretched face moved by 0.03 m along x: the largest displacement is at least that.
    assert s["max_displacement"] >= 0.03


@pytest.mark.parametrize(
    "patch, key, line, text",
    [
        (("[solver]\n", "[solver]\nfoo = 1\n"), "solver.foo", 17, "unknown key 'foo'"),
        (("mu = 1000.0", 'mu = "soft"'), "material[0].mu", 12, "expected number"),
        (('type = "neo-hookean"', 'type = "rubber"'), "material[0].type", 11, "unknown material"),
        (("value = 0.03", "value = 0.03\ncurve2 = 1"), "constraint[3].curve2", None, "unknown key"),
        (
            (
                'normal = [1, 0, 0] } }\n[[constraint]]\ntype = "fix"\ndofs = "y"',
                "normal = [1, 0, 0] }, box = [[5, 5, 5], [6, 6, 6]] }"
                '\n[[constraint]]\ntype = "fix"\ndofs = "y"',
            ),
            "constraint[0].nodes",
            None,
            "selects no node",
        ),
        (  # a box written as a table, as other tools spell it: the message shows the form
            (
                "nodes = { plane = { point = [0, 0, 0], normal = [1, 0, 0] } }",
                "nodes = { box = { min = [0, 0, 0] } }",
            ),
            "constraint[0].nodes.box",
            26,
            "expected list [[x0, y0, z0], [x1, y1, z1]] (opposite corners [m])",
        ),
    ],
)
def test_scene_errors_name_key_and_line(tmp_path, patch, key, line, text):
    bad = TENSION.replace(*patch, 1)
    assert bad != TENSION
    p = _write(tmp_path, bad)
    with pytest.raises(SceneError) as err:
        load_scene(p)
    e = err.value
    assert e.key == key and text in str(e) and str(p) in str(e)
    if line:
        assert e.line == line and f":{line}" in str(e)
    r = runner.invoke(app, ["run", str(p), "-o", str(tmp_path / "o")])
    assert r.exit_code == 2 and "error" in r.output


def test_not_toml_and_missing_file(tmp_path):
    r = runner.invoke(app, ["run", str(_write(tmp_path, "[mesh\nfile=")), "-o", str(tmp_path)])
    assert r.exit_code == 2 and "not valid TOML" in r.output
    r = runner.invoke(app, ["run", str(tmp_path / "nope.toml"), "-o", str(tmp_path)])
    assert r.exit_code == 2 and "no such scene file" in r.output


def test_millimetre_warning(tmp_path):
    text = """
    [mesh]
    primitive = "box"
    size = [100.0, 50.0, 50.0]
    [[material]]
    type = "linear-elastic"
    E = 1e4
    nu = 0.3
    density = 1000.0
    """
    sc = load_scene(_write(tmp_path, text))
    assert any("millimetres" in w for w in sc.warnings)


def test_time_step_above_critical_exits_2(tmp_path):
    text = TENSION.replace("static = true", "static = false\ndt = 1.0")
    r = runner.invoke(app, ["run", str(_write(tmp_path, text)), "-o", str(tmp_path / "o")])
    assert r.exit_code == 2 and "exceeds the stable time step" in r.output


def test_interrupt_keeps_frames_and_summary(tmp_path, monkeypatch):
    """Ctrl-C in the middle of a run: the frames so far and a summary saying so are kept."""
    from pliant import runner as run_mod
    from pliant.tled import Solver

    text = TENSION.replace("static = true", "static = false").replace("[output]", "[output]\nframes = 10")
    sc = load_scene(_write(tmp_path, text))
    calls = {"n": 0}
    orig = Solver.run

    def flaky(self, *a, **k):
        calls["n"] += 1
        if calls["n"] == 4:
            raise KeyboardInterrupt
        return orig(self, *a, **k)

    monkeypatch.setattr(Solver, "run", flaky)
    s = run_mod.run_scene(sc, tmp_path / "o", progress=False)
    assert s["interrupted"] and s["frames"] == 4
    saved = json.loads((tmp_path / "o" / "summary.json").read_text())
    assert saved["interrupted"] and (tmp_path / "o" / "result.pvd").read_text().count("<DataSet") == 4


def test_an_automatic_step_ends_the_run_at_its_duration(tmp_path):
    """dt = "auto" is the fewest whole steps of at most safety × dt_critical that reach the duration,
    so the run ends at it (a 0.01 s run went on to 0.01129 s, the next multiple of the step)."""
    from pliant import runner as run_mod

    text = TENSION.replace("static = true", "static = false").replace("duration = 1.0", "duration = 0.01")
    sc = load_scene(_write(tmp_path, text))
    model, solver = run_mod.build(sc)
    n = int(np.ceil(0.01 / (0.8 * model.dt_critical)))  # the solver's default safety, 0.8
    assert 0.01 / (0.8 * model.dt_critical) % 1 > 0.01  # a step that does not divide the duration
    assert solver.dt == pytest.approx(0.01 / n, rel=1e-15)  # one division: round-off only
    s = run_mod.run_scene(sc, None, progress=False)
    assert s["steps"] == n and s["simulated_time"] == pytest.approx(0.01, rel=1e-12)  # n sums of dt


def test_a_run_replaces_an_earlier_runs_files_and_keeps_the_users(tmp_path):
    """A run of 3 frames into the folder of a run of 10 left frames 4 to 10 beside its own (a
    folder mixing two runs); files that are not a run's stay."""
    from pliant import runner as run_mod

    text = TENSION.replace("static = true", "static = false").replace("duration = 1.0", "duration = 0.2")
    out = tmp_path / "o"
    run_mod.run_scene(load_scene(_write(tmp_path, text.replace("[output]", "[output]\nframes = 10"))), out)
    (out / "notes.txt").write_text("mine")
    (out / "frame_123456.vtu").write_text("")  # frame 123456 of a long run (six digits)
    (out / "frame_1.vtu").write_text("")  # not a name a run gives a frame: stays
    assert len(list(out.glob("frame_*.vtu"))) == 13
    with pytest.warns(
        pl.PliantWarning, match="replaced the 15 files of an earlier run"
    ):  # 12 frames, .pvd, summary.json, reactions.json
        run_mod.run_scene(load_scene(_write(tmp_path, text.replace("[output]", "[output]\nframes = 3"))), out)
    frames = [f"frame_{k:05d}.vtu" for k in range(4)]
    assert sorted(f.name for f in out.glob("frame_*.vtu")) == frames + ["frame_1.vtu"]
    assert (out / "notes.txt").read_text() == "mine"


def test_scene_tools_and_errors(tmp_path):
    """[[tool]] tables build rigid tools with keyframes; bad ones are named errors."""
    text = TENSION.replace(
        "[output]",
        """[[tool]]
type = "capsule"
radius = 0.005
length = 0.04
rotation = [90.0, 0.0, 0.0]
mu_s = 0.3
keyframes = [{ t = 0.0, position = [0.05, 0.05, 0.2] }, { t = 1.0, position = [0.05, 0.05, 0.11] }]

[output]""",
    )
    sc = load_scene(_write(tmp_path, text))
    (tool,) = sc.builder.tools
    R, p = tool.pose(0.5)
    assert np.allclose(p, [0.05, 0.05, 0.155]) and np.allclose(R @ [0, 0, 1], [0, -1, 0], atol=1e-12)
    bad = text.replace('type = "capsule"', 'type = "scalpel"')
    with pytest.raises(SceneError, match="unknown tool 'scalpel'"):
        load_scene(_write(tmp_path, bad, "b.toml"))
    bad = text.replace("mu_s = 0.3", "mu_s = 0.3\nmu_k = 0.5")
    with pytest.raises(SceneError, match="mu_k <= mu_s"):
        load_scene(_write(tmp_path, bad, "c.toml"))


def test_scene_cylinder_tool_restricted_to_a_selection(tmp_path):
    """type = "cylinder" and a `nodes` selection restrict the tool to those nodes (the builder
    receives exactly the nodes the selection names)."""
    text = TENSION.replace(
        "[output]",
        """[[tool]]
type = "cylinder"
radius = 0.005
length = 0.04
position = [0.05, 0.05, 0.2]
nodes = { box = [[0.0, 0.0, 0.09], [0.05, 1.0, 1.0]] }

[output]""",
    )
    sc = load_scene(_write(tmp_path, text))
    (tool,) = sc.builder.tools
    assert isinstance(tool, pl.contact.Cylinder) and tool.radius == 0.005
    X = sc.builder.nodes
    expect = np.nonzero((X[:, 0] <= 0.05 + 1e-12) & (X[:, 2] >= 0.09 - 1e-12))[0]
    assert np.array_equal(sc.builder.tool_nodes[0], expect)
    bad = text.replace("[0.0, 0.0, 0.09], [0.05, 1.0, 1.0]", "[5.0, 5.0, 5.0], [6.0, 6.0, 6.0]")
    with pytest.raises(SceneError, match=r"tool\[0\]\.nodes"):
        load_scene(_write(tmp_path, bad, "b.toml"))


def test_scene_pressure_load_matches_the_api(tmp_path):
    """[[load]] type = "pressure": the boundary triangles whose nodes are all selected carry it;
    the scene's model equals one built through the API with those faces (same bits)."""
    from pliant.mesh.topology import boundary_faces

    text = TENSION.replace(
        "[output]",
        """[[load]]
type = "pressure"
value = -200.0
nodes = { plane = { point = [0.1, 0, 0], normal = [1, 0, 0], side = "on", tol = 1e-6 } }
curve = "ramp"

[output]""",
    )
    sc = load_scene(_write(tmp_path, text))
    ((F, p, _),) = sc.builder._pressures
    X, T = sc.builder.nodes, sc.builder.tets
    B, _ = boundary_faces(T)
    expect = B[np.all(np.abs(X[B][:, :, 0] - 0.1) <= 1e-6, axis=1)]
    assert sorted(map(tuple, F.tolist())) == sorted(map(tuple, expect.tolist()))
    assert np.all(p == -200.0)
    bad = text.replace(
        'nodes = { plane = { point = [0.1, 0, 0], normal = [1, 0, 0], side = "on", tol = 1e-6 } }',
        "nodes = { ids = [0] }",
    )
    with pytest.raises(SceneError, match=r"load\[\d\]\.nodes.*no whole boundary triangle"):
        load_scene(_write(tmp_path, bad, "b.toml"))


@pytest.mark.parametrize(
    "table, expect",
    [
        (
            'type = "transversely-isotropic"\nmu = 1000.0\nK = 10000.0\neta = 500.0\ndirection = [1, 1, 0]',
            pl.TransverselyIsotropic(1000.0, 10000.0, 500.0, (1, 1, 0)),
        ),
        (
            'type = "polynomial"\nC10 = 400.0\nC20 = 50.0\nK = 10000.0',
            pl.Polynomial(400.0, 0.0, 50.0, K=10000.0),
        ),
        (
            'type = "arruda-boyce"\nmu = 1000.0\nlambda_m = 3.0\nK = 10000.0',
            pl.ArrudaBoyce(1000.0, 3.0, 10000.0),
        ),
    ],
)
def test_scene_other_materials(tmp_path, table, expect):
    text = TENSION.replace('type = "neo-hookean"\nmu = 1000.0\nK = 10000.0', table)
    (s,) = load_scene(_write(tmp_path, text)).builder.sets
    assert s.material == expect
    bad = text.replace("K = 10000.0", "E = 3000.0")
    with pytest.raises(SceneError, match="takes"):
        load_scene(_write(tmp_path, bad, "b.toml"))


def test_scene_viscoelastic_material(tmp_path):
    text = TENSION.replace(
        "mu = 1000.0\nK = 10000.0",
        "mu = 1000.0\nK = 10000.0\nprony_iso = [[0.3, 0.1]]\nprony_vol = [[0.1, 0.5]]",
    )
    (s,) = load_scene(_write(tmp_path, text)).builder.sets
    assert s.material == pl.Viscoelastic(
        pl.NeoHookean(mu=1000.0, K=10000.0), iso=[(0.3, 0.1)], vol=[(0.1, 0.5)]
    )
    bad = text.replace("[[0.3, 0.1]]", "[[0.9, 0.1], [0.3, 1.0]]")
    with pytest.raises(SceneError, match="sum"):
        load_scene(_write(tmp_path, bad, "b.toml"))


BUNNY = Path(__file__).resolve().parents[2] / "shared" / "meshes" / "stanford-bunny.obj"


def _mesh_scene_refused(tmp_path, mesh: str) -> str:
    """`pliant run` of a scene with this [mesh] table (lines) and a Neo-Hookean material: exit
    code 2; its output."""
    text = f'[mesh]\n{mesh}\n[[material]]\ntype = "neo-hookean"\nE = 1e4\nnu = 0.3\ndensity = 1000.0\n'
    r = runner.invoke(app, ["run", str(_write(tmp_path, text)), "-o", str(tmp_path / "o")])
    assert r.exit_code == 2, r.output
    return r.output


@pytest.mark.parametrize("mesh", [f'file = "{BUNNY}"', 'primitive = "sphere"\nradius = 0.01'])
def test_an_edge_longer_than_the_body_exits_2_naming_the_key(tmp_path, mesh):
    """edge_length = 5 for a body a few centimetres across (a length in millimetres or
    centimetres): refused at once naming mesh.edge_length and the body's size, where fTetWild ran
    for minutes (a 1 cm sphere: over 2 minutes at an edge of 6 diagonals)."""
    out = _mesh_scene_refused(tmp_path, mesh + "\nedge_length = 5.0")
    assert "mesh.edge_length" in out and "bounding-box diagonal" in out


@pytest.mark.parametrize("envelope", [1e-6, 0.08])
def test_an_envelope_fTetWild_cannot_use_exits_2_naming_the_key(tmp_path, envelope):
    """envelope = 1e-6 ran fTetWild for what looked like ever (over 100 s at 1e-5 on a 642-vertex
    sphere), 0.1 made it abort; the bounds are named with the key."""
    out = _mesh_scene_refused(tmp_path, f'file = "{BUNNY}"\nenvelope = {envelope}')
    assert "mesh.envelope" in out and "expected 5e-05 to 0.05" in out
