"""Linear hexahedra, wedges and pyramids split into tetrahedra (pliant.mesh.split) and read from
mesh files (pliant.io.read_volume_mesh_file).

References: a file gmsh 4.15.2 wrote with all four cell kinds (its counts, and the volumes its
MeshVolume plugin gave: tests/data/README.md); the volumes of unit cells in closed form; the
patch test (u = A X gives zero force at every interior node and the closed-form stress in every
element only if the tetrahedra of neighbouring cells meet on whole faces); the boundary of a
box."""

from __future__ import annotations

import itertools
import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

import pliant as pl
from pliant.cli import app
from pliant.errors import MeshError
from pliant.io import read_volume_mesh_file
from pliant.mesh.primitives import tet_volumes
from pliant.mesh.split import split_cells
from pliant.mesh.topology import boundary_faces

HYBRID = Path(__file__).parent / "data" / "gmsh415_hybrid_ascii41.msh"
TETRA10 = Path(__file__).parent / "data" / "gmsh415_box_tetra10_ascii22.msh"
HEX20 = Path(__file__).parent / "data" / "gmsh415_box_hex20_ascii41.msh"
runner = CliRunner()

UNIT = {
    "hexahedron": (
        np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1.0]]),
        1.0,
    ),
    "wedge": (np.array([[0, 0, 0], [0, 1, 0], [1, 0, 0], [0, 0, 1], [0, 1, 1], [1, 0, 1.0]]), 0.5),
    "pyramid": (np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0.5, 0.5, 1.0]]), 1 / 3),
}
MIRRORED = {"hexahedron": [4, 5, 6, 7, 0, 1, 2, 3], "wedge": [0, 2, 1, 3, 5, 4], "pyramid": [0, 3, 2, 1, 4]}


@pytest.mark.parametrize("kind", sorted(UNIT))
def test_a_cell_numbered_any_way_is_filled_by_positive_tetrahedra(kind):
    """Every numbering of a unit cell's nodes (each local corner given each global index), in VTK's
    orientation and mirrored: 6, 3 or 2 positive tetrahedra whose volumes sum to the cell's (closed
    form; 1e-12 is round-off)."""
    X, volume = UNIT[kind]
    n = len(X)
    perms = np.array(list(itertools.permutations(range(n))))
    # Numbering k gets its own copy of the nodes, global node j of copy k at X[perms[k, j]]: local
    # corner i is global node cells[k, i], at X[i]. The offset n k keeps the order of the indices
    # within a cell (all the split reads of them), so one call splits every numbering.
    nodes = X[perms].reshape(-1, 3)
    cells = np.argsort(perms, axis=1) + n * np.arange(len(perms))[:, None]
    cells = np.concatenate([cells, cells[:, MIRRORED[kind]]])
    T, owner = split_cells(nodes, kind, cells)
    v = tet_volumes(nodes, T)
    assert np.all(np.bincount(owner, minlength=len(cells)) == {8: 6, 6: 3, 5: 2}[n])
    assert v.min() > 0
    np.testing.assert_allclose(np.bincount(owner, weights=v), volume, rtol=0, atol=1e-12)


def test_a_wedge_written_as_a_hexahedron_with_repeated_nodes_is_the_wedge():
    """Nodes 0 1 2 2 3 4 5 5 (a wedge some writers store as a hexahedron): the flat tetrahedra go,
    the rest fill the wedge (volume 1/2), for every numbering."""
    X, volume = UNIT["wedge"]
    for perm in itertools.permutations(range(6)):
        p = np.array(perm)
        cell = np.argsort(p)[[0, 1, 2, 2, 3, 4, 5, 5]]
        T, _ = split_cells(X[p], "hexahedron", cell[None, :])
        assert tet_volumes(X[p], T).min() > 0
        assert tet_volumes(X[p], T).sum() == pytest.approx(volume, abs=1e-12)


def test_hexahedra_numbered_at_random_meet_on_whole_faces():
    """A 4 × 4 × 4 grid of hexahedra, its interior nodes jittered by up to 8 % of a cell, its nodes
    numbered at random and half of its cells mirrored: the tetrahedra's boundary is the box's 96
    quads as 192 triangles
    (a quad cut one way from one cell and the other way from its neighbour would add 4 triangles
    inside), and they fill the box (volume 1 to round-off)."""
    rng = np.random.default_rng(7)
    n = 4
    g = np.stack(np.meshgrid(*(np.linspace(0, 1, n + 1),) * 3, indexing="ij"), -1).reshape(-1, 3)
    inner = np.all((g > 0) & (g < 1), axis=1)
    idx = np.arange(len(g)).reshape((n + 1,) * 3)
    corners = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]
    H = np.array(
        [
            [idx[i + a, j + b, k + c] for a, b, c in corners]
            for i, j, k in itertools.product(range(n), repeat=3)
        ]
    )
    for _ in range(10):
        perm = rng.permutation(len(g))
        X = g[perm] + np.where(inner[perm, None], rng.uniform(-0.02, 0.02, g.shape), 0.0)
        C = np.argsort(perm)[H]
        flip = rng.random(len(C)) < 0.5
        C[flip] = C[flip][:, MIRRORED["hexahedron"]]
        T, owner = split_cells(X, "hexahedron", C)
        assert len(T) == 6 * len(H) and np.array_equal(owner, np.repeat(np.arange(len(H)), 6))
        assert tet_volumes(X, T).min() > 0
        assert tet_volumes(X, T).sum() == pytest.approx(1.0, abs=1e-12)
        assert len(boundary_faces(T)[0]) == 2 * 6 * n * n


def test_gmsh_hybrid_mesh_of_every_cell_kind():
    """gmsh's file: 144 hexahedra, 24 pyramids, 146 wedges and 528 tets become 528 + 6·144 + 2·24 +
    3·146 = 1,878 tets; each physical group (an element set by name) holds 4.0e-6 m³ as gmsh's
    MeshVolume says (1e-12 relative: round-off), and every boundary triangle lies on the L-shaped
    body's outer faces, whose area is 3.6e-3 m² (closed form): the cells' tetrahedra meet each
    other, and gmsh's own tets, on whole faces."""
    m = read_volume_mesh_file(HYBRID)
    assert m.split == {"hexahedron": 144, "pyramid": 24, "wedge": 146}
    assert m.tets.shape == (1878, 4)
    v = tet_volumes(m.nodes, m.tets)
    assert v.min() > 0
    for name in ("hexes", "tets", "wedges"):
        assert v[m.element_sets[name]].sum() == pytest.approx(4.0e-6, rel=1e-12)
    assert sum(s.size for k, s in m.element_sets.items() if not k.startswith("gmsh:")) == len(m.tets)
    B = boundary_faces(m.tets)[0]
    P = m.nodes[B]
    c = P.mean(axis=1)
    near = lambda a, b: np.abs(a - b) < 1e-12  # noqa: E731
    outer = near(c[:, 0], 0) | near(c[:, 0], 0.04) | near(c[:, 1], 0) | near(c[:, 1], 0.02) | near(c[:, 2], 0)
    outer |= near(c[:, 2], 0.02) & (c[:, 0] > 0.02) | near(c[:, 2], 0.01) & (c[:, 0] < 0.02)
    outer |= near(c[:, 0], 0.02) & (c[:, 2] > 0.01)
    assert outer.all()
    area = 0.5 * np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), axis=1).sum()
    # bottom, the two tops, the sides y = 0 and y = 0.02, x = 0, x = 0.04, the step at x = 0.02
    faces = [0.04 * 0.02, 0.02 * 0.02, 0.02 * 0.02, 2 * (0.04 * 0.01 + 0.02 * 0.01), 0.02 * 0.01, 0.02 * 0.02]
    assert area == pytest.approx(sum(faces) + 0.02 * 0.01, rel=1e-12)


def _cauchy_neo_hookean(F, mu, K):
    """σ = μ J^(−5/3) dev(F Fᵀ) + K (J − 1) I of the decoupled Neo-Hookean, Voigt order."""
    J = np.linalg.det(F)
    b = F @ F.T
    sig = mu * J ** (-5 / 3) * (b - np.trace(b) / 3 * np.eye(3)) + K * (J - 1) * np.eye(3)
    return sig[[0, 1, 2, 0, 1, 0], [0, 1, 2, 1, 2, 2]]


def _shuffled(tmp_path: Path, seed: int) -> Path:
    """gmsh's hybrid mesh with its nodes numbered at random, as a .vtu."""
    import meshio

    mesh = meshio.read(HYBRID)
    perm = np.random.default_rng(seed).permutation(len(mesh.points))
    new = np.argsort(perm)  # old node i is new node new[i]
    cells = [(c.type, new[c.data]) for c in mesh.cells if c.data.ndim == 2 and c.data.shape[1] >= 4]
    path = tmp_path / f"shuffled{seed}.vtu"
    meshio.write(path, meshio.Mesh(mesh.points[perm], cells))
    return path


def test_a_quadratic_tet_is_its_eight_linear_ones():
    """A tetra10 of a skew tet, its corners numbered every way (the mid-edge nodes following
    them), which makes each of the octahedron's three diagonals the shortest in turn: 8 positive
    tets through all 10 nodes whose volumes sum to the parent's (closed form; 1e-15 is round-off),
    each a linear tet of an eighth of it (red refinement: all 8 have the same volume)."""
    from pliant.mesh.split import refine_tetra10

    P = np.array([[0, 0, 0], [1.0, 0.1, 0], [0.3, 1.2, 0], [0.2, 0.3, 0.9]])
    volume = abs(np.linalg.det(P[1:] - P[0])) / 6
    edges = [(0, 1), (1, 2), (0, 2), (0, 3), (1, 3), (2, 3)]
    used = set()
    for perm in itertools.permutations(range(4)):
        Q = P[list(perm)]
        X = np.vstack([Q] + [(Q[a] + Q[b]) / 2 for a, b in edges])
        T, owner = refine_tetra10(X, np.arange(10)[None, :])
        v = tet_volumes(X, T)
        assert len(T) == 8 and set(T.ravel()) == set(range(10)) and np.all(owner == 0)
        np.testing.assert_allclose(v, volume / 8, rtol=1e-12)
        inner = {tuple(sorted(t)) for t in T[4:].tolist()}
        used.add(frozenset.intersection(*(frozenset(t) for t in inner)))  # the diagonal all 4 share
    assert len(used) == 3


def test_gmsh_quadratic_tets_become_eight_linear_tets_each():
    """gmsh's order-2 mesh of a 0.03 × 0.02 × 0.01 box (88 tetra10, 205 nodes): 704 tets using
    every node, filling the box (6.0e-6 m³ as gmsh's MeshVolume, 1e-12 relative), whose boundary
    is the box's surface (area 2.2e-3 m², closed form: the faces of neighbouring cells meet)."""
    m = read_volume_mesh_file(TETRA10)
    assert m.split == {"tetra10": 88} and m.tets.shape == (704, 4)
    assert np.unique(m.tets).size == len(m.nodes) == 205
    v = tet_volumes(m.nodes, m.tets)
    assert v.min() > 0 and v.sum() == pytest.approx(6.0e-6, rel=1e-12)
    assert v[m.element_sets["body"]].sum() == pytest.approx(6.0e-6, rel=1e-12)
    P = m.nodes[boundary_faces(m.tets)[0]]
    area = 0.5 * np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), axis=1).sum()
    assert area == pytest.approx(2 * (0.03 * 0.02 + 0.03 * 0.01 + 0.02 * 0.01), rel=1e-12)


@pytest.mark.parametrize("anp", [False, True])
@pytest.mark.parametrize("numbering", ["gmsh", "random", "tetra10"])
def test_patch_test_on_the_gmsh_hybrid_mesh(backend, anp, numbering, tmp_path):
    """u = A X on gmsh's hybrid mesh, with its own node numbering and with one drawn at random, and
    on gmsh's quadratic tets:
    the internal force vanishes at every node off the boundary and every element carries the
    closed-form stress of F = I + A (a quad cut one way from one cell and the other way from its
    neighbour leaves a force at its nodes). Tolerances: round-off of sums of O(100) terms of size
    σ·h² in float64 (1e-10 relative)."""
    path = {"gmsh": HYBRID, "tetra10": TETRA10}.get(numbering) or _shuffled(tmp_path, 3)
    m = read_volume_mesh_file(path)
    material = pl.NeoHookean(E=3000.0, nu=0.45)
    b = pl.ModelBuilder()
    b.add_mesh(m.nodes, m.tets)
    b.set_material(material, density=1000.0)
    b.nodal_pressure = anp
    model = b.finalize("float64", backend=backend)
    A = np.array([[0.02, 0.01, -0.005], [0.003, -0.01, 0.012], [-0.008, 0.004, 0.015]])
    s = model.state()
    s.set_displacements(m.nodes @ A.T)
    f = model.internal_forces(s)
    on_boundary = np.zeros(len(m.nodes), bool)
    on_boundary[boundary_faces(m.tets)[0]] = True
    expected = _cauchy_neo_hookean(np.eye(3) + A, material.mu, material.K)
    scale = np.abs(expected).max() * 0.004**2  # σ times a cell face [N]
    assert (~on_boundary).sum() > 50
    assert np.abs(f[~on_boundary]).max() < 1e-10 * scale
    assert np.abs(model.element_results(s)["cauchy"] - expected).max() < 1e-10 * np.abs(expected).max()


def test_a_twisted_hexahedron_is_named(tmp_path):
    """A hexahedron whose top face is turned by 120° about its axis cannot be split into
    tetrahedra of one orientation: MeshError naming the cell; `pliant mesh quality` exits 2 with it,
    no traceback; without it, the JSON report counts the 2 hexahedra split into 12 tets."""
    import meshio

    X, _ = UNIT["hexahedron"]
    X = X.copy()
    a = np.radians(120)
    R = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    X[4:, :2] = (X[4:, :2] - 0.5) @ R.T + 0.5
    good = UNIT["hexahedron"][0] + [2, 0, 0]
    pts = np.vstack([UNIT["hexahedron"][0], X, good])
    cells = np.array([np.arange(8), np.arange(8, 16), np.arange(16, 24)])
    path = tmp_path / "twisted.vtu"
    meshio.write(path, meshio.Mesh(pts, [("hexahedron", cells)]))
    with pytest.raises(MeshError, match=r"twisted\.vtu: cell 1 \(hexahedron\).*both orientations"):
        read_volume_mesh_file(path)
    r = runner.invoke(app, ["mesh", "quality", str(path)])
    assert r.exit_code == 2 and "cell 1 (hexahedron)" in r.output and "Traceback" not in r.output
    meshio.write(path, meshio.Mesh(pts, [("hexahedron", cells[[0, 2]])]))
    r = runner.invoke(app, ["mesh", "quality", "--json", str(path)])
    assert r.exit_code == 0 and json.loads(r.output)["split_cells"] == {"hexahedron": 2}
    assert json.loads(r.output)["tets"] == 12


def _sagging(tmp_path: Path, mesh: Path, fixed: str) -> dict:
    """`pliant run` of the mesh file for 2 ms under gravity, the nodes ``fixed`` held (a scene's
    node selection): its summary."""
    (tmp_path / "s.toml").write_text(
        f'[mesh]\nfile = "{mesh}"\n'
        '[[material]]\ntype = "neo-hookean"\nE = 3000.0\nnu = 0.45\ndensity = 1000.0\n'
        "[solver]\nduration = 0.002\ndt = 1e-4\n"
        f'[[constraint]]\ntype = "fix"\nnodes = {fixed}\n[[load]]\ntype = "gravity"\n'
    )
    r = runner.invoke(app, ["run", str(tmp_path / "s.toml"), "-o", str(tmp_path / "out")])
    assert r.exit_code == 0, r.output
    return json.loads((tmp_path / "out" / "summary.json").read_text())


@pytest.mark.filterwarnings("ignore:.*split into tetrahedra")  # the summary's warning, asserted
def test_a_scene_on_a_hexahedral_mesh_file_says_it_was_split(tmp_path):
    """A scene whose [mesh] file holds hexahedra runs, and its summary's warnings say how many
    cells became how many tets; quadratic hexahedra are still refused by name (exit 2)."""
    import meshio

    X, T = read_volume_mesh_file(HYBRID)[:2]
    hexes = [c.data for c in meshio.read(HYBRID).cells if c.type == "hexahedron"][0]
    used = np.unique(hexes)
    remap = np.full(len(X), -1)
    remap[used] = np.arange(used.size)
    meshio.write(tmp_path / "hexes.vtu", meshio.Mesh(X[used], [("hexahedron", remap[hexes])]))
    summary = _sagging(
        tmp_path, tmp_path / "hexes.vtu", "{ plane = { point = [0.0, 0.0, 0.0], normal = [1.0, 0.0, 0.0] } }"
    )
    assert summary["elements"] == 6 * len(hexes)
    assert any("144 hexahedra split into tetrahedra" in w for w in summary["warnings"])


@pytest.mark.filterwarnings("ignore:.*split into tetrahedra")  # the summary's warning, asserted
def test_quadratic_hexahedra_are_taken_by_their_corners(tmp_path):
    """gmsh's incomplete order-2 box (8 hexahedron20, 81 nodes; its x = 0 face the physical
    surface "fixed" of quad8): linearized by their 8 corners and split, 48 tets on the 27 corner
    nodes (the 54 mid-edge nodes left out: no element uses them), filling the box (6e-6 m³, closed
    form); "fixed" renumbered to the 9 corners on x = 0; a scene fixing it runs and says so."""
    import meshio

    raw = meshio.read(HEX20)
    (cells,) = [c.data for c in raw.cells if c.type == "hexahedron20"]
    m = read_volume_mesh_file(HEX20)
    assert m.split == {"hexahedron20": 8} and m.tets.shape == (48, 4)
    assert len(m.nodes) == 27 and np.unique(m.tets).size == 27
    corners = {tuple(p) for p in raw.points[np.unique(cells[:, :8])]}
    assert {tuple(p) for p in m.nodes} == corners
    v = tet_volumes(m.nodes, m.tets)
    assert v.min() > 0 and v.sum() == pytest.approx(0.03 * 0.02 * 0.01, rel=1e-12)
    np.testing.assert_array_equal(m.node_sets["fixed"], np.nonzero(m.nodes[:, 0] == 0.0)[0])
    assert m.node_sets["fixed"].size == 9
    summary = _sagging(tmp_path, HEX20, '{ set = "fixed" }')
    assert summary["nodes"] == 27
    assert any("hexahedron20 by their corners, mid-edge nodes dropped" in w for w in summary["warnings"])


def test_grid_hexahedra_are_in_vtk_order_and_fill_their_box():
    """grid_hexahedra on graded lines: every cell's corners are its grid box's in VTK's order (the
    unit cube's pattern, closed form), and the cells split into tets fill the box (its volume,
    1e-12 relative: round-off)."""
    from pliant.mesh.primitives import grid_hexahedra

    xs, ys, zs = [0, 0.1, 0.3], [0, 0.2, 0.25, 0.5], [0, 0.4]
    X, H = grid_hexahedra(xs, ys, zs)
    assert H.shape == (2 * 3 * 1, 8)
    unit, _ = UNIT["hexahedron"]
    for cell in H:
        P = X[cell]
        lo, hi = P.min(axis=0), P.max(axis=0)
        np.testing.assert_array_equal(P, lo + unit * (hi - lo))
    T, _ = split_cells(X, "hexahedron", H)
    assert tet_volumes(X, T).sum() == pytest.approx(0.3 * 0.5 * 0.4, rel=1e-12)
