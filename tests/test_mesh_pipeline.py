"""Mesh pipeline on real meshes (../shared/meshes: the study's bunny, a kidney, Spot) and closed
forms (regular tet, torus volume, Loop subdivision counts from Euler's formula)."""

from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

import pliant as pl
from pliant.cli import app
from pliant.errors import MeshError
from pliant.mesh.primitives import tet_volumes
from pliant.mesh.repair import surface_volume

SHARED = Path(__file__).resolve().parents[2] / "shared" / "meshes"
runner = CliRunner()


def shared(name):
    p = SHARED / name
    if not p.exists():
        pytest.skip(f"real mesh {p} not available (../shared/meshes beside the checkout)")
    return p


def _euler(F):
    e = np.unique(np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1), axis=0)
    return len(e)


def test_qem_simplification_of_the_study_bunny():
    """Bunny 35,947 vertices → 3,596 and 362 (the study's figures), staying on the surface. The
    scan is repaired first (holes closed): a closed genus-0 surface of F faces has F/2 + 2
    vertices, so the targets are 7,188 and 720 faces."""
    from scipy.spatial import cKDTree

    V, F = pl.mesh.read_surface(shared("stanford-bunny.obj"))
    assert (len(V), len(F)) == (35947, 69451)  # the published scan
    diag = np.linalg.norm(np.ptp(V, axis=0))
    tree = cKDTree(V)
    Vr, Fr, _ = pl.mesh.repair_surface(V, F)
    for target_v in (3596, 362):
        Vs, Fs = pl.mesh.simplify(Vr, Fr, target_faces=2 * target_v - 4)
        assert len(Vs) == target_v
        rep = pl.mesh.check_surface(Vs, Fs, self_intersections=False)
        assert rep.watertight and rep.winding_consistent  # manifold kept
        # Simplified vertices stay near the original surface (nearest original vertex; the scan's
        # vertex spacing is ~1e-3 of the diagonal): within 1 % of the diagonal.
        d, _ = tree.query(Vs)
        assert np.percentile(d, 99) < 0.01 * diag


def test_simplify_open_scan_keeps_its_boundary():
    V, F = pl.mesh.read_surface(shared("stanford-bunny.obj"))
    Vs, Fs = pl.mesh.simplify(V, F, target_faces=7000)
    before = pl.mesh.check_surface(V, F, self_intersections=False)
    after = pl.mesh.check_surface(Vs, Fs, self_intersections=False)
    assert after.non_manifold_edges == 0
    assert after.boundary_edges == before.boundary_edges and after.holes == before.holes


def test_loop_subdivision_counts_follow_euler():
    """Loop subdivision adds one vertex per edge: V' = V + E, F' = 4F. On the closed 362-vertex
    bunny V' = 4V − 6: 1,442 / 5,762 / 23,042 (the study's 1,416 / 5,603 / 22,293 fit V' = 4V − 3 − B
    for a mesh with one hole of B = 29 edges, B doubling each level)."""
    V, F = pl.mesh.read_surface(shared("stanford-bunny.obj"))
    V, F, _ = pl.mesh.repair_surface(V, F)
    V, F = pl.mesh.simplify(V, F, target_faces=720)
    counts = [len(V)]
    Vp, Fp = V, F
    for level in (1, 2, 3):
        Vs, Fs = pl.mesh.subdivide_loop(V, F, level)
        assert len(Vs) == len(Vp) + _euler(Fp) and len(Fs) == 4 * len(Fp)
        counts.append(len(Vs))
        Vp, Fp = Vs, Fs
    assert counts == [362, 1442, 5762, 23042]


def test_regular_tet_quality_and_time_step():
    X = np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1.0]])
    T = pl.mesh.orient_positive(X, np.array([[0, 1, 2, 3]]))
    q = pl.mesh.tet_quality(X, T)
    assert q["radius_edge"][0] == pytest.approx(np.sqrt(6) / 4)
    assert q["min_dihedral"][0] == pytest.approx(np.degrees(np.arccos(1 / 3)))
    assert q["max_dihedral"][0] == pytest.approx(np.degrees(np.arccos(1 / 3)))
    a = np.sqrt(8.0)  # edge
    assert q["volume"][0] == pytest.approx(a**3 / (6 * np.sqrt(2)))
    assert q["min_altitude"][0] == pytest.approx(a * np.sqrt(2 / 3))
    m = pl.LinearElastic(E=1e4, nu=0.3)
    dt = pl.mesh.critical_time_steps(X, T, m, 1000.0)
    assert dt[0] == pytest.approx(a * np.sqrt(2 / 3) / np.sqrt((m.lam + 2 * m.mu) / 1000.0))


def test_torus_of_the_study():
    """The study's torus: a 1,729-vertex surface tetrahedralized (study: 2,145 nodes, 7,456 tets).
    Checked against the closed-form volume 2π²Rr² (the polyhedral surface is inscribed: a little
    smaller, by under 2 % at this resolution)."""
    R, r = 0.05, 0.02
    V, F = pl.mesh.primitive_surface("torus", major_radius=R, minor_radius=r, segments=91, minor_segments=19)
    assert len(V) == 1729
    X, T, info = pl.mesh.surface_to_tets(V, F, target_tets=7456)
    q = pl.mesh.tet_quality(X, T)
    assert q["volume"].min() > 0
    exact = 2 * np.pi**2 * R * r * r
    assert 0.96 * exact < q["volume"].sum() < exact
    print(f"torus: {len(X):,} nodes, {len(T):,} tets (study: 2,145 / 7,456)")


@pytest.mark.parametrize("name", ["stanford-bunny.obj", "kidney.obj"])
def test_open_scans_become_valid_tet_meshes(name):
    V, F = pl.mesh.read_surface(shared(name))
    assert not pl.mesh.check_surface(V, F, self_intersections=False).watertight
    X, T, info = pl.mesh.surface_to_tets(V, F)
    q = pl.mesh.tet_quality(X, T)
    assert q["volume"].min() > 0 and 5000 < len(T) < 200_000
    assert 0.9 <= info["volume_ratio"] <= 1.1
    # One fTetWild run: the kidney scan's walls are 0.34 mm thick on a 15 cm diagonal, and the
    # default envelope (2e-3 of it, 0.31 mm) let fTetWild lay their two sheets onto each other
    # (28 % of the volume, then a second run at 1e-3); the envelope follows the walls from the start.
    assert len(info["tries"]) == 1
    # A valid tet mesh: no face in more than two tets, one face-connected body, and a closed
    # boundary (every boundary edge in an even number of boundary faces).
    from pliant.mesh.tetra import largest_component
    from pliant.mesh.topology import boundary_faces

    faces = np.sort(
        np.concatenate([T[:, [1, 2, 3]], T[:, [0, 2, 3]], T[:, [0, 1, 3]], T[:, [0, 1, 2]]]), axis=1
    )
    assert np.unique(faces, axis=0, return_counts=True)[1].max() <= 2
    assert len(largest_component(T)) == len(T)
    bf, _ = boundary_faces(T)
    e = np.sort(np.concatenate([bf[:, [0, 1]], bf[:, [1, 2]], bf[:, [2, 0]]]), axis=1)
    assert np.all(np.unique(e, axis=0, return_counts=True)[1] % 2 == 0)
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(pl.NeoHookean(E=5e3, nu=0.45), density=1000.0)
    assert b.finalize().dt_critical > 0


def test_bad_surfaces(tmp_path):
    txt = tmp_path / "x.obj"
    txt.write_text("this is not a mesh\n")
    with pytest.raises(MeshError, match="empty"):
        pl.mesh.read_surface(txt)
    r = runner.invoke(app, ["mesh", "check", str(txt)])
    assert r.exit_code == 2 and "empty" in r.output
    junk = tmp_path / "x.stl"
    junk.write_bytes(b"\x00\x01garbage")
    r = runner.invoke(app, ["mesh", "tetrahedralize", str(junk), str(tmp_path / "o.vtu")])
    assert r.exit_code == 2 and "x.stl" in r.output
    # Three triangles on one edge: non-manifold beyond repair.
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1.0]])
    F = np.array([[0, 1, 2], [1, 0, 3], [0, 1, 4]])
    assert pl.mesh.check_surface(V, F).notes == []  # no note that repair would split it
    with pytest.raises(MeshError, match="non-manifold edge"):
        pl.mesh.repair_surface(V, F)


@pytest.mark.parametrize("edge", ["1e-6", "1e-300", "5e-324"])
def test_an_edge_length_too_small_for_any_mesh_is_refused(tmp_path, edge):
    """An edge length that would make more than MAX_TETS tets is refused naming the count; at
    1e-300 m and below its square underflowed to 0 and the count divided by it (ZeroDivisionError,
    an internal error, exit 3; found by mutating examples/organs_contact.toml's edge_length)."""
    import trimesh

    m = trimesh.creation.icosphere(subdivisions=2, radius=0.05)
    src = tmp_path / "ball.stl"
    m.export(src)
    r = runner.invoke(
        app, ["mesh", "tetrahedralize", str(src), str(tmp_path / "o.vtu"), "--edge-length", edge]
    )
    assert r.exit_code == 2 and "would make about" in r.output and "give a larger edge length" in r.output, (
        r.output
    )


def _cubes(shift, drop_shared=False):
    """Two 2 cm cubes (trimesh's boxes: 12 faces each), the second moved by ``shift`` [m]; with
    ``drop_shared`` the second loses its faces on the first one's +x face (one interface of three
    faces per edge), and the vertices are merged as a file would hold them."""
    import trimesh

    a = trimesh.creation.box((0.02, 0.02, 0.02))
    b = a.copy()
    b.apply_translation(shift)
    V, F = np.r_[a.vertices, b.vertices], np.r_[a.faces, b.faces + len(a.vertices)]
    if drop_shared:
        F = F[~np.all(np.isclose(V[F][:, :, 0], 0.01), axis=1) | (np.arange(len(F)) < 12)]
    m = trimesh.Trimesh(V, F, process=True)
    return np.asarray(m.vertices), np.asarray(m.faces)


def test_bodies_touching_along_an_edge_or_a_face_are_split_there():
    """Non-manifold edges where closed bodies touch: two cubes sharing an edge (four faces on it),
    and two cubes sharing a face that the file holds once (three faces on each of its edges). Repair
    splits the surface there, closes each region over the interface and drops the interface left on
    its own (flat); the volume of what it keeps is the two cubes' 2 (2 cm)³: exact to round-off (the
    faces are planar). Tetrahedralized, the edge-sharing pair fills the same volume within 1 %
    (fTetWild keeps the boundary within its envelope, 2e-3 of the diagonal)."""
    exact = 2 * 0.02**3
    V, F = _cubes((0.02, 0.02, 0.0))
    assert "where bodies touch" in pl.mesh.check_surface(V, F).notes[0]  # check points to repair
    Vr, Fr, actions = pl.mesh.repair_surface(V, F, bodies="all")
    assert "split the surface at 1 non-manifold edge(s) (bodies touching there)" in actions
    assert surface_volume(Vr, Fr) == pytest.approx(exact, rel=1e-12)
    X, T, _ = pl.mesh.surface_to_tets(V, F, edge_length=0.005)
    assert tet_volumes(X, T).sum() == pytest.approx(exact, rel=0.01)
    V, F = _cubes((0.02, 0.0, 0.0), drop_shared=True)
    assert len(F) == 22
    Vr, Fr, actions = pl.mesh.repair_surface(V, F, bodies="all")
    assert "split the surface at 4 non-manifold edge(s) (bodies touching there)" in actions
    # the two open cubes and the interface, each closed over its one square hole, said once
    assert "filled 1 hole(s) (4 boundary edges) by minimum-area triangulation, in each of 3 pieces" in actions
    assert "dropped 1 flat piece(s) enclosing no volume" in actions
    assert surface_volume(Vr, Fr) == pytest.approx(exact, rel=1e-12)


def test_holes_that_meet_at_a_vertex_are_filled():
    """An octahedron without two faces that share only a vertex (its boundary passes that vertex
    twice, a figure eight) and a cube's surface without two such faces: repair closes each hole by
    itself (a three-edge hole's only triangle is the face removed), so the surface encloses the
    solid's volume again (4/3 for the octahedron of unit radius, 1 for the cube; round-off only)."""
    octa = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1.0]])
    octa_faces = np.array(
        [[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]]
    )
    cube = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    cube_faces = np.array(
        [[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1], [2, 3, 7], [2, 7, 6]]
        + [[0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]]
    )
    # octahedron: faces 0 (0, 2, 4) and 6 (3, 1, 5) share no vertex; 0 and 2 (1, 3, 4) share vertex 4
    for V, F, drop, volume in [(octa, octa_faces, [0, 2], 4 / 3), (cube, cube_faces, [0, 8], 1.0)]:
        keep = np.setdiff1d(np.arange(len(F)), drop)
        shared = set(F[drop[0]].tolist()) & set(F[drop[1]].tolist())
        assert len(shared) == 1  # the two holes meet at one vertex
        Vr, Fr, actions = pl.mesh.repair_surface(V, F[keep])
        assert "filled 2 hole(s) (6 boundary edges) by minimum-area triangulation" in actions
        assert pl.mesh.check_surface(Vr, Fr).ok
        assert surface_volume(Vr, Fr) == pytest.approx(volume, rel=1e-12)


def test_repair_reports_every_change_it_makes():
    """A tetrahedron's four faces, one of them wound against the others, then all four inward: the
    repaired surface is closed with outward faces (positive volume: 1/6 of the unit cube's corner)
    and the actions say what was changed; a surface needing nothing says nothing."""
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0]])
    outward = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    one_flipped = outward.copy()
    one_flipped[1] = one_flipped[1, ::-1]
    for F, expected in [
        (outward, []),
        (one_flipped, ["made winding consistent"]),
        (outward[:, ::-1], ["flipped faces outward"]),
    ]:
        Vr, Fr, actions = pl.mesh.repair_surface(V, F)
        assert surface_volume(Vr, Fr) == pytest.approx(
            1 / 6, rel=1e-12
        )  # sums of products of 0 and 1: round-off only
        assert actions == expected


def test_subdivision_levels_beyond_any_memory_are_refused():
    """4^1000 overflows a float: a MeshError naming the levels, not an OverflowError."""
    V, F = pl.mesh.primitive_surface("sphere", radius=1.0)
    with pytest.raises(MeshError, match="1000 levels turn 1,280 faces"):
        pl.mesh.subdivide_loop(V, F, 1000)


def test_embedding_follows_affine_motion():
    """Embedded vertices are barycentric in their tets: under an affine motion of the nodes they
    move by exactly the same affine map."""
    X, T = pl.mesh.box_tets((1, 1, 1), (4, 4, 4), jitter=0.2, seed=2)
    rng = np.random.default_rng(0)
    P = rng.uniform(0.05, 0.95, (500, 3))
    emb = pl.mesh.embed_surface(X, T, P, np.zeros((0, 3), int))
    assert np.all(emb.distance == 0) and np.all(emb.weights > -1e-12)
    A = np.array([[1.1, 0.2, 0.0], [0.0, 0.9, 0.1], [0.05, 0.0, 1.2]])
    c = np.array([0.3, -0.1, 0.2])
    assert np.allclose(emb.positions(T, X @ A.T + c), P @ A.T + c)


def test_cli_mesh_commands(tmp_path):
    spot = shared("spot.obj")
    r = runner.invoke(app, ["mesh", "check", str(spot)])
    assert r.exit_code == 0 and "ok" in r.output
    r = runner.invoke(app, ["mesh", "simplify", str(spot), str(tmp_path / "s.obj"), "--ratio", "0.5"])
    assert r.exit_code == 0, r.output
    r = runner.invoke(
        app, ["mesh", "subdivide", str(tmp_path / "s.obj"), str(tmp_path / "d.obj"), "--levels", "1"]
    )
    assert r.exit_code == 0, r.output
    out = tmp_path / "spot.vtu"
    r = runner.invoke(app, ["mesh", "tetrahedralize", str(spot), str(out), "--edge-length", "0.15"])
    assert r.exit_code == 0, r.output
    r = runner.invoke(app, ["mesh", "quality", str(out), "--png", str(tmp_path / "q.png"), "--json"])
    assert r.exit_code == 0, r.output
    assert (tmp_path / "q.png").stat().st_size > 5000
    r = runner.invoke(app, ["mesh", "simplify", str(spot), str(tmp_path / "s.obj")])
    assert r.exit_code == 2 and "exactly one" in r.output
    # A radius–edge ratio no tet can meet (below the regular tet's √6/4) or none at all is refused
    # before meshing (nan was taken, and the check skipped).
    for q in ("nan", "0.5"):
        r = runner.invoke(app, ["mesh", "tetrahedralize", str(spot), str(tmp_path / "q.vtu"), "--quality", q])
        assert r.exit_code == 2 and f"--quality {q}: expected a finite radius–edge ratio >= 0.612" in r.output


def test_loop_boundary_and_interior_rules():
    """Loop's rules on a small open mesh, computed by hand: boundary edge → midpoint; boundary
    vertex → 3/4 v + 1/8 (its two boundary neighbours); interior edge → 3/8 (a + b) + 1/8 (c + d)."""
    V = np.array([[0, 0, 0], [1, -0.3, 0], [2, 0, 0], [0, 1, 0], [1, 1, 0.2], [2, 1, 0.0]])
    F = np.array([[0, 1, 4], [0, 4, 3], [1, 2, 5], [1, 5, 4]])
    V2, F2 = pl.mesh.subdivide_loop(V, F, 1)
    assert len(V2) == 6 + 9 and len(F2) == 16
    assert np.allclose(V2[1], 0.75 * V[1] + 0.125 * (V[0] + V[2]))  # boundary even
    assert np.allclose(V2[0], 0.75 * V[0] + 0.125 * (V[1] + V[3]))  # corner: boundary rule
    mids = V2[6:]
    assert np.isclose(np.linalg.norm(mids - 0.5 * (V[0] + V[1]), axis=1), 0).any()  # boundary odd
    interior = 0.375 * (V[1] + V[4]) + 0.125 * (V[0] + V[5])  # edge (1, 4)
    assert np.isclose(np.linalg.norm(mids - interior, axis=1), 0).any()
    assert np.allclose(V2[3], 0.75 * V[3] + 0.125 * (V[0] + V[4]))  # corner (0, 1, 0)


def test_graded_grid_is_conforming_and_fills_its_box():
    """grid_tets on graded_coordinates: positive tets whose volumes sum to the box's, and whose
    boundary triangles (faces used by one tet only) add up to the box's surface area, which holds
    only if every interior face is shared (conforming)."""
    from pliant.errors import InputError
    from pliant.mesh.topology import boundary_faces

    xs = pl.mesh.graded_coordinates(0.1, 0.3, 1.5, 2.0)
    np.testing.assert_allclose(np.diff(xs)[:3], 0.1)  # uniform up to fine_to
    np.testing.assert_allclose(np.diff(xs)[3:] / np.diff(xs)[2:-1], 1.5)  # then geometric
    assert xs[-1] >= 2.0 and xs[-2] < 2.0
    zs = np.array([0.0, 0.5, 0.7])
    X, T = pl.mesh.grid_tets(xs, xs[:4], zs)
    e = X[T]
    vol = np.einsum("ij,ij->i", np.cross(e[:, 1] - e[:, 0], e[:, 2] - e[:, 0]), e[:, 3] - e[:, 0]) / 6
    L = np.array([xs[-1], xs[3], zs[-1]])
    assert vol.min() > 0 and np.isclose(vol.sum(), L.prod(), rtol=1e-12)
    F, _ = boundary_faces(T)
    tri = X[F]
    area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1).sum()
    assert np.isclose(area, 2 * (L[0] * L[1] + L[1] * L[2] + L[0] * L[2]), rtol=1e-12)
    with pytest.raises(InputError, match="strictly increasing"):
        pl.mesh.grid_tets([0.0, 1.0, 1.0], xs, zs)
    with pytest.raises(InputError, match="ratio"):
        pl.mesh.graded_coordinates(0.1, 0.3, 0.9, 2.0)
