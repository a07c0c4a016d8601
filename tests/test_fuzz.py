"""Property-based fuzzing (hypothesis) of everything that reads user files: the scene loader, the
NiftySim importer and the mesh readers. Property: a file either loads (and then builds and steps)
or raises a typed pliant error (InputError; InstabilityError once running) whose message is one
line naming the file. Any other exception, a crash or a hang fails. A fixed budget of examples,
derandomized, so that CI runs the same cases every time."""

import atexit
import math
import os
import re
import shutil
import tempfile
import warnings
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import pliant as pl
from pliant.errors import InputError, PliantError
from pliant.io.niftysim import load_niftysim
from pliant.scene import load_scene
from test_hostile import SCENE
from test_niftysim import _cube_xml

# CI's budget: 120 examples per test, the same ones every run. PLIANT_FUZZ_EXAMPLES=5000 explores
# more, with fresh random cases each time (a developer's hunt; failures print their input).
_EXPLORE = int(os.environ.get("PLIANT_FUZZ_EXAMPLES", "0"))
BUDGET = settings(
    max_examples=_EXPLORE or 120,
    deadline=None,
    derandomize=not _EXPLORE,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)

# The hostile-input tests' minimal scene, with more of everything for the mutations to hit.
BASE = (
    SCENE.replace('title = "bar"', 'title = "fuzz"')
    .replace("density = 1000.0", "density = 1000.0\nprony_iso = [[0.3, 0.1]]")
    .replace("duration = 0.001", 'duration = 0.0005\ndamping = 5.0\ndtype = "float64"')
    + """[[constraint]]
type = "displacement"
nodes = { box = [[0.04, -1, -1], [1, 1, 1]] }
value = 0.001
dofs = "x"
curve = { type = "ramp", t1 = 0.0005 }
[[load]]
type = "gravity"
[[tool]]
type = "sphere"
radius = 0.005
position = [0.0, 0.0, 0.02]
[output]
frames = 2
"""
)

HOSTILE = [
    "nan",
    "inf",
    "-inf",
    "0",
    "-1",
    "1e308",
    "1e-308",
    "100000",
    "99999999999999999999",
    '""',
    '"x"',
    '"' + "y" * 300 + '"',
    "[]",
    "[[]]",
    "[1, 2]",
    "[nan, 0, 0]",
    "{}",
    "{ a = 1 }",
    "true",
    "false",
    "2.5",
    "[0.0, 0.0, 0.0]",
    "[1e30, 1, 1]",
    "-0.0",
]


def _check_error(e: Exception, path: Path):
    msg = str(e)
    assert "\n" not in msg and msg.strip(), repr(msg)
    assert str(path) in msg, f"the message does not name the file: {msg}"
    assert "np.float64(" not in msg and "array(" not in msg, msg


def _build_and_step(scene):
    """What `pliant run` does with a loaded scene, for three steps."""
    from pliant.runner import build

    model, solver = build(scene)
    solver.run(model.state(), steps=3)


def _loads_or_fails_by_name(load, p: Path):
    """The property of every scene-like file: loads, builds and steps, or fails typed by name."""
    try:
        _build_and_step(load(p))
    except InputError as e:
        _check_error(e, p)
    except PliantError:  # went unstable while stepping: typed, and named by the runner
        pass


@pytest.fixture(autouse=True)
def _a_hang_fails():
    """A test of CI's budget that runs past 10 minutes fails (TimeoutError) instead of stalling the
    suite: a reader that never returns is one of the failures these tests look for. Not set when
    exploring (PLIANT_FUZZ_EXAMPLES), whose budget is the developer's."""
    import signal

    if _EXPLORE or not hasattr(signal, "SIGALRM"):
        yield
        return

    def hung(signum, frame):
        raise TimeoutError("a fuzz test ran past 600 s: a reader hangs on one of its cases")

    old = signal.signal(signal.SIGALRM, hung)
    signal.alarm(600)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


_CASES = Path(tempfile.mkdtemp(prefix="pliant-fuzz-"))  # one folder a process, each case overwriting
atexit.register(shutil.rmtree, _CASES, ignore_errors=True)


def _write(text: str | bytes, suffix: str) -> Path:
    p = _CASES / f"case{suffix}"
    p.write_text(text, encoding="utf-8", errors="surrogatepass") if isinstance(text, str) else p.write_bytes(
        text
    )
    return p


# --- scenes ------------------------------------------------------------------------------------
_value_lines = [i for i, ln in enumerate(BASE.splitlines()) if "=" in ln]


@st.composite
def scene_texts(draw):
    lines = BASE.splitlines()
    for _ in range(draw(st.integers(1, 3))):
        i = draw(st.sampled_from(_value_lines))
        key = lines[i].split("=", 1)[0]
        kind = draw(st.integers(0, 5))
        if kind == 0:
            lines[i] = key + "= " + draw(st.sampled_from(HOSTILE))
        elif kind == 1:
            x = draw(st.floats(allow_nan=True, allow_infinity=True))
            lines[i] = key + "= " + (repr(x) if math.isfinite(x) else str(x).replace("inf", "inf"))
        elif kind == 2:
            lines[i] = key + "= " + str(draw(st.integers(-(2**70), 2**70)))
        elif kind == 3:
            lines[i] = ""
        elif kind == 4:
            name = draw(st.text(st.characters(codec="utf-8", exclude_characters='"\\\n\r'), max_size=12))
            lines[i] = lines[i] + f'\n"{name}" = 1'
        else:
            lines.insert(
                i,
                draw(
                    st.sampled_from(
                        ["[solver]", "[[tool]]", "[[material]]", "[mesh]", "[output]", "[[load]]", "x = ["]
                    )
                ),
            )
    return "\n".join(lines) + "\n"


@BUDGET
@given(scene_texts())
def test_scene_files_load_or_fail_by_name(text):
    _loads_or_fails_by_name(load_scene, _write(text, ".toml"))


# --- NiftySim ---------------------------------------------------------------------------------
_, _, _, _, CUBE = _cube_xml()
NIFTY_HOSTILE = HOSTILE + [
    "all",
    "T4",
    "T4ANP",
    "H8",
    "NH",
    "RAMP",
    "HILLY",
    "0 0 0",
    "1 2 3 4 5",
    "-5",
    "0.5 0.5",
    "1e-300",
    "NODES",
    "UNIFORM",
    "DIFFORM",
]


def _h8_bar() -> str:
    """An H8 model: the bar of tests/test_niftysim_h8.py, two element sets, an end pressure on a
    Quad face, HGKappa."""
    from test_niftysim_h8 import _bar_xml, _end_face

    q = " ".join(str(v) for v in _end_face())
    load = (
        '<Constraint Type="Pressure" LoadShape="RAMP" NumFaces="1" FaceType="Quad">'
        f"<Faces>{q}</Faces><Magnitude>10</Magnitude></Constraint>"
    )
    sets = [(np.arange(3), "NH", "1000 20000"), (np.arange(3, 6), "LE", "3000 0.3")]
    return _bar_xml(load=load, sets=sets)[0]


H8_BAR = _h8_bar()


@st.composite
def niftysim_texts(draw, base: str = CUBE):
    root = ET.fromstring(base)
    elems = list(root.iter())
    for _ in range(draw(st.integers(1, 3))):
        el = draw(st.sampled_from(elems))
        kind = draw(st.integers(0, 3))
        token = draw(st.sampled_from(NIFTY_HOSTILE))
        if kind == 0 and el.attrib:
            el.set(draw(st.sampled_from(sorted(el.attrib))), token)
        elif kind == 1:
            el.text = token if draw(st.booleans()) else (el.text or "") + " " + token
        elif kind == 2 and el is not root:
            for parent in root.iter():
                if el in list(parent):
                    parent.remove(el)
                    break
        else:
            el.set(draw(st.sampled_from(["Type", "NumNodes", "DOF", "LoadShape", "Size"])), token)
    return ET.tostring(root, encoding="unicode")


@BUDGET
@given(niftysim_texts())
def test_niftysim_files_load_or_fail_by_name(text):
    _loads_or_fails_by_name(load_niftysim, _write(text, ".xml"))


@BUDGET
@given(niftysim_texts(H8_BAR))
def test_niftysim_h8_files_load_or_fail_by_name(text):
    """H8 models (split into tetrahedra, Quad faces, element sets mapped), mutated."""
    _loads_or_fails_by_name(load_niftysim, _write(text, ".xml"))


def _membrane_bar() -> str:
    """The H8 bar with membranes: its long faces listed as Q4 in two <ShellElementSet>s, a Linear
    one (listed) and a NeoHookean one (Size consecutive from the first)."""
    from test_niftysim_h8 import _bar_xml
    from test_niftysim_membranes import _long_faces

    Q = " ".join(str(v) for v in _long_faces().ravel())
    shells = (
        f'<ShellElements Type="Q4" NumEls="24">{Q}</ShellElements>'
        '<ShellElementSet Size="12"><Material Type="Linear">6000 0.3<Density>900</Density>'
        "<Thickness>0.0005</Thickness></Material>" + " ".join(map(str, range(12))) + "</ShellElementSet>"
        '<ShellElementSet Size="12"><Material Type="NeoHookean">500<Density>900</Density>'
        "<Thickness>0.001</Thickness></Material>12</ShellElementSet>"
    )
    return _bar_xml()[0].replace("<SystemParams>", shells + "<SystemParams>")


MEMBRANE_BAR = _membrane_bar()


@BUDGET
@given(niftysim_texts(MEMBRANE_BAR))
def test_niftysim_membrane_files_load_or_fail_by_name(text):
    """Models with membranes (<ShellElements>, <ShellElementSet>s of both materials), mutated."""
    _loads_or_fails_by_name(load_niftysim, _write(text, ".xml"))


# --- mesh files ---------------------------------------------------------------------------------
OBJ = (
    "".join(f"v {x} {y} {z}\n" for x, y, z in [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)])
    + "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"
)


@st.composite
def obj_texts(draw):
    lines = OBJ.splitlines()
    for _ in range(draw(st.integers(1, 4))):
        i = draw(st.integers(0, len(lines) - 1))
        words = lines[i].split()
        j = draw(st.integers(0, len(words) - 1))
        words[j] = draw(
            st.sampled_from(
                [
                    "nan",
                    "inf",
                    "0",
                    "-1",
                    "5",
                    "99999999999999999999",
                    "1/2/3",
                    "x",
                    "",
                    "-0",
                    "1e400",
                    "f",
                    "v",
                    "vt",
                ]
            )
        )
        lines[i] = " ".join(words)
    return "\n".join(lines) + "\n"


@BUDGET
@given(obj_texts())
def test_obj_files_read_or_fail_by_name(text):
    _surface_reads_or_fails_by_name(_write(text, ".obj"))


def _surface_reads_or_fails_by_name(p: Path) -> None:
    """read_surface(p) gives finite vertices and faces that index them, or an InputError naming p."""
    try:
        V, F = pl.mesh.read_surface(p)
    except InputError as e:
        _check_error(e, p)
        return
    assert np.all(np.isfinite(V)) and F.min() >= 0 and F.max() < len(V)


@BUDGET
@given(st.binary(max_size=400), st.sampled_from([".stl", ".ply", ".off", ".vtk", ".vtu", ".msh", ".obj"]))
def test_binary_garbage_is_refused_by_name(data, suffix):
    p = _write(data, suffix)
    for read in (pl.mesh.read_surface, pl.io.read_volume_mesh):
        try:
            read(p)
        except InputError as e:
            _check_error(e, p)


def _polydata_seeds() -> list[bytes]:
    """A binary POLYDATA file with every section (tests/test_vtk_polydata.py) and the head of
    NiftySim's ASCII box surface."""
    import struct

    from test_vtk_polydata import DATA, _binary_file

    d = _CASES
    _binary_file(
        d / "b.vtk", "float", b"FIELD FieldData 1\nlabels 1 2 int\n" + struct.pack(">2i", 7, 9) + b"\n"
    )
    return [(d / "b.vtk").read_bytes(), (DATA / "niftysim_box_surface.vtk").read_bytes()[:3000]]


_POLYDATA = _polydata_seeds()
_POLYDATA_WORDS = [b" ", b"\n", b"-1", b"99999999", b"nan", b"POLYGONS 1 4\n", b"5.1", b"METADATA\n"]


def _mutate(draw, seeds: list[bytes], words: list[bytes]) -> bytes:
    """One of ``seeds`` with up to eight edits: a byte changed, bytes deleted, one of ``words``
    inserted, the rest cut off."""
    d = bytearray(draw(st.sampled_from(seeds)))
    for _ in range(draw(st.integers(1, 8))):
        if not d:
            break
        i = draw(st.integers(0, len(d) - 1))
        op = draw(st.integers(0, 3))
        if op == 0:
            d[i] = draw(st.integers(0, 255))
        elif op == 1:
            del d[i : i + draw(st.integers(1, 50))]
        elif op == 2:
            d[i:i] = draw(st.sampled_from(words))
        else:
            d = d[:i]
    return bytes(d)


@st.composite
def polydata_bytes(draw):
    """A legacy VTK POLYDATA file, mutated (_mutate; a 60-second run of such edits found a read
    past the end of a binary array, 393,573 cases)."""
    return _mutate(draw, _POLYDATA, _POLYDATA_WORDS)


_DATA = Path(__file__).parent / "data"
_HEX_GRID = (  # two hexahedra, a wedge, a pyramid and a quadratic tet: the cells split into tets
    b"# vtk DataFile Version 4.2\nh\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 12 float\n"
    b"0 0 0 1 0 0 1 1 0 0 1 0 0 0 1 1 0 1 1 1 1 0 1 1 2 0 0 2 1 0 2 0 1 2 1 1\n"
    b"CELLS 5 44\n8 0 1 2 3 4 5 6 7\n8 1 8 9 2 5 10 11 6\n6 1 8 9 5 10 11\n5 0 1 2 3 4\n"
    b"10 0 1 3 4 1 2 3 4 5 6\nCELL_TYPES 5\n12 12 13 14 24\n"
)
_GRIDS = [
    (_DATA / "vtk93_grid_bin51.vtk").read_bytes(),
    (_DATA / "vtk93_grid_ascii42.vtk").read_bytes()[:4000],
    _HEX_GRID,
]
_GRID_WORDS = [b" ", b"\n", b"-1", b"99999999", b"nan", b"CELL_DATA 3\n", b"NORMALS n float\n", b"METADATA\n"]


@st.composite
def grid_bytes(draw):
    """A legacy VTK UNSTRUCTURED_GRID file VTK wrote (tests/test_vtk_grid.py), mutated."""
    return _mutate(draw, _GRIDS, _GRID_WORDS)


@BUDGET
@given(grid_bytes())
def test_vtk_grid_files_read_or_fail_by_name(data):
    """read_vtk_grid gives finite points and cells that index them, or an InputError naming the
    file; read_volume_mesh and read_surface (meshio, then this reader) read the file or name it."""
    from pliant.io.vtk_grid import read_vtk_grid

    p = _write(data, ".vtk")
    for read in (pl.io.read_volume_mesh, pl.mesh.read_surface):  # meshio, then this reader
        try:
            read(p)
        except InputError as e:
            _check_error(e, p)
    try:
        mesh = read_vtk_grid(p)
    except InputError as e:
        _check_error(e, p)
        return
    assert np.all(np.isfinite(mesh.points))
    for block in mesh.cells:
        for c in block.data:
            assert np.all((np.asarray(c) >= 0) & (np.asarray(c) < len(mesh.points)))


@BUDGET
@given(polydata_bytes())
def test_vtk_polydata_files_read_or_fail_by_name(data):
    _surface_reads_or_fails_by_name(_write(data, ".vtk"))


def test_fuzz_messages_quote_no_numpy_reprs():
    """The check above (no 'np.float64(' in any message) has teeth: numpy 2 prints scalars so."""
    assert re.search(r"np\.float64\(", repr(np.float64(1.0))) or np.__version__ < "2"


# --- STL, OFF and PLY text: the bulk parsers against the line-by-line readers ------------------
_CORNERS = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
_FACES = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]
_STL = (
    "solid tet\n"
    + "".join(
        "facet normal 0 0 0\n  outer loop\n"
        + "".join("    vertex {} {} {}\n".format(*_CORNERS[i]) for i in f)
        + "  endloop\nendfacet\n"
        for f in _FACES
    )
    + "endsolid tet\n"
)
_OFF = "OFF\n4 4 0\n" + "".join("{} {} {}\n".format(*c) for c in _CORNERS)
_OFF += "".join("3 {} {} {}\n".format(*f) for f in _FACES)
_PLY = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
_PLY += "element face 4\nproperty list uchar int vertex_indices\nend_header\n"
_PLY += "".join("{} {} {}\n".format(*c) for c in _CORNERS) + "".join(
    "3 {} {} {}\n".format(*f) for f in _FACES
)
_WORDS = ["nan", "inf", "-1", "0", "3", "4", "5", "2.5", "1e400", "-0", "99999999999999999999", "x", "#"]
_WORDS += ["facet", "vertex", "endfacet", "endloop", "outer", "solid", "endsolid", "OFF", "COFF", "ply"]
_WORDS += ["element", "property", "list", "uchar", "float", "end_header", "face", "vertex_indices", ""]


@st.composite
def surface_texts(draw, base: str):
    """``base`` with one to four mutations: a word replaced or put in, a line deleted, duplicated,
    moved, joined to the next or split in two, a blank line or a carriage return put in, or the
    file cut short."""
    lines = base.splitlines()
    for _ in range(draw(st.integers(1, 4))):
        i = draw(st.integers(0, len(lines) - 1))
        kind = draw(st.integers(0, 9))
        words = lines[i].split() or [""]
        if kind <= 1:
            words[draw(st.integers(0, len(words) - 1))] = draw(st.sampled_from(_WORDS))
            lines[i] = " ".join(words)
        elif kind == 7:
            words.insert(draw(st.integers(0, len(words))), draw(st.sampled_from(_WORDS)))
            lines[i] = " ".join(words)
        elif kind == 8 and i + 1 < len(lines):
            lines[i : i + 2] = [lines[i] + " " + lines[i + 1]]
        elif kind == 9:
            k = draw(st.integers(0, len(words)))
            lines[i : i + 1] = [" ".join(words[:k]), " ".join(words[k:])]
        elif kind == 2:
            del lines[i]
        elif kind == 3:
            lines.insert(i, lines[i])
        elif kind == 4:
            lines.insert(draw(st.integers(0, len(lines) - 1)), lines.pop(i))
        elif kind == 5:
            lines.insert(i, draw(st.sampled_from(["", "  ", "\r", "# note"])))
        elif kind == 6:
            lines = lines[:i] + [lines[i][: draw(st.integers(0, len(lines[i])))]]
        if not lines:
            lines = [""]
    return "\n".join(lines) + draw(st.sampled_from(["\n", "", "\r\n"]))


def _outcome(p: Path):
    """read_surface's result (vertices, faces) or the InputError's message, checked to name p."""
    try:
        V, F = pl.mesh.read_surface(p)
    except InputError as e:
        _check_error(e, p)
        return str(e)
    assert np.all(np.isfinite(V)) and F.min() >= 0 and F.max() < len(V)
    return V, F


def _bulk_agrees_with_lines(text: str, suffix: str, module, bulk: str) -> None:
    """The property: read_surface reads the file, or refuses it naming the file; and with the
    bulk parser (``module.bulk``) turned off, the line-by-line reader gives the same vertices and
    faces, or refuses it too (the bulk parser takes a file only where it reads it as the lines do)."""
    from unittest import mock

    p = _write(text, suffix)
    got = _outcome(p)
    with mock.patch.object(module, bulk, lambda *a, **k: None):
        by_lines = _outcome(p)
    if isinstance(got, str) or isinstance(by_lines, str):
        assert isinstance(got, str) and isinstance(by_lines, str), (got, by_lines)
    else:
        assert np.array_equal(got[0], by_lines[0]) and np.array_equal(got[1], by_lines[1])


@BUDGET
@given(surface_texts(_STL))
def test_stl_text_reads_as_its_lines_or_fails_by_name(text):
    from pliant.io import stl

    _bulk_agrees_with_lines(text, ".stl", stl, "_ascii_corners_in_bulk")


@BUDGET
@given(surface_texts(_OFF))
def test_off_text_reads_as_its_lines_or_fails_by_name(text):
    from pliant.io import off

    _bulk_agrees_with_lines(text, ".off", off, "_fast")


@BUDGET
@given(surface_texts(_PLY))
def test_ply_text_reads_as_its_lines_or_fails_by_name(text):
    from pliant.io import ply

    _bulk_agrees_with_lines(text, ".ply", ply, "_ascii_in_bulk")


# --- volume meshes in meshio's text formats -------------------------------------------------------
def _meshio_text(suffix: str, cells: str = "tetra", **kw) -> str:
    """Two tets, or a tet's four faces (cells="triangle"), with gmsh tags where the format keeps
    them, in the text meshio writes for suffix."""
    import meshio

    X = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1]], float)
    rows = {"tetra": [[0, 1, 2, 3], [1, 2, 3, 4]], "triangle": [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]}[
        cells
    ]
    tags = {"gmsh:physical": [np.ones(len(rows), int)], "gmsh:geometrical": [np.ones(len(rows), int)]}
    p = _CASES / f"base{suffix}"
    mesh = meshio.Mesh(X, [(cells, np.array(rows))], cell_data=tags if ".msh" in suffix else {})
    meshio.write(p, mesh, **kw)
    return p.read_text()


_MESHIO_BASES = [
    (fmt, suffix, cells, _meshio_text(suffix, cells, **kw))
    for cells in ("tetra", "triangle")
    for fmt, suffix, kw in [
        ("gmsh22", ".msh", {"file_format": "gmsh22", "binary": False}),
        ("ansys", ".msh", {"file_format": "ansys", "binary": False}),
        ("vtk", ".vtk", {"binary": False}),
        ("vtu", ".vtu", {"binary": False}),
        ("medit", ".mesh", {}),
        ("abaqus", ".inp", {}),
    ]
] + [
    # formats whose readers looped for ever at the end of a cut file (tets only: CI's budget)
    (fmt, suffix, "tetra", _meshio_text(suffix, "tetra", file_format=fmt))
    for fmt, suffix in [("mdpa", ".mdpa"), ("nastran", ".bdf"), ("tecplot", ".dat"), ("su2", ".su2")]
]


@pytest.mark.parametrize(
    "suffix, cells, base", [b[1:] for b in _MESHIO_BASES], ids=[f"{b[0]}-{b[2]}" for b in _MESHIO_BASES]
)
def test_meshio_texts_read_or_fail_by_name(suffix, cells, base):
    """The property for meshes in meshio's formats: read_volume_mesh gives nodes (N, 3) and tets
    (M, 4) that index them, read_surface finite vertices and triangles that index them; or each an
    InputError of one line naming the file (meshio's own failures included), and no hang."""

    @BUDGET
    @given(surface_texts(base))
    def reads_or_fails(text):
        p = _write(text, suffix)
        if cells == "triangle":
            _surface_reads_or_fails_by_name(p)
            return
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # coincident nodes, meshio's "only for debugging"
                X, T, _ = pl.io.read_volume_mesh(p)
        except InputError as e:
            _check_error(e, p)
            return
        assert X.shape[1:] == (3,) and T.shape[1:] == (4,) and T.min() >= 0 and T.max() < len(X)

    reads_or_fails()
