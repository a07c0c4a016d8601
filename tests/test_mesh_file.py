"""Mesh files no one here wrote (NiftySim's tetrahedral sphere, BSD; meshes gmsh wrote) read
through meshio."""

import itertools
import sys
import warnings
from pathlib import Path

import meshio
import numpy as np
import pytest
from typer.testing import CliRunner

import pliant as pl
from pliant.cli import app

DATA = Path(__file__).parent / "data"
SPHERE = DATA / "niftysim_sphere.vtk"


def _boundary_nodes(T):
    faces = np.sort(
        np.concatenate([T[:, [0, 1, 2]], T[:, [0, 1, 3]], T[:, [0, 2, 3]], T[:, [1, 2, 3]]]), axis=1
    )
    uniq, count = np.unique(faces, axis=0, return_counts=True)
    return np.unique(uniq[count == 1])


def _sphere_builder(material):
    X, T, _ = pl.io.read_volume_mesh(SPHERE)
    b = pl.ModelBuilder()
    b.add_mesh(X, pl.mesh.orient_positive(X, T), source=str(SPHERE))
    b.set_material(material, density=1000.0)
    return X, T, b


def test_sphere_file_reads_and_is_valid():
    X, T, _ = pl.io.read_volume_mesh(SPHERE)
    assert X.shape == (278, 3) and T.shape == (789, 4)  # as NiftySim's README states
    _, _, b = _sphere_builder(pl.NeoHookean(mu=100.0, K=800.0))
    model = b.finalize()
    # A tet mesh inscribed in the unit sphere: volume below 4π/3, and within 10 % of it.
    V = model.element_volumes().sum()
    assert 0.9 * 4 / 3 * np.pi < V < 4 / 3 * np.pi


def test_patch_test_on_sphere_mesh():
    """Affine displacement of the surface nodes ⇒ the same affine field inside (NH, NiftySim's
    material constants μ = 100 Pa, K = 800 Pa)."""
    X, T, b = _sphere_builder(pl.NeoHookean(mu=100.0, K=800.0))
    A = np.array([[0.08, 0.02, 0.0], [0.0, -0.05, 0.03], [0.01, 0.0, 0.06]])
    surface = _boundary_nodes(T)
    inner = np.setdiff1d(np.arange(len(X)), surface)
    b.prescribe(surface, (X @ A.T)[surface], curve=pl.Ramp(1.0))
    model = b.finalize("float64")
    sim = pl.Simulation(model)
    sim.relax(tol=1e-10)
    # Residual 1e-10 relative ⇒ displacement error far below 1e-7 of |u| ~ 0.1.
    assert np.abs(sim.displacements[inner] - (X @ A.T)[inner]).max() < 1e-7


def test_free_fall_under_gravity():
    """An unconstrained body under gravity falls rigidly: u = ½ g t² (central differences started
    at rest add ½ g t Δt, the start-up offset of u⁻ = u⁰), with no stress."""
    X, T, b = _sphere_builder(pl.NeoHookean(mu=1e4, K=8e4))
    b.set_gravity((0.0, 0.0, -9.81))
    model = b.finalize("float64")
    sim = pl.Simulation(model)
    sim.run(steps=400)
    t, dt = sim.time, sim.solver.dt
    expected = -0.5 * 9.81 * t * (t + dt)
    assert np.allclose(sim.displacements[:, 2], expected, rtol=1e-9)
    assert np.allclose(sim.displacements[:, :2], 0.0, atol=1e-12)
    assert np.abs(sim.element_results()["cauchy"]).max() < 1e-6 * 1e4


# tests/data/README.md: two 2 × 2 × 1 cm boxes side by side (x in [0, 2] and [2, 4] cm), meshed by
# gmsh 4.15.2 (PyPI wheel) with physical volumes "left" (11) and "right" (22) and a physical surface
# "fixed" (5, the x = 0 face), written as MSH 4.1 ASCII and MSH 2.2 binary. gmsh's own counts of
# each volume's tets: 70 and 70.
GMSH_BOXES = ["gmsh415_two_boxes_ascii41.msh", "gmsh415_two_boxes_binary22.msh"]


@pytest.mark.parametrize("name", GMSH_BOXES)
def test_gmsh_physical_volumes_are_element_sets_by_name(name):
    """Each named physical volume is an element set by its name (and by its tag, as before): gmsh's
    count of its tets, the box's volume 4e-6 m³ (tets fill a box exactly: 1e-12 relative for the
    sums' rounding), every centroid on its side of x = 2 cm."""
    X, T, sets = pl.io.read_volume_mesh(DATA / name)
    a, b, c, d = (X[T[:, i]] for i in range(4))
    v = np.einsum("ij,ij->i", b - a, np.cross(c - a, d - a)) / 6
    for side, tag in (("left", 11), ("right", 22)):
        np.testing.assert_array_equal(sets[side], sets[f"gmsh:physical={tag}"])
        assert len(sets[side]) == 70
        assert v[sets[side]].sum() == pytest.approx(0.02 * 0.02 * 0.01, rel=1e-12)
        x = X[T[sets[side]]].mean(axis=1)[:, 0]
        assert np.all(x < 0.02) if side == "left" else np.all(x > 0.02)
    assert "fixed" not in sets  # a surface: no element set


def test_a_scene_selects_gmsh_volumes_by_name(tmp_path):
    """Materials on region = { set = "left" } and the rest: the scene runs; an unknown name is
    refused listing the file's sets."""

    def scene(region: str) -> Path:
        p = tmp_path / "s.toml"
        p.write_text(
            f'[mesh]\nfile = "{DATA / GMSH_BOXES[0]}"\n'
            '[[material]]\ntype = "neo-hookean"\nE = 9000.0\nnu = 0.45\ndensity = 1000.0\n'
            f'region = {{ set = "{region}" }}\n'
            '[[material]]\ntype = "neo-hookean"\nE = 3000.0\nnu = 0.45\ndensity = 1000.0\n'
            '[solver]\nduration = 0.002\n[[constraint]]\ntype = "fix"\n'
            'nodes = { plane = { point = [0.0, 0.0, 0.0], normal = [1.0, 0.0, 0.0], side = "below" } }\n'
        )
        return p

    run = CliRunner().invoke(app, ["run", str(scene("left")), "-o", str(tmp_path / "out")])
    assert run.exit_code == 0, run.output
    bad = CliRunner().invoke(app, ["run", str(scene("middle")), "-o", str(tmp_path / "out2")])
    assert bad.exit_code == 2 and "unknown element set 'middle'" in bad.output and "left" in bad.output


@pytest.mark.parametrize("name", GMSH_BOXES)
def test_gmsh_physical_surfaces_are_node_sets(name):
    """The physical surface "fixed" (the x = 0 face) is a node set, by name and by tag: every node
    of the mesh on that face, none off it."""
    X, _, _, nodes = pl.io.read_volume_mesh_sets(DATA / name)
    np.testing.assert_array_equal(nodes["fixed"], nodes["gmsh:physical=5"])
    np.testing.assert_array_equal(nodes["fixed"], np.nonzero(X[:, 0] == 0.0)[0])


def test_a_scene_fixes_a_gmsh_surface_by_name(tmp_path):
    """nodes = { set = "fixed" } fixes what the plane x = 0 fixes: the same displacements, bit for
    bit, after 400 steps under gravity; an unknown node set is refused listing the file's."""

    def run(nodes: str, out: str):
        return _sag(tmp_path, DATA / GMSH_BOXES[1], nodes, out)

    by_set, a = run('{ set = "fixed" }', "a")
    by_plane, b = run("{ plane = { point = [0.0, 0.0, 0.0], normal = [1.0, 0.0, 0.0] } }", "b")
    assert by_set.exit_code == 0 and by_plane.exit_code == 0, by_set.output + by_plane.output
    ua = meshio_last_displacement(a)
    assert np.abs(ua).max() > 0 and np.array_equal(ua, meshio_last_displacement(b))
    bad, _ = run('{ set = "free" }', "c")
    assert bad.exit_code == 2 and "unknown node set 'free'" in bad.output and "fixed" in bad.output


def _sag(tmp_path: Path, mesh: Path, nodes: str, out: str, material: str = ""):
    """`pliant run` of the mesh file under gravity for 4 ms (float64), the nodes ``nodes`` fixed:
    the CLI's result and the output folder."""
    p = tmp_path / f"{out}.toml"
    p.write_text(
        f'[mesh]\nfile = "{mesh}"\n'
        '[[material]]\ntype = "neo-hookean"\nE = 3000.0\nnu = 0.45\ndensity = 1000.0\n'
        + material
        + '[solver]\nduration = 0.004\ndt = 1e-5\ndtype = "float64"\n'
        f'[[constraint]]\ntype = "fix"\nnodes = {nodes}\n[[load]]\ntype = "gravity"\n'
    )
    return CliRunner().invoke(app, ["run", str(p), "-o", str(tmp_path / out)]), tmp_path / out


def meshio_last_displacement(out: Path) -> np.ndarray:
    import meshio

    last = sorted(out.glob("*.vtu"))[-1]
    return np.asarray(meshio.read(last).point_data["displacement"])


def test_abaqus_element_and_node_sets():
    """The same boxes written by gmsh as an Abaqus .inp (ELSETs and NSETs of its physical groups,
    Mesh.SaveGroupsOfElements/Nodes): the ELSETs "left" and "right" are element sets (70 tets, the
    box's volume each, 1e-12 relative as above), the NSET "fixed" is the nodes on x = 0."""
    X, T, sets, nodes = pl.io.read_volume_mesh_sets(DATA / "gmsh415_two_boxes.inp")
    a, b, c, d = (X[T[:, i]] for i in range(4))
    v = np.einsum("ij,ij->i", b - a, np.cross(c - a, d - a)) / 6
    for side in ("left", "right"):
        assert len(sets[side]) == 70
        assert v[sets[side]].sum() == pytest.approx(0.02 * 0.02 * 0.01, rel=1e-12)
    assert np.all(X[T[sets["left"]]].mean(axis=1)[:, 0] < 0.02)
    np.testing.assert_array_equal(nodes["fixed"], np.nonzero(X[:, 0] == 0.0)[0])


def test_abaqus_c3d8_hexahedra_with_their_sets(tmp_path):
    """gmsh's Abaqus .inp of a transfinite 0.04 × 0.01 × 0.01 box of 8 C3D8 (2 × 2 × 2) (ELSET
    "block", NSET "fixed" on x = 0): the hexahedra become 48 tets filling the box (1e-12 relative),
    "block" holds them all, "fixed" is the nodes on x = 0; a scene fixing the set runs to the same
    bits as one fixing the plane x = 0."""
    m = pl.io.read_volume_mesh_file(DATA / "gmsh415_hex_box.inp")
    assert m.split == {"hexahedron": 8} and m.tets.shape == (48, 4)
    v = pl.mesh.primitives.tet_volumes(m.nodes, m.tets)
    assert v.min() > 0 and v[m.element_sets["block"]].sum() == pytest.approx(0.04 * 0.01 * 0.01, rel=1e-12)
    np.testing.assert_array_equal(m.node_sets["fixed"], np.nonzero(m.nodes[:, 0] == 0.0)[0])

    def run(nodes: str, out: str):
        result, folder = _sag(
            tmp_path, DATA / "gmsh415_hex_box.inp", nodes, out, 'region = { set = "block" }\n'
        )
        assert result.exit_code == 0, result.output
        return meshio_last_displacement(folder)

    ua = run('{ set = "fixed" }', "a")
    assert np.abs(ua).max() > 0
    assert np.array_equal(ua, run("{ plane = { point = [0.0, 0.0, 0.0], normal = [1.0, 0.0, 0.0] } }", "b"))


def test_nodes_written_once_per_element_corner_are_warned_of(tmp_path):
    """NiftySim's sphere written with one node per element corner (as some exporters write volume
    meshes): its 789 tets no longer share nodes and each would move on its own. The reader warns,
    counting the 4 × 789 − 278 nodes that repeat a position and naming the first pair (the first
    corner whose original node came before); the file as NiftySim wrote it draws no warning."""
    X, T, _ = pl.io.read_volume_mesh(SPHERE)
    soup = tmp_path / "soup.vtu"
    meshio.write(soup, meshio.Mesh(X[T].reshape(-1, 3), [("tetra", np.arange(T.size).reshape(-1, 4))]))
    seen: dict[int, int] = {}
    first = None
    for j, node in enumerate(T.ravel().tolist()):
        if node in seen and first is None:
            first = (seen[node], j)
        seen.setdefault(node, j)
    with pytest.warns(pl.PliantWarning) as record:
        pl.io.read_volume_mesh(soup)
    (message,) = [str(w.message) for w in record]
    assert f"{4 * 789 - 278} node(s) lie exactly where another node lies" in message
    assert f"first: nodes {first[0]} and {first[1]}" in message and str(soup) in message
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        pl.io.read_volume_mesh(SPHERE)


def _shortest_edge(X, T):
    """The shortest of the tetrahedra's edges [m], every pair of corners measured."""
    return min(
        np.linalg.norm(X[T[:, a]] - X[T[:, b]], axis=1).min() for a, b in itertools.combinations(range(4), 2)
    )


def test_nodes_all_but_at_another_are_warned_of_and_nodes_a_gap_apart_are_not(tmp_path):
    """The sphere written one node per element corner, each corner's position moved by up to 1e-7
    of the sphere's size (a writer that computes each element's corners on its own and rounds
    them): the reader warns of the 4 × 789 − 278 repeated nodes, all but coincident. Two copies of
    the sphere a hundredth of its shortest edge apart (bodies meant to be separate, closer than any
    element) draw no warning: the fraction, a thousandth, lies between."""
    from pliant.mesh.topology import CLOSE_FRACTION

    X, T, _ = pl.io.read_volume_mesh(SPHERE)
    rng = np.random.default_rng(5)
    corners = X[T].reshape(-1, 3)
    corners += rng.uniform(-1e-7, 1e-7, corners.shape) * np.ptp(X, axis=0).max()
    soup = tmp_path / "soup.vtu"
    meshio.write(soup, meshio.Mesh(corners, [("tetra", np.arange(T.size).reshape(-1, 4))]))
    with pytest.warns(pl.PliantWarning) as record:
        pl.io.read_volume_mesh(soup)
    (message,) = [str(w.message) for w in record]
    assert f"{4 * 789 - 278} node(s) lie where another node lies or closer to it than 0.1% of" in message
    shortest = _shortest_edge(X, T)
    # Two copies, the second moved by 10 × the fraction of the shortest edge: each node of the
    # second lies that far from its twin.
    apart = tmp_path / "apart.vtu"
    two = np.concatenate([X, X + [10 * CLOSE_FRACTION * shortest, 0, 0]])
    meshio.write(apart, meshio.Mesh(two, [("tetra", np.concatenate([T, T + len(X)]))]))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        pl.io.read_volume_mesh(apart)


def test_coincident_nodes_are_the_pairs_a_brute_force_search_finds():
    """Random jittered boxes with nodes planted near others (some at, some just inside and some
    just outside the fraction of the shortest edge) against every pair's distance computed
    directly: the same count, first pair and largest distance."""
    from pliant.mesh.topology import CLOSE_FRACTION, coincident_nodes

    for seed in range(8):
        rng = np.random.default_rng(seed)
        X, T = pl.mesh.box_tets((0.1, 0.05, 0.02), (6, 4, 3), jitter=0.25, seed=seed)
        tol = CLOSE_FRACTION * _shortest_edge(X, T)
        k = int(rng.integers(0, 6))
        twins = rng.choice(len(X), k, replace=False)
        gap = tol * rng.choice([0.0, 0.5, 0.999, 1.001, 3.0], k)
        direction = rng.normal(size=(k, 3))
        extra = X[twins] + gap[:, None] * direction / np.linalg.norm(direction, axis=1)[:, None]
        Y = np.concatenate([X, extra])
        # Each planted node becomes the corner of a copy of a tet of its twin.
        owner = np.array([np.nonzero((T == t).any(axis=1))[0][0] for t in twins], dtype=np.int64)
        U = np.concatenate(
            [T, np.where(T[owner] == twins[:, None], len(X) + np.arange(k)[:, None], T[owner])]
        )
        d = np.linalg.norm(Y[:, None] - Y[None], axis=2)
        i, j = np.nonzero(np.triu(d <= CLOSE_FRACTION * _shortest_edge(Y, U), 1))
        got = coincident_nodes(Y, U)
        if not len(i):
            assert got == (0, -1, -1, 0.0)
            continue
        first = np.lexsort((i, j))[0]
        assert got[:3] == (np.unique(j).size, i[first], j[first])
        assert got[3] == pytest.approx(d[i, j].max(), rel=1e-12)


_INP_NODES = "*NODE\n1, 0, 0, 0\n2, 1, 0, 0\n3, 0, 1, 0\n4, 0, 0, 1\n"
_VTK_NO_POINTS = (
    "# vtk DataFile Version 5.1\nno points\nASCII\nDATASET UNSTRUCTURED_GRID\nCELLS 2 4\n"
    "OFFSETS vtktypeint64\n0\n4\nCONNECTIVITY vtktypeint64\n0\n1\n2\n3\nCELL_TYPES 1\n10\n"
)
_GMSH41_CUT = (
    "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 4 1 4\n3 0 0 4\n1\n2\n3\n4\n0 0 0\n1 0 0\n0 1 0\n"
    "0 0 1\n$EndNodes\n$Elements\n1 1 1 1\n3 1 4 1\n1 1 2\n"
)
_TECPLOT_HUGE = (  # meshio's Tecplot reader keeps node numbers as Python ints, of any size
    'VARIABLES = "X", "Y", "Z"\nZONE NODES = 4, ELEMENTS = 1,\n'
    "DATAPACKING = BLOCK, ZONETYPE = FETETRAHEDRON\n"
    "0.0 1.0 0.0 0.0\n0.0 0.0 1.0 0.0\n0.0 0.0 0.0 1.0\n99999999999999999999 2 3 4\n"
)


@pytest.mark.parametrize(
    "name, text, says",
    [
        ("empty.inp", _INP_NODES + "*ELEMENT, TYPE=C3D4\n", "its tetra blocks hold no cells"),
        (
            "nameless.inp",
            _INP_NODES + "*ELEMENT\n1, 1, 2, 3, 4\n",
            "(RuntimeError: TYPE not found in *ELEMENT)",
        ),
        ("cut.msh", _GMSH41_CUT, "a block of tetra cells holds 2 node numbers in rows of 2; expected 4"),
        ("nopoints.vtk", _VTK_NO_POINTS, "no points; expected (N, 3) node coordinates"),
        ("huge.dat", _TECPLOT_HUGE, "tetra node numbers unreadable (Python int too large"),
        (
            "beyond.inp",
            _INP_NODES.replace("2, 1, 0, 0", "2, 1e+900, 0, 0") + "*ELEMENT, TYPE=C3D4\n1, 1, 2, 3, 4\n",
            "node 1 has a non-finite coordinate [inf, 0.0, 0.0]; expected finite",
        ),
    ],
    ids=[
        "abaqus-empty-element-block",
        "abaqus-element-without-type",
        "gmsh41-cut-in-a-cell",
        "vtk-no-points",
        "tecplot-index-beyond-64-bits",
        "abaqus-coordinate-beyond-float64",
    ],
)
def test_malformed_volume_mesh_files_are_refused_on_one_line(tmp_path, name, text, says):
    """Found by fuzzing meshio's formats (mutated word by word and line by line): these ended in
    numpy's AxisError, ValueError ("cannot reshape array of size 2 into shape (4)"), IndexError and
    OverflowError, or in a message of three lines (meshio's own, holding newlines); a coordinate
    beyond float64's range was read as infinite and returned (found by changing single bytes)."""
    p = tmp_path / name
    p.write_text(text)
    with pytest.raises(pl.errors.MeshError) as e:
        pl.io.read_volume_mesh(p)
    assert says in str(e.value) and str(p) in str(e.value) and "\n" not in str(e.value)


@pytest.mark.parametrize(
    "cut",
    [-3, -12, 40, "points"],
    ids=["in-a-cell-section", "in-a-header", "a-bracket-short", "before-points"],
)
def test_a_truncated_ansys_msh_is_refused_and_does_not_hang(tmp_path, cut: int | str):
    """meshio's ANSYS / Fluent reader (a .msh that is not gmsh's) skips to a closing bracket one
    character at a time and, once the file has ended, kept reading for ever. A truncated file, or
    one with a bracket short, is now refused. The reading runs on a thread given 60 s, so that a
    hang fails this test instead of stalling the suite."""
    whole = meshio.Mesh(
        np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float), [("tetra", np.array([[0, 1, 2, 3]]))]
    )
    p = tmp_path / "fluent.msh"
    meshio.write(p, whole, file_format="ansys", binary=False)
    text = p.read_text()
    if cut == "points":  # the points section's first line, then nothing
        text = text[: text.index("\n", text.index("(10 (1")) + 1]
    else:
        text = text[:cut] if cut < 0 else text.replace(")", "", 1)
    p.write_text(text)
    _refused_in_time(p)


def _refused_in_time(p: Path) -> None:
    """read_volume_mesh(p) raises a MeshError naming p. It runs on a thread given 60 s (a read of
    these few hundred bytes takes milliseconds), so that a reader that loops for ever fails the
    test instead of stalling the suite."""
    import threading

    got: list[BaseException | None] = []

    def read():
        try:
            pl.io.read_volume_mesh(p)
            got.append(None)
        except BaseException as e:  # noqa: BLE001 (handed to the test's thread)
            got.append(e)

    t = threading.Thread(target=read, daemon=True)
    t.start()
    t.join(60)
    assert got, "read_volume_mesh did not return in 60 s"
    assert isinstance(got[0], pl.errors.MeshError) and str(p) in str(got[0]), got[0]


_TWO_TETS = meshio.Mesh(
    np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1]], float),
    [("tetra", np.array([[0, 1, 2, 3], [1, 2, 3, 4]]))],
)


@pytest.mark.parametrize(
    "fmt, suffix, after",
    [
        ("mdpa", ".mdpa", "Begin Nodes"),
        ("nastran", ".bdf", "BEGIN BULK"),
        ("tecplot", ".dat", "FETETRAHEDRON\n0"),
        ("ply", ".ply", "ply\n"),
    ],
)
def test_a_file_cut_short_in_a_format_whose_reader_loops_is_refused(tmp_path, fmt, suffix, after):
    """meshio's Kratos, Nastran and Tecplot readers skip lines until a keyword, and its PLY
    reader skips blank lines, for ever once the file has ended: a file that meshio itself wrote,
    cut short (found by cutting each format's file at every byte; each cut here hangs
    meshio.read), hung read_volume_mesh. Each is now refused by name."""
    p = tmp_path / f"cut{suffix}"
    meshio.write(p, _TWO_TETS, file_format=fmt, **({"binary": False} if fmt == "ply" else {}))
    text = p.read_text()
    p.write_text(text[: text.index(after) + len(after)])
    _refused_in_time(p)


@pytest.mark.parametrize("empty", [".node", ".ele"])
@pytest.mark.parametrize("which", [".node", ".ele"])
def test_a_tetgen_file_without_its_header_line_is_refused(tmp_path, empty, which):
    """meshio's TetGen reader skips blank and comment lines for ever when a .node or .ele file
    holds no header line (an empty file, or comments only): either file read by either name."""
    meshio.write(tmp_path / "m.node", _TWO_TETS, file_format="tetgen")
    (tmp_path / f"m{empty}").write_text("# only a comment\n\n")
    _refused_in_time(tmp_path / f"m{which}")


# Every format meshio writes that read_volume_mesh reads (suffix, meshio's writer keywords), in
# ASCII and binary where both exist; the TetGen pair is cut in its .node file.
_WRITTEN = [
    (".inp", {}),
    (".msh", {"file_format": "ansys", "binary": False}),
    (".msh", {"file_format": "ansys", "binary": True}),
    (".avs", {}),
    (".f3grid", {"binary": False}),
    (".f3grid", {"binary": True}),
    (".msh", {"file_format": "gmsh22", "binary": False}),
    (".msh", {"file_format": "gmsh22", "binary": True}),
    (".msh", {"file_format": "gmsh", "binary": False}),
    (".msh", {"file_format": "gmsh", "binary": True}),
    (".mdpa", {}),
    (".mesh", {}),
    (".meshb", {}),
    (".bdf", {}),
    (".vol", {}),
    (".post", {}),
    (".su2", {}),
    (".dat", {}),
    (".vtk", {"binary": False}),
    (".vtk", {"binary": True}),
    (".vtu", {"binary": False}),
    (".vtu", {"binary": True}),
    (".xml", {}),
    (".node", {}),
]


@pytest.mark.parametrize(
    "suffix, kw",
    _WRITTEN,
    ids=[f"{kw.get('file_format', s[1:])}{'-binary' * kw.get('binary', 0)}" for s, kw in _WRITTEN],
)
def test_every_cut_of_a_written_file_reads_or_is_refused_by_name(tmp_path, suffix, kw):
    """Two tets written by meshio, cut at every byte: each cut file reads as nodes (N, 3) and tets
    that index them, or is refused by a one-line InputError naming it; never another exception,
    and never a hang (the cuts run on a thread given 120 s, about 50 times what they take). This
    is how the hanging readers above were found."""
    import threading

    p = tmp_path / f"two{suffix}"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # meshio's "only for debugging", "legacy format"
        meshio.write(p, _TWO_TETS, **kw)
    whole = p.read_bytes()
    wrong: list[str] = []
    done: list[int] = []

    def cuts():
        for cut in range(len(whole)):
            p.write_bytes(whole[:cut])
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")  # coincident nodes and the like
                    X, T, _ = pl.io.read_volume_mesh(p)
                if not (X.shape[1:] == (3,) and T.shape[1:] == (4,) and (len(T) == 0 or T.max() < len(X))):
                    wrong.append(f"cut {cut}: nodes {X.shape}, tets {T.shape}")
            except pl.errors.InputError as e:
                if str(p) not in str(e) or "\n" in str(e):
                    wrong.append(f"cut {cut}: {e}")
            except Exception as e:  # noqa: BLE001 (reported below)
                wrong.append(f"cut {cut}: {type(e).__name__}: {e}")
            done.append(cut)

    t = threading.Thread(target=cuts, daemon=True)
    t.start()
    t.join(120)
    assert len(done) == len(whole), f"the read of cut {len(done)} did not return"
    assert not wrong, wrong[:5]


@pytest.mark.skipif(
    sys.platform != "linux", reason="the bound is Linux's RLIMIT_DATA; elsewhere reads are unbounded"
)
def test_a_count_beyond_what_a_file_holds_is_refused_not_allocated(tmp_path):
    """meshio allocates arrays by the counts a file states. A gmsh 4.1 binary file of 300 bytes
    whose node count reads a billion asked for 24 GB, which Linux grants lazily and then answers
    by killing the process when it is touched (this is how a byte-changing fuzz run ended, in the
    kernel's out-of-memory kill). The read is now bounded (2 GiB beyond what the process held,
    more for large files): the file is refused by name, and the process's own bound is restored."""
    import resource

    p = tmp_path / "billion.msh"
    meshio.write(p, _TWO_TETS, file_format="gmsh", binary=True)
    data = bytearray(p.read_bytes())
    at = data.index(b"$Nodes\n") + 7 + 8  # the header's 4 size_t: blocks, nodes, min and max tag
    assert np.frombuffer(data[at : at + 8], np.uint64)[0] == 5
    data[at : at + 8] = np.uint64(10**9).tobytes()
    p.write_bytes(bytes(data))
    before = resource.getrlimit(resource.RLIMIT_DATA)
    with pytest.raises(
        pl.errors.MeshError, match=r"billion.msh: cannot read .*MemoryError.*a count in the file"
    ):
        pl.io.read_volume_mesh(p)
    assert resource.getrlimit(resource.RLIMIT_DATA) == before


@pytest.mark.skipif(sys.platform != "linux", reason="the bound is Linux's RLIMIT_DATA")
def test_the_read_bound_refuses_only_inside_and_scales_with_the_file():
    """Inside the bound an allocation of 3 GiB (untouched: Linux grants it lazily) fails, as
    2 GiB is the bound for a small file; after it the same allocation succeeds; a 100 MB file is
    given 64 bytes a byte (6.4 GB)."""
    from pliant.io.files import _bounded_memory, _read_memory

    with _bounded_memory(1000), pytest.raises(MemoryError):
        np.empty(3 << 30, np.uint8)
    assert np.empty(3 << 30, np.uint8).nbytes == 3 << 30
    assert _read_memory(1000) == 2 << 30 and _read_memory(100_000_000) == 6_400_000_000
