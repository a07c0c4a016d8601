"""Hostile input on the command line, one test per defect class (issue 11): every bad input gives
exit code 2 and one line on stderr that names the culprit, no traceback, no signal, no hang, no
Python warning, nothing half-written. Runs the installed ``pliant`` program of this environment,
as a user would."""

import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import meshio
import numpy as np
import pytest

import pliant as pl
from pliant.mesh import grid_tets
from test_niftysim import _cube_xml

PLIANT = Path(sys.executable).with_name("pliant")
ROOT = Path(__file__).parents[1]

SCENE = """title = "bar"
[mesh]
primitive = "box"
size = [0.1, 0.02, 0.02]
cells = [5, 2, 2]
[[material]]
type = "neo-hookean"
E = 5e5
nu = 0.45
density = 1000.0
[solver]
duration = 0.001
[[constraint]]
type = "fix"
nodes = { plane = { point = [-0.05, 0, 0], normal = [1, 0, 0] } }
"""


FLOAT64 = ("[solver]\n", '[solver]\ndtype = "float64"\n')  # SCENE in float64


def cli(*args, cwd=None, timeout=120):
    """Run the installed program; a hang is a failure (TimeoutExpired propagates)."""
    assert PLIANT.exists(), f"the pliant program is not installed in this environment ({PLIANT})"
    env = {**os.environ, "PYTHONWARNINGS": "default"}  # warnings would show if not routed
    env.pop("PLIANT_DEBUG", None)
    return subprocess.run(
        [str(PLIANT), *map(str, args)], capture_output=True, text=True, timeout=timeout, cwd=cwd, env=env
    )


def refused(r, *words):
    """Exit code 2 and exactly one stderr line, 'error: ...', naming each of ``words``."""
    lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert r.returncode == 2, (r.returncode, r.stdout[-2000:], r.stderr[-2000:])
    assert len(lines) == 1 and lines[0].startswith("error: "), r.stderr[-3000:]
    assert "Traceback" not in r.stderr + r.stdout
    for w in words:
        assert w in lines[0], (w, lines[0])
    return lines[0]


def scene(tmp_path, text=SCENE, name="s.toml"):
    p = tmp_path / name
    p.write_text(text)
    return p


# --- resources: threads, steps, sizes ---------------------------------------------------------
@pytest.mark.parametrize("value", ["100000", "0", "-3"])
def test_thread_counts_out_of_range_are_refused_in_scenes(tmp_path, value):
    """100,000 threads crashed OpenMP (segmentation fault); 0 and negatives were taken silently."""
    p = scene(tmp_path, SCENE.replace("duration = 0.001", f"duration = 0.001\nthreads = {value}"))
    refused(cli("run", p, "-o", tmp_path / "o"), str(p), "solver.threads", value)
    assert not (tmp_path / "o").exists()  # a refused run leaves no folder behind


@pytest.mark.parametrize("value", ['"shearing"', "-0.1", "1.5", "true"])
def test_bad_nodal_pressure_stabilization_is_refused_by_key(tmp_path, value):
    """ "shear" or a fraction 0–1 (docs/scenes.md); anything else names the key and its line."""
    solver = "duration = 0.001\nnodal_pressure = true\nnodal_pressure_stabilization = "
    p = scene(tmp_path, SCENE.replace("duration = 0.001", solver + value))
    refused(cli("run", p, "-o", tmp_path / "o"), str(p), "solver.nodal_pressure_stabilization")
    ok = scene(tmp_path, SCENE.replace("duration = 0.001", solver + '"shear"'), name="ok.toml")
    assert cli("run", ok, "-o", tmp_path / "ok").returncode == 0


@pytest.mark.parametrize("value", ["100000", "0", "-1"])
def test_thread_counts_out_of_range_are_refused_on_the_command_line(tmp_path, value):
    refused(cli("run", scene(tmp_path), "-o", tmp_path / "o", "--threads", value), "threads", value)


def test_thread_limit_in_the_api_and_the_engine():
    import pliant as pl
    from pliant import _core

    X, T = pl.mesh.box_tets((1, 1, 1), (1, 1, 1))
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(pl.NeoHookean(E=1e3, nu=0.3), 1000.0)
    for bad in (100000, 0, -1, 2.5, True):
        with pytest.raises(pl.InputError, match="threads"):
            b.finalize(threads=bad)
    assert b.finalize(threads=_core.thread_limit()).threads == _core.thread_limit()


def test_huge_duration_is_refused_before_anything_runs(tmp_path):
    p = scene(tmp_path, SCENE.replace("duration = 0.001", "duration = 1e20"))
    refused(cli("run", p, "-o", tmp_path / "o"), str(p), "duration", "steps")
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize(
    "patch, key",
    [
        (("<TotalTime>0.05</TotalTime>", "<TotalTime>1e30</TotalTime>"), "steps"),
        (("<TimeStep>1e-4</TimeStep>", "<TimeStep>nan</TimeStep>"), "TimeStep"),
        (("<TimeStep>1e-4</TimeStep>", "<TimeStep>-1</TimeStep>"), "TimeStep"),
        (("<DampingCoeff>20</DampingCoeff>", "<DampingCoeff>fast</DampingCoeff>"), "DampingCoeff"),
        (("<Density>1000</Density>", "<Density>inf</Density>"), "Density"),
        (('NumEls="48"', 'NumEls="53"'), "NumEls"),
        (('NumNodes="27"', 'NumNodes="x"'), "NumNodes"),
        (("<Nodes>0 ", "<Nodes>99999 "), "node 99999"),
        (("0.01</Magnitudes>", "nan</Magnitudes>"), "Magnitudes"),
        (('NumParams="2">1000 20000', 'NumParams="3">1000 20000'), "NumParams"),
    ],
)
def test_niftysim_bad_values_are_named(tmp_path, patch, key):
    """Each NiftySim value that used to crash or pass silently (TotalTime 1e30, TimeStep nan,
    NumEls larger than the list, a constraint on node 99999 reported without the file)."""
    *_, xml = _cube_xml()
    assert patch[0] in xml
    p = tmp_path / "m.xml"
    p.write_text(xml.replace(*patch, 1))
    refused(cli("run", p, "-o", tmp_path / "o"), str(p), key)
    assert not (tmp_path / "o").exists()


def test_deeply_nested_toml_is_refused(tmp_path):
    p = scene(tmp_path, "a = " + "[" * 5000 + "]" * 5000 + "\n")
    refused(cli("run", p, "-o", tmp_path / "o"), str(p), "nested")


def test_huge_title_does_not_hang(tmp_path):
    """A 2-million-character title made the PNG title layout run for minutes. A hang fails through
    the subprocess time-out (a guard against a hang, not a speed target: the run takes ~2 s)."""
    p = scene(tmp_path, SCENE.replace('"bar"', '"' + "x" * 2_000_000 + '$\\\\frac{"'))
    r = cli("run", p, "-o", tmp_path / "o", "--no-progress", timeout=60)
    assert r.returncode == 0 and r.stderr == "", r.stderr[-2000:]
    assert (tmp_path / "o" / "result.png").stat().st_size > 10_000


def test_box_sizes_and_jitter_are_bounded(tmp_path):
    p = scene(tmp_path, SCENE.replace("cells = [5, 2, 2]", "cells = [100000, 100000, 100000]"))
    refused(cli("run", p, "-o", tmp_path / "o"), str(p), "tets")
    p = scene(tmp_path, SCENE.replace("cells = [5, 2, 2]", "cells = [5, 2, 2]\njitter = 0.7"))
    refused(cli("run", p, "-o", tmp_path / "o"), str(p), "jitter")
    # TOML's true passed as one cell (bool is an int in Python), and the API's int() made 2.5 two
    p = scene(tmp_path, SCENE.replace("cells = [5, 2, 2]", "cells = [true, 2, 2]"))
    refused(cli("run", p, "-o", tmp_path / "o"), str(p), "mesh.cells", "three integers")
    for cells in [(True, 2, 2), (2.5, 2, 2)]:
        with pytest.raises(pl.InputError, match="expected three integers"):
            pl.mesh.box_tets((0.1, 0.02, 0.02), cells)
    # a subnormal size passes as a length > 0, but the cells' corners coincide (the fuzzer's case:
    # the message showed a numpy array of the coordinates, named xs, which the scene does not have)
    p = scene(tmp_path, SCENE.replace("size = [0.1, 0.02, 0.02]", "size = [0.1, 0.02, 5e-324]"))
    line = refused(cli("run", p, "-o", tmp_path / "o"), str(p), "size = [0.1, 0.02, 5e-324]", "too small")
    assert "array(" not in line and "xs =" not in line


def test_an_element_that_ruins_the_time_step_is_named(tmp_path):
    """A 0.1 mm layer of cells in a bar of 2 cm ones leaves elements 100 times slower than the
    median: the run works, but the user is told which element costs the steps (it used to be
    silent)."""
    X, T = grid_tets([0.0, 0.02, 0.04, 0.0401, 0.06, 0.1], [0.0, 0.01, 0.02], [0.0, 0.01, 0.02])
    mesh = tmp_path / "thin.vtu"
    meshio.write(mesh, meshio.Mesh(X - (0.05, 0.01, 0.01), [("tetra", T)]))
    p = scene(tmp_path, SCENE.replace('primitive = "box"', f'file = "{mesh}"'))
    r = cli("run", p, "-o", tmp_path / "o", "--no-progress")
    warn = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert r.returncode == 0 and len(warn) == 1 and warn[0].startswith("warning: "), r.stderr
    assert re.search(r"element \d+ limits the stable time step", warn[0])


def test_a_density_too_small_for_any_stable_step_is_named(tmp_path):
    """density = 5e-324 kg/m^3 passes as a finite number > 0, but sqrt((lambda + 2 mu) / density)
    overflows: every element's stable step is 0 s, and the critical step with damping divided by
    it (ZeroDivisionError, exit 3; found by tests/test_fuzz.py with PLIANT_FUZZ_EXAMPLES=1500). A
    denormal that neither float32 nor float64 holds as a normal number: refused naming it."""
    p = scene(tmp_path, SCENE.replace("density = 1000.0", "density = 5e-324"))
    refused(cli("run", p, "-o", tmp_path / "o"), str(p), "element set", "density 4.94066e-324", "beyond what")
    p = scene(tmp_path, SCENE.replace("density = 1000.0", "density = 5e-324").replace(*FLOAT64))
    refused(cli("run", p, "-o", tmp_path / "o"), str(p), "density 4.94066e-324", "float64")


# --- memory: a mesh larger than the machine ---------------------------------------------------
def _guarded(argv, capsys):
    """The pliant program run in this process (so that a test can make the machine small): its
    exit code and its non-empty stderr lines."""
    import io

    from rich.console import Console

    from pliant.cli import app
    from pliant.guard import run_guarded

    buf = io.StringIO()
    capsys.readouterr()
    code = run_guarded(app, [str(a) for a in argv], Console(file=buf, width=400))
    text = buf.getvalue() + capsys.readouterr().err
    return code, [ln for ln in text.splitlines() if ln.strip()]


def _machine_with(monkeypatch, *available):
    """Makes pliant.memory see these amounts available [bytes], one per check, the last one
    thereafter (Linux's MemAvailable otherwise)."""
    import pliant.memory

    left = list(available)
    monkeypatch.setattr(pliant.memory, "available_memory", lambda: left.pop(0) if len(left) > 1 else left[0])


def test_a_mesh_larger_than_the_machine_is_refused_before_it_is_made(tmp_path, monkeypatch, capsys):
    """Linux gives every allocation and ends the process without a word when the pages run out: a
    box, a model or a run's frames that need more than the memory available are refused up front,
    naming the size and both amounts (exit 2). 1 GB available here: the 6e6-tet box of [100, 100,
    100] cells needs 2.4 GB at box_tets' 400 bytes a tet (measured 320)."""
    _machine_with(monkeypatch, 1e9)
    p = scene(tmp_path, SCENE.replace("cells = [5, 2, 2]", "cells = [100, 100, 100]"))
    code, lines = _guarded(["run", p, "-o", tmp_path / "o"], capsys)
    assert code == 2 and len(lines) == 1, lines
    for w in (str(p), "cells = [100, 100, 100]", "6e+06 tets", "2.4 GB", "1 GB available"):
        assert w in lines[0], (w, lines[0])
    assert not (tmp_path / "o").exists()  # refused before anything was made


def test_a_model_or_frames_larger_than_the_machine_are_refused(tmp_path, monkeypatch, capsys):
    """The same for a mesh that exists (a file, or the API's arrays) but whose model would not fit
    (300 bytes a tet on top of the mesh), and for a model whose frames would not (700)."""
    X, T = grid_tets(*(np.linspace(0.0, 0.01, 11),) * 3)  # 6,000 tets
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(pl.NeoHookean(mu=1e4, K=1e5), 1000.0)
    _machine_with(monkeypatch, 1e6)  # 1.8 MB needed
    with pytest.raises(pl.InputError, match=r"a model of 6,000 tets needs about 0.0018 GB of memory"):
        b.finalize()
    _machine_with(monkeypatch, 1e12, 1e12, 1e6)  # the box and the model fit, the frames (4.2 MB) do not
    p = scene(tmp_path, SCENE.replace("cells = [5, 2, 2]", "cells = [10, 10, 10]"))
    code, lines = _guarded(["run", p, "-o", tmp_path / "o", "--no-progress"], capsys)
    assert code == 2 and len(lines) == 1 and "the frames of 6,000 tets needs about 0.0042 GB" in lines[0], (
        lines
    )


# --- files: unreadable input, unwritable output ----------------------------------------------
def _bad_outputs(tmp_path):
    (tmp_path / "file").write_text("x")
    return {
        "missing folder": (tmp_path / "no" / "such" / "out.{ext}", "does not exist"),
        "under a file": (tmp_path / "file" / "out.{ext}", "not a folder"),
        "read-only folder": (Path("/proc") / "out.{ext}", "/proc/out"),
        "a folder": (tmp_path, "folder"),
    }


@pytest.mark.parametrize("case", ["missing folder", "under a file", "read-only folder", "a folder"])
@pytest.mark.parametrize("command", ["simplify", "subdivide", "repair", "tetrahedralize"])
def test_unwritable_mesh_outputs_are_named(tmp_path, command, case):
    out, words = _bad_outputs(tmp_path)[case]
    ext = "vtu" if command == "tetrahedralize" else "stl"
    out = Path(str(out).format(ext=ext))
    extra = ["--ratio", "0.5"] if command == "simplify" else []
    r = cli("mesh", command, ROOT / "examples" / "data" / "kidney.obj", out, *extra)
    refused(r, str(out).rstrip("/") if case != "a folder" else str(out), words)


def test_unknown_output_format_is_named(tmp_path):
    refused(
        cli("mesh", "repair", ROOT / "examples" / "data" / "kidney.obj", tmp_path / "k.xyz"),
        "k.xyz",
        "format",
    )


def test_a_sweep_file_given_to_run_says_to_use_sweep(tmp_path):
    refused(
        cli("run", ROOT / "examples" / "cantilever_sweep.toml", "-o", tmp_path / "o"), "pliant sweep", "base"
    )
    assert not (tmp_path / "o").exists()


def test_scene_encodings(tmp_path):
    """TOML is UTF-8. A UTF-8 byte-order mark (Windows editors write one) made a scene "not valid
    TOML" at line 1: it is skipped, and the scene runs. UTF-16, with or without its mark, is named
    as such, for a scene and for a sweep."""
    scene = tmp_path / "bom.toml"
    scene.write_bytes(b"\xef\xbb\xbf" + SCENE.encode())
    r = cli("run", scene, "-o", tmp_path / "o", "--no-progress")
    assert r.returncode == 0 and json.loads((tmp_path / "o" / "summary.json").read_text())["steps"] > 0
    sweep = (ROOT / "examples" / "cantilever_sweep.toml").read_text()
    sweep = sweep.replace('base = "cantilever.toml"', f'base = "{ROOT / "examples" / "cantilever.toml"}"')
    for name, text, says in [
        ("u16.toml", SCENE.encode("utf-16"), "UTF-16-encoded; expected UTF-8"),
        ("u16be.toml", SCENE.encode("utf-16-be"), "NUL bytes (UTF-16, or not text); expected UTF-8"),
    ]:
        (tmp_path / name).write_bytes(text)
        refused(cli("run", tmp_path / name, "-o", tmp_path / "o2"), name, says)
    (tmp_path / "sweep.toml").write_bytes(sweep.encode("utf-16"))
    refused(cli("sweep", tmp_path / "sweep.toml", "-o", tmp_path / "o3"), "sweep.toml", "UTF-16-encoded")


def test_a_mesh_given_to_run_says_what_reads_it(tmp_path):
    mesh = ROOT / "tests" / "data" / "niftysim_sphere.vtk"
    refused(
        cli("run", mesh, "-o", tmp_path / "o"),
        "a mesh (.vtk), not a scene",
        "[mesh] file",
        "pliant mesh check",
    )
    assert not (tmp_path / "o").exists()


def test_results_folder_that_cannot_be_made(tmp_path):
    (tmp_path / "file").write_text("x")
    refused(cli("run", scene(tmp_path), "-o", tmp_path / "file" / "o"), "file", "o")


@pytest.mark.parametrize("content", [b"<VTKFile garbage", b"", b"\x00\xff" * 100])
def test_unreadable_volume_meshes_are_named(tmp_path, content):
    """meshio prints 'Error: ...' and calls sys.exit(1) on some files: it was exit 1 with a blank
    error line."""
    p = tmp_path / "bad.vtu"
    p.write_bytes(content)
    refused(cli("mesh", "quality", p), str(p), "cannot read")
    s = scene(tmp_path, SCENE.replace('primitive = "box"', f'file = "{p}"'))
    refused(cli("run", s, "-o", tmp_path / "o"), str(s), "mesh.file", str(p))


def test_flat_surface_is_refused_as_enclosing_no_volume(tmp_path):
    """Four coplanar vertices, both sides: fTetWild crashed (segmentation fault)."""
    p = tmp_path / "flat.obj"
    p.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\nf 1 3 2\nf 2 3 4\n")
    refused(cli("mesh", "tetrahedralize", p, tmp_path / "flat.vtu"), "encloses no volume", "plane")
    assert not (tmp_path / "flat.vtu").exists()


def test_a_repeated_element_is_refused_by_name(tmp_path):
    """Two copies of one tet have no boundary: the run went on and its picture crashed (exit 3)."""
    X = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0]]) * 0.01
    p = tmp_path / "twice.vtu"
    meshio.write(p, meshio.Mesh(X, [("tetra", np.array([[0, 1, 2, 3], [1, 2, 3, 0]]))]))
    s = scene(tmp_path, SCENE.replace('primitive = "box"', f'file = "{p}"'))
    refused(cli("run", s, "-o", tmp_path / "o"), "element 1 has the same four nodes as element 0")
    assert not (tmp_path / "o").exists() or not any((tmp_path / "o").iterdir())


def test_quality_of_degenerate_tets_prints_no_nan(tmp_path):
    """A zero-volume tet made 'the worst element costs nan× the steps'."""
    X = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0], [1, 1, 0]])
    p = tmp_path / "d.vtu"
    meshio.write(p, meshio.Mesh(X, [("tetra", np.array([[0, 1, 2, 3], [0, 1, 2, 4]]))]))
    r = cli("mesh", "quality", p)
    assert r.returncode == 0 and "1 degenerate" in r.stdout, r.stdout + r.stderr
    assert not re.search(r"\b(nan|inf)\b", r.stdout), r.stdout
    r = cli("mesh", "quality", p, "--json")
    import json

    s = json.loads(r.stdout)  # strict JSON: no NaN or Infinity tokens
    assert s["degenerate"] == 1 and s["dt_critical"]["element"] == 0


def test_quality_names_elements_that_overlap(tmp_path):
    """Two positive tets on the same side of their face: quality showed a clean mesh (0 inverted,
    0 degenerate) that the run then refused; it names the overlap now, as the run does."""
    X = 0.01 * np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [0.2, 0.2, 0.5]])
    p = tmp_path / "tangled.vtu"
    meshio.write(p, meshio.Mesh(X, [("tetra", np.array([[0, 1, 2, 3], [0, 1, 2, 4]]))]))
    words = "elements 0 and 1 lie on the same side of their common face [0, 1, 2]"
    r = cli("mesh", "quality", p)
    assert r.returncode == 0 and words in r.stdout.replace("\n", " "), r.stdout + r.stderr
    import json

    assert words in json.loads(cli("mesh", "quality", p, "--json").stdout)["not_conforming"]
    s = scene(tmp_path, SCENE.replace('primitive = "box"', f'file = "{p}"'))
    refused(cli("run", s, "-o", tmp_path / "o"), words)


# --- messages ---------------------------------------------------------------------------------
def test_empty_key_is_quoted_in_the_message(tmp_path):
    p = scene(tmp_path, SCENE + '"" = 1\n')
    line = refused(cli("run", p, "-o", tmp_path / "o"), str(p), 'constraint[0].""')
    assert ": :" not in line


def test_png_false_does_not_announce_a_picture(tmp_path):
    p = scene(tmp_path, SCENE + "[output]\npng = false\n")
    r = cli("run", p, "-o", tmp_path / "o", "--no-progress")
    assert r.returncode == 0 and "result.png" not in r.stdout and "summary.json" in r.stdout
    assert not (tmp_path / "o" / "result.png").exists()


def _with_signals(disposition: str, argv: list[str]) -> list[str]:
    """``argv`` run with SIGINT at its default ("default": as from a terminal) or ignored
    ("ignore": as a shell's background job), whatever this process has (a test runner started in
    the background ignores SIGINT, and its children inherit that): a launcher sets it and execs
    the command in its place (the same process, so its pid gets the signals sent)."""
    launcher = (
        "import os, signal, sys; "
        f"signal.signal(signal.SIGINT, signal.{'SIG_DFL' if disposition == 'default' else 'SIG_IGN'}); "
        "os.execv(sys.argv[1], sys.argv[1:])"
    )
    return [sys.executable, "-c", launcher, *argv]


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["ctrl-c", "sigterm"])
def test_interrupted_run_indexes_every_frame_it_wrote(tmp_path, sig):
    """Ctrl-C between a frame's file and the index left result.pvd one frame short. SIGTERM (a
    batch scheduler's time limit, `timeout`, `kill`) ended the run without its summary: both now
    end it as an interruption, every frame indexed and summary.json written."""
    p = scene(
        tmp_path, SCENE.replace("duration = 0.001", "duration = 100.0") + "[output]\nevery = 1\npng = false\n"
    )
    proc = subprocess.Popen(
        _with_signals("default", [str(PLIANT), "run", str(p), "-o", str(tmp_path / "o"), "--no-progress"]),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, "PYTHONFAULTHANDLER": "1"},  # SIGABRT below prints every thread's stack
    )
    deadline = time.time() + 60
    while time.time() < deadline and len(list((tmp_path / "o").glob("frame_*.vtu"))) < 20:
        time.sleep(0.05)
    proc.send_signal(sig)
    try:
        out, err = proc.communicate(timeout=60)
    except subprocess.TimeoutExpired:  # a hang: fail with where the run was (faulthandler's dump)
        proc.send_signal(signal.SIGABRT)
        out, err = proc.communicate(timeout=30)
        pytest.fail(f"the run did not end within 60 s of {sig!r}; its stacks:\n{err[-6000:]}")
    assert proc.returncode == 130, (out, err)
    assert "Traceback" not in err and "interrupted at t = " in err
    assert json.loads((tmp_path / "o" / "summary.json").read_text())["interrupted"]
    frames = sorted(f.name for f in (tmp_path / "o").glob("frame_*.vtu"))
    listed = re.findall(r'file="([^"]+)"', (tmp_path / "o" / "result.pvd").read_text())
    assert len(frames) >= 20 and listed == frames
    assert not list((tmp_path / "o").glob(".*tmp*"))  # nothing half-written left behind


def test_a_run_that_ignores_ctrl_c_is_not_interrupted_by_it(tmp_path):
    """A run started with SIGINT ignored (a shell's background job) runs to its end whatever SIGINTs
    arrive, even while frames are written (where the interrupt is held and raised after the frame:
    such a run was interrupted by a SIGINT that landed there). 200 frames of a short run, a SIGINT
    every 20 ms from its 10th frame on."""
    p = scene(
        tmp_path,
        SCENE.replace("duration = 0.001", "duration = 0.05") + "[output]\nframes = 200\npng = false\n",
    )
    proc = subprocess.Popen(
        _with_signals("ignore", [str(PLIANT), "run", str(p), "-o", str(tmp_path / "o"), "--no-progress"]),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    deadline = time.time() + 60
    while time.time() < deadline and len(list((tmp_path / "o").glob("frame_*.vtu"))) < 10:
        time.sleep(0.02)
    sent = 0
    while proc.poll() is None and time.time() < deadline:
        proc.send_signal(signal.SIGINT)
        sent += 1
        time.sleep(0.02)
    out, err = proc.communicate(timeout=60)
    assert sent > 5, "the run ended before the SIGINTs"
    assert proc.returncode == 0, (out, err)
    assert not json.loads((tmp_path / "o" / "summary.json").read_text())["interrupted"]


def test_an_interrupt_before_frame_0_is_on_disk_still_ends_with_a_summary(tmp_path, monkeypatch):
    """Frame 0 is written inside the run's interruption handling: a Ctrl-C that lands while its
    fields are computed (before the file is held against interrupts) ends the run as interrupted,
    with summary.json, which lists no index since no frame reached the disk, and only files that exist."""
    from pliant.io.results import ResultWriter
    from pliant.runner import run_scene
    from pliant.scene import load_scene

    def interrupted(self, state):
        raise KeyboardInterrupt  # where Python raises a SIGINT that lands outside the held block

    monkeypatch.setattr(ResultWriter, "write", interrupted)
    summary = run_scene(load_scene(scene(tmp_path)), tmp_path / "o")
    on_disk = json.loads((tmp_path / "o" / "summary.json").read_text())
    assert summary["interrupted"] and on_disk["interrupted"] and on_disk["frames"] == 0
    assert "result.pvd" not in on_disk["files"] and not (tmp_path / "o" / "result.pvd").exists()
    assert all((tmp_path / "o" / f).is_file() for f in on_disk["files"])  # each file it lists is there


# --- the guard itself --------------------------------------------------------------------------
def test_internal_errors_give_one_line_a_log_and_exit_3(tmp_path, monkeypatch):
    """An unexpected exception is a bug, but the user gets one line naming it and the log file
    that holds the traceback."""
    import io

    import typer
    from rich.console import Console

    from pliant.guard import EXIT_INTERNAL, run_guarded

    app = typer.Typer()

    @app.command()
    def boom(x: int = 1):
        raise RuntimeError("kaboom [/bold] \n second line")

    @app.command()
    def other():
        pass

    monkeypatch.setenv("TMPDIR", str(tmp_path))
    import tempfile

    monkeypatch.setattr(tempfile, "tempdir", None)
    buf = io.StringIO()
    code = run_guarded(app, ["boom"], Console(file=buf, width=300))
    lines = [ln for ln in buf.getvalue().splitlines() if ln.strip()]
    assert code == EXIT_INTERNAL == 3 and len(lines) == 1, buf.getvalue()
    assert "RuntimeError: kaboom" in lines[0] and "Traceback" not in buf.getvalue()
    log = Path(re.search(r"full traceback in (\S+?);", lines[0]).group(1))
    assert log.parent == tmp_path and "Traceback" in log.read_text()
    assert "raise RuntimeError" in log.read_text()


def test_file_system_refusals_exit_2(tmp_path):
    """An OSError that escapes a command (permissions, a full disk) is the environment's, not a
    bug: exit 2 and one line naming the file."""
    import io

    import typer
    from rich.console import Console

    from pliant.guard import run_guarded

    app = typer.Typer()

    @app.command()
    def read():
        raise PermissionError(13, "Permission denied", str(tmp_path / "locked.obj"))

    @app.command()
    def other():
        pass

    buf = io.StringIO()
    assert run_guarded(app, ["read"], Console(file=buf, width=300)) == 2
    assert buf.getvalue().strip() == f"error: {tmp_path / 'locked.obj'}: Permission denied"


def test_inputs_that_are_not_regular_files_are_refused_without_waiting(tmp_path):
    """A named pipe with no writer made `pliant run model.xml` and `pliant mesh quality` wait for
    ever (the XML parser, the VTK header check opened it); /dev/zero and a folder were "no such
    file". Each is now refused by what it is (cli's timeout fails a hang)."""
    pipe = tmp_path / "pipe"
    os.mkfifo(pipe)
    for name in ("model.xml", "mesh.vtk", "scene.toml", "sweep.toml"):
        (tmp_path / name).symlink_to(pipe)
    scene = tmp_path / "s.toml"
    not_regular = "not a regular file (a pipe, device or socket"
    for args, culprit, what in [
        (("run", tmp_path / "model.xml"), "model.xml", not_regular),
        (("run", tmp_path / "scene.toml"), "scene.toml", not_regular),
        (("run", "/dev/zero"), "/dev/zero", not_regular),
        (("run", tmp_path), str(tmp_path), "a folder, not a file"),
        (("sweep", tmp_path / "sweep.toml"), "sweep.toml", not_regular),
        (("mesh", "quality", tmp_path / "mesh.vtk"), "mesh.vtk", not_regular),
        (("mesh", "check", "/dev/zero"), "/dev/zero", not_regular),
        (("run", scene), "[mesh.file]", not_regular),
    ]:
        scene.write_text(SCENE.replace('primitive = "box"', f'file = "{tmp_path / "mesh.vtk"}"'))
        out = tmp_path / "out"
        refused(
            cli(*args, "-o", out, timeout=60) if args[0] in ("run", "sweep") else cli(*args, timeout=60),
            culprit,
            what,
        )


def test_outputs_are_written_with_the_users_permissions_and_never_over_a_device(tmp_path):
    """Every output was mode 0600 whatever the umask (the temporary file's, renamed into place):
    a colleague or a web server could not read the results. A file now gets what open() gives a
    new one, 0666 less the umask, or keeps the mode of the file it replaces. And an output path
    that is a pipe or a device is refused: the rename would have replaced /dev/null itself."""
    scene = tmp_path / "s.toml"
    scene.write_text(SCENE)
    r = subprocess.run(
        f"umask 027 && {PLIANT} run {scene} -o {tmp_path / 'out'} --no-progress",
        shell=True,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert r.returncode == 0, r.stderr
    for f in (tmp_path / "out").iterdir():
        assert f.stat().st_mode & 0o777 == 0o640, (f.name, oct(f.stat().st_mode))
    mesh = tmp_path / "t.vtk"
    meshio.write(mesh, meshio.Mesh(np.eye(4, 3)[[3, 0, 1, 2]], [("tetra", np.array([[0, 1, 2, 3]]))]))
    kept = tmp_path / "kept.png"
    kept.write_bytes(b"")
    kept.chmod(0o604)
    assert cli("mesh", "quality", mesh, "--png", kept).returncode == 0
    assert kept.stat().st_mode & 0o777 == 0o604 and kept.stat().st_size > 1000
    pipe = tmp_path / "pipe.png"
    os.mkfifo(pipe)
    refused(cli("mesh", "quality", mesh, "--png", pipe, timeout=60), "pipe.png", "not a regular file")
    assert pipe.is_fifo()


def test_usage_errors_exit_2():
    r = cli("run")
    assert r.returncode == 2 and "Traceback" not in r.stderr
    r = cli("no-such-command")
    assert r.returncode == 2 and "Traceback" not in r.stderr


# --- more resource bounds (found by a second probe) -------------------------------------------
@pytest.mark.parametrize(
    "patch, words",
    [
        (("size = [0.1, 0.02, 0.02]", "size = [1e300, 1e300, 1e300]"), ["non-finite volume"]),
        # float64 holds these numbers, and the step they make is refused.
        ([("E = 5e5", "E = 1e300"), FLOAT64], ["steps"]),
        ([("density = 1000.0", "density = 1e-300"), FLOAT64], ["steps"]),
        # A given dt is checked against the mesh's highest frequency, whose M⁻¹K overflowed (an
        # internal error: ARPACK could not start): refused against its stable step (1e-156 s).
        (
            ("density = 1000.0\n[solver]\n", 'density = 1e-300\n[solver]\ndt = 1e-3\ndtype = "float64"\n'),
            ["dt = 0.001 s exceeds the stable time step"],
        ),
        # float32 does not hold them: refused naming the material and the range (1e-300 was 0 in
        # the engine; 1e300 inf). μ = 1e308 with K as NiftySim gives it: 2μ overflows even float64.
        (("E = 5e5", "E = 1e300"), ["element set", "3.45e+299 is beyond what float32 holds", "SI units"]),
        (("density = 1000.0", "density = 1e-300"), ["density 1e-300 kg/m^3", "beyond what float32 holds"]),
        (
            ('type = "neo-hookean"\nE = 5e5\nnu = 0.45\n', 'type = "neo-hookean"\nmu = 1e308\nK = 3000.0\n'),
            ["NeoHookean(mu=1e+308, lam=-inf)", "beyond what float32 holds"],
        ),
        (
            [("E = 5e5\nnu = 0.45\n", "mu = 1e308\nK = 3000.0\n"), FLOAT64],
            ["lam=-inf", "-inf is beyond what float64 holds"],
        ),
        (
            ("duration = 0.001", "duration = 0.001\nstatic = true\nincrements = 1000000000"),
            ["solver.increments"],
        ),
    ],
)
def test_extreme_values_are_refused_in_one_line(tmp_path, patch, words):
    """Coordinates that overflow the geometry (an internal error before), materials and densities
    that make the stable step absurdly small (automatic or given), and a billion load increments
    (a hang)."""
    text = SCENE
    for old, new in patch if isinstance(patch, list) else [patch]:
        assert old in text
        text = text.replace(old, new)
    p = scene(tmp_path, text)
    refused(cli("run", p, "-o", tmp_path / "o"), str(p), *words)


@pytest.mark.parametrize("size", [1e10, 1e-12])
def test_volumes_beyond_float32_are_refused_and_float64_takes_the_large_ones(tmp_path, size):
    """A box 1e10 m across (a file read in the wrong unit) has tets of ~1e28 m^3: in float32 the
    engine's forces V0·S·∇N overflowed and the run stopped as "unstable" (exit 1, NaN at the first
    step); tets of 1e-12 m (1e-37 m^3) lost their mass and forces to underflow. Both are refused,
    naming the element and the range; float64 holds 1e28 m^3 and runs."""
    text = SCENE.replace("size = [0.1, 0.02, 0.02]", f"size = [{size}, {size}, {size}]")
    text = text.replace("point = [-0.05, 0, 0]", f"point = [{-size / 2}, 0, 0]")
    text = text.replace("duration = 0.001", "duration = 1e-14" if size < 1 else "duration = 0.001")
    p = scene(tmp_path, text)
    refused(
        cli("run", p, "-o", tmp_path / "o"), str(p), "element 0 has volume", "float32", "dtype = 'float64'"
    )
    if size > 1:
        p64 = scene(tmp_path, text.replace(*FLOAT64), name="f64.toml")
        r = cli("run", p64, "-o", tmp_path / "o64")
        assert r.returncode == 0 and "Traceback" not in r.stderr, r.stderr[-2000:]


def test_a_mesh_file_cell_beyond_its_nodes_is_named(tmp_path):
    """A cell of a volume mesh file that refers to a node the file does not have (meshio reads it
    as it is): `pliant mesh quality` crashed with an IndexError (exit 3); now the file, the cell,
    its kind and the node are named, exit 2, for tets and for the cells split into them."""
    X = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1.0]])
    for kind, cell, node in (("tetra", [0, 1, 3, 99], 99), ("hexahedron", [0, 1, 2, 3, 4, 5, 6, -1], -1)):
        p = tmp_path / f"{kind}.vtu"
        meshio.write(p, meshio.Mesh(X, [(kind, np.array([cell]))]))
        refused(cli("mesh", "quality", p), str(p), f"cell 0 ({kind}) refers to node {node}", "8 nodes")


def test_volume_meshes_with_other_cells_are_refused(tmp_path):
    """Cells beside tets were dropped silently: the run simulated a part of the body. Linear
    hexahedra are split into tetrahedra now (pliant.mesh.split), quadratic ones by their corners;
    a cell pliant does not take (a Lagrange tetrahedron) is refused by kind."""
    X = np.array(
        [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1], [2, 0, 0.0]]
    )
    p = tmp_path / "hex.vtu"
    hexa = np.array([[0, 1, 2, 3, 4, 5, 6, 7]])
    meshio.write(p, meshio.Mesh(X, [("hexahedron", hexa), ("tetra", np.array([[1, 8, 2, 5]]))]))
    r = cli("mesh", "quality", p)
    assert r.returncode == 0 and "7 tets" in r.stdout, r.stdout[-2000:]  # 6 from the hexahedron
    lagrange = "VTK_LAGRANGE_TETRAHEDRON"
    meshio.write(
        p, meshio.Mesh(np.random.default_rng(0).random((10, 3)), [(lagrange, np.arange(10)[None, :])])
    )
    refused(cli("mesh", "quality", p), str(p), f"1 {lagrange}")


@pytest.mark.parametrize(
    "args, words",
    [
        (["demo", "--duration", "-1"], ["--duration"]),
        (["demo", "--duration", "nan"], ["--duration"]),
        (["bench", "--dtype", "float16"], ["--dtype"]),
        (["bench", "--sizes", "1000000000000"], ["--sizes"]),
        (["bench", "--steps", "1000000000000"], ["--steps"]),
        (["view", "x.toml", "--port", "0"], ["--port"]),
        (
            ["mesh", "subdivide", ROOT / "src" / "pliant" / "data" / "spot.obj", "OUT", "--levels", "6"],
            ["6 levels"],
        ),
    ],
)
def test_command_options_out_of_range(tmp_path, args, words):
    args = [tmp_path / "s.obj" if a == "OUT" else a for a in args]
    if args[0] == "demo":
        args += ["-o", tmp_path / "d"]
    refused(cli(*args, cwd=tmp_path), *words)
    assert not (tmp_path / "d").exists()


@pytest.mark.parametrize("value", ['"faces"', "1", "true"])
def test_unknown_strain_smoothing_is_named(tmp_path, value):
    p = scene(tmp_path, SCENE.replace("duration = 0.001", f"duration = 0.001\nstrain_smoothing = {value}"))
    refused(cli("run", p, "-o", tmp_path / "o"), str(p), "solver.strain_smoothing")


def test_edge_smoothing_runs_from_a_scene(tmp_path):
    """`strain_smoothing = "edge"` in [solver] builds the edge domains and runs."""
    from pliant.scene import load_scene

    p = scene(tmp_path, SCENE.replace("duration = 0.001", 'duration = 0.001\nstrain_smoothing = "edge"'))
    model = load_scene(p).builder.finalize()
    assert model._engine.n_edges > model.n_elements  # ~1.2 edges per tet (here 6 × 20 cells)
    r = cli("run", p, "-o", tmp_path / "o")
    assert r.returncode == 0, r.stderr


def test_a_blade_in_a_viscoelastic_edge_smoothed_scene_is_refused_upfront(tmp_path):
    """The Prony state of edge-smoothed strain lives on edges, which a cut changes: the scene is
    refused when loaded, not at the first cut."""
    text = (ROOT / "examples" / "cut_cantilever.toml").read_text()
    text = text.replace("density = 1100.0", "density = 1100.0\nprony_iso = [[0.3, 0.1]]")
    text = text.replace("damping = 5.0", 'damping = 5.0\nstrain_smoothing = "edge"')
    p = scene(tmp_path, text)
    refused(cli("run", p, "-o", tmp_path / "o"), str(p), "solver.strain_smoothing", "cannot be cut yet")


def test_a_displacement_applied_whole_in_the_first_step_is_named_when_it_inverts(tmp_path):
    """The bar's free end prescribed −3 cm along x with no curve (a constant: all of it in the
    first step) crosses its 2 cm cells in that step and inverts them, whatever the step: the error
    names the node, the displacement and what to do, where it said only "reduce dt"; ramped
    (curve = "smooth-ramp" over 0.05 s) the same displacement runs, and an instability later than
    the first check (the same ramp over 1 ms, inverting at 0.875 ms) gets no such hint."""
    push = (
        '[[constraint]]\ntype = "displacement"\ndofs = "x"\nvalue = -0.03\n'
        "nodes = { plane = { point = [0.05, 0, 0], normal = [1, 0, 0] } }\n"
    )
    r = cli("run", scene(tmp_path, SCENE + push), "-o", tmp_path / "o")
    lines = [ln for ln in r.stderr.splitlines() if ln.startswith("error: ")]
    assert r.returncode == 1 and len(lines) == 1 and "Traceback" not in r.stderr, r.stderr
    assert "is prescribed -0.03 m along x from the first step on" in lines[0], lines[0]
    assert 'curve = "smooth-ramp"' in lines[0]
    ramped = SCENE + push.replace("value = -0.03\n", 'value = -0.03\ncurve = "smooth-ramp"\n')
    r = cli(
        "run", scene(tmp_path, ramped.replace("duration = 0.001", "duration = 0.05")), "-o", tmp_path / "o2"
    )
    assert r.returncode == 0, r.stderr
    r = cli("run", scene(tmp_path, ramped), "-o", tmp_path / "o3")
    assert r.returncode == 1 and "inverted" in r.stderr and "first step" not in r.stderr, r.stderr
