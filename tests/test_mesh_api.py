"""The mesh functions' arguments (pliant.mesh): arrays that are no mesh, indices out of range,
numbers that are no numbers are refused naming the function and the culprit, where they were
numpy's or Python's errors (IndexError, TypeError, a 1.5 PiB allocation) before. Found by calling
each public function with one argument replaced by a hostile value."""

from __future__ import annotations

import itertools
import re

import numpy as np
import pytest

import pliant as pl
from pliant.mesh.repair import _tri_tri_intersect, count_self_intersections

V, F = pl.mesh.primitive_surface("sphere", radius=0.01, subdivisions=2)
X, T = pl.mesh.box_tets((0.02, 0.01, 0.01), (3, 2, 2))

SURFACE_CALLS = {
    "check_surface": lambda v, f: pl.mesh.check_surface(v, f),
    "repair": lambda v, f: pl.mesh.repair_surface(v, f),
    "simplify": lambda v, f: pl.mesh.simplify(v, f, target_faces=100),
    "subdivide": lambda v, f: pl.mesh.subdivide_loop(v, f),
    "default_edge_length": lambda v, f: pl.mesh.default_edge_length(v, f),
    "surface_to_tets": lambda v, f: pl.mesh.surface_to_tets(v, f),
    "tetrahedralize": lambda v, f: pl.mesh.tetrahedralize(v, f),
}
TET_CALLS = {
    "tet_quality": lambda x, t: pl.mesh.tet_quality(x, t),
    "orient_positive": lambda x, t: pl.mesh.orient_positive(x, t),
    "tet_quality ": lambda x, t: pl.mesh.critical_time_steps(x, t, pl.NeoHookean(E=1e3, nu=0.3), 1000.0),
    "embed_surface": lambda x, t: pl.mesh.embed_surface(x, t, V * 0.5, F),
}


def _out_of_range(f):
    g = f.copy()
    g[3, 1] = 10**9
    return g


def _stray(x):
    y = x.copy()
    y[2, 0] = np.nan
    return y


@pytest.mark.parametrize("who", SURFACE_CALLS)
@pytest.mark.parametrize(
    "bad, says",
    [
        (lambda v, f: (v, _out_of_range(f)), r"face 3 has node index 1000000000; expected 0 <= index < 162"),
        (lambda v, f: (v, -f), r"face 0 has node index -0|face \d+ has node index -\d+"),
        (lambda v, f: (_stray(v), f), r"node 2 has a non-finite coordinate"),
        (lambda v, f: (v[:, :2], f), r"nodes have shape \(162, 2\)"),
        (lambda v, f: (v, f[:, :2]), r"faces have shape \(320, 2\)"),
        (lambda v, f: ("x", f), r"must be numeric arrays"),
        (lambda v, f: (v, f + 0.5), r"face indices must be integers"),
    ],
)
def test_surface_functions_name_a_surface_that_is_no_surface(who, bad, says):
    v, f = bad(V, F)
    with pytest.raises(pl.MeshError, match=says):
        SURFACE_CALLS[who](v, f)


@pytest.mark.parametrize("who", TET_CALLS)
def test_tet_functions_name_an_index_out_of_range_and_a_non_finite_node(who):
    t = T.copy()
    t[5, 2] = len(X)
    with pytest.raises(
        pl.MeshError, match=rf"element 5 has node index {len(X)}; expected 0 <= index < {len(X)}"
    ):
        TET_CALLS[who](X, t)
    with pytest.raises(pl.MeshError, match="node 2 has a non-finite coordinate"):
        TET_CALLS[who](_stray(X), T)


def _brute_force_self_intersections(v, f) -> int:
    """Every pair of faces that share no vertex and whose bounding boxes meet (an exact filter: the
    Möller test alone, its planes' round-off at 1e12 m, calls faces apart intersecting), through
    the same Möller test: the reference for the grid's candidate search."""
    tri = v[f]
    lo, hi = tri.min(axis=1), tri.max(axis=1)
    pairs = np.array(
        [
            (a, b)
            for a, b in itertools.combinations(range(len(f)), 2)
            if not set(f[a]) & set(f[b]) and np.all((lo[a] <= hi[b]) & (lo[b] <= hi[a]))
        ]
    )
    with np.errstate(over="ignore", invalid="ignore"):
        return int(_tri_tri_intersect(tri[pairs[:, 0]], tri[pairs[:, 1]]).sum())


@pytest.mark.parametrize("far", [1e3, 1e12, 1e300])
def test_a_stray_vertex_far_out_is_checked_without_filling_memory(far):
    """A scan's stray vertex (a spike to ``far`` m from a 1 cm sphere): check_surface finds the
    self-intersections an all-pairs search finds (the grid put the spike's faces in 1e14
    cells at 1e12 m: a 1.5 PiB allocation; at 1e300, an OverflowError), and calls only the
    spike's needle faces degenerate (at 1e3 m every face of the sphere was, measured against the
    surface's size)."""
    v = V.copy()
    v[5] = [far, 0.0, 0.0]
    report = pl.mesh.check_surface(v, F)  # 0.05 s measured; the old grid did not finish
    assert report.self_intersections == _brute_force_self_intersections(v, F) > 0
    spike = int(np.any(F == 5, axis=1).sum())
    assert report.degenerate_faces <= spike


def test_large_faces_beside_small_ones_are_paired_as_an_all_pairs_search_pairs_them():
    """A 1 cm sphere through the top of a 1 m hexagonal prism (its 24 faces each over up to 4e5
    cells of the grid the sphere's small faces set, more than there are faces: paired by box): the
    same count as the all-pairs search."""
    bv, bf = pl.mesh.primitive_surface("cylinder", radius=0.5, height=0.5, segments=6)
    v = np.vstack([V + [0.0, 0.0, 0.25], bv])
    f = np.vstack([F, bf + len(V)])
    assert count_self_intersections(v, f) == _brute_force_self_intersections(v, f) > 0


@pytest.mark.parametrize(
    "call, says",
    [
        (lambda: pl.mesh.graded_coordinates(1e-320, 0.01, 1.2, 0.05), "coordinates; expected at most 1e"),
        (lambda: pl.mesh.graded_coordinates(1e-9, 0.0, 1.0, 1.0), "coordinates; expected at most 1e"),
        (lambda: pl.mesh.graded_coordinates(1j, 0.01, 1.2, 0.05), "expected h > 0"),
        (lambda: pl.mesh.grid_tets([0, 1], "x", [0, 1]), "ys = 'x'; expected at least 2 finite"),
        (lambda: pl.mesh.box_tets(origin=(0, np.nan, 0)), "origin = .*expected 3 finite numbers"),
        (lambda: pl.mesh.box_tets(jitter=1j), "jitter = 1j; expected 0 <= jitter < 0.5"),
        (lambda: pl.mesh.box_tets(size=1j), "size = 1j; expected three finite lengths"),
        (lambda: pl.mesh.box_tets(seed=-3), "seed = -3; expected an integer >= 0"),
        (lambda: pl.mesh.box_tets(seed=1.5), "seed = 1.5; expected a whole number"),
        (
            lambda: pl.mesh.split_quads([[0, 1, 2]]),
            r"split_quads: quads = \[\[0, 1, 2\]\]; expected an \(F, 4\)",
        ),
        (lambda: pl.mesh.split_quads([[0, 1, 2, -1]]), "expected an .* node indices >= 0"),
        (lambda: pl.mesh.primitive_surface(np.array([1.0])), r"unknown primitive \[1.0\]"),
        (lambda: pl.mesh.primitive_surface("sphere"), "sphere: give radius"),
        (lambda: pl.mesh.primitive_surface("sphere", radius=np.array([1.0, 2.0])), "radius = "),
        (lambda: pl.mesh.simplify(V, F, ratio=1j), "ratio = 1j; expected 0 < ratio <= 1"),
        (lambda: pl.mesh.simplify(V, F, target_faces=100.5), "target_faces = 100.5; expected a whole number"),
        (lambda: pl.mesh.subdivide_loop(V, F, levels=0.5), "levels = 0.5; expected a whole number"),
        (lambda: pl.mesh.surface_to_tets(V, F, target_tets=7.5), "target_tets = 7.5; expected a whole"),
        (lambda: pl.mesh.repair_surface(V, F, bodies=np.array([1])), "bodies = "),
        (lambda: pl.mesh.critical_time_steps(X, T, "rubber", 1000.0), "material = str; expected a pliant"),
        (lambda: pl.mesh.critical_time_steps(X, T, pl.NeoHookean(E=1e3, nu=0.3), -1.0), "density = -1"),
        (lambda: pl.mesh.embed_surface(X, T, np.full((3, 3), 1e300), np.zeros((0, 3), int)), "too far"),
        (lambda: pl.mesh.embed_surface(X, T, V, F, candidates=0), "candidates = 0; expected >= 1"),
    ],
)
def test_mesh_arguments_that_are_no_numbers_or_too_many_are_named(call, says):
    with pytest.raises(pl.InputError, match=says):
        call()


def test_a_stray_vertex_is_named_where_it_makes_the_surface_as_good_as_flat():
    """Spot (shared/meshes, 2,930 vertices, about 1 m across) with one vertex moved 1 km or 1e12 m
    out: check_surface names it as a problem; tetrahedralize, which measures flatness and volume
    against the surface's size, says the surface encloses no volume because of it (it said "all
    vertices lie on one plane (a flat sheet)", of a cow); repair, whose merge tolerance is relative
    to that size too, names it. The four shared meshes and a 1 m × 1 mm needle have none."""
    from pliant.mesh.repair import stray_vertex
    from test_mesh_pipeline import shared

    v, f = pl.mesh.read_surface(shared("spot.obj"))
    for far in (1e3, 1e12):
        w = v.copy()
        w[100] = [far, 0.0, 0.0]
        distance = re.escape(f"{far:.3g}")
        says = rf"vertex 100 lies {distance} m from the others' median, 99 % of them within 1.\d+ m"
        assert any(re_match(says, p) for p in pl.mesh.check_surface(w, f).problems)
        with pytest.raises(pl.MeshError, match=rf"encloses no volume: {says}.*as good as flat"):
            pl.mesh.tetrahedralize(w, f)
    with pytest.raises(pl.MeshError, match=r"no valid faces left .*; vertex 100 lies 1e\+12 m"):
        pl.mesh.repair_surface(w, f)
    for name in ("spot.obj", "stanford-bunny.obj", "liver.obj", "kidney.obj"):
        assert stray_vertex(pl.mesh.read_surface(shared(name))[0]) == ""
    needle, _ = pl.mesh.primitive_surface("cylinder", radius=5e-4, height=1.0, segments=64)
    assert stray_vertex(needle) == ""


def re_match(pattern: str, text: str) -> bool:
    return re.search(pattern, text) is not None


@pytest.mark.parametrize("bad", ["false", np.array([True, False]), None, 2])
@pytest.mark.parametrize(
    "call, name",
    [
        (lambda b: pl.mesh.check_surface(V, F, self_intersections=b), "self_intersections"),
        (lambda b: pl.mesh.repair_surface(V, F, fill_holes=b), "fill_holes"),
        (lambda b: pl.mesh.repair_surface(V, F, keep_largest=b), "keep_largest"),
        (lambda b: pl.mesh.simplify(V, F, target_faces=100, preserve_boundary=b), "preserve_boundary"),
        (lambda b: pl.mesh.tetrahedralize(V, F, optimize=b), "optimize"),
        (lambda b: pl.mesh.tetrahedralize(V, F, cache=b), "cache"),
        (lambda b: pl.mesh.tetrahedralize(V, F, keep_all=b), "keep_all"),
        (lambda b: pl.mesh.surface_to_tets(V, F, repair=b), "repair"),
        (lambda b: pl.mesh.surface_to_tets(V, F, keep_largest=b), "keep_largest"),
        (lambda b: pl.mesh.surface_to_tets(V, F, fill_shell=b), "fill_shell"),
    ],
)
def test_mesh_flags_are_true_or_false(call, name, bad):
    """A flag given a string, an array, None or 2 is named: bool() made "false" True (a repair
    skipped, a cache bypassed the other way round), and an array raised numpy's "truth value of an
    array is ambiguous", naming no argument."""
    with pytest.raises(pl.InputError, match=rf"{name} = .*expected True or False"):
        call(bad)


@pytest.mark.parametrize(
    "call, says",
    [
        (
            lambda: pl.mesh.tetrahedralize(V, F, edge_length="0.004"),
            r"edge length '0.004'; expected a finite",
        ),
        (lambda: pl.mesh.tetrahedralize(V, F, edge_length=True), "edge length True; expected a finite"),
        (lambda: pl.mesh.tetrahedralize(V, F, edge_length=0.0), "edge length 0.0; expected a finite"),
        (lambda: pl.mesh.tetrahedralize(V, F, edge_length_fac=2.0), "edge_length_fac = 2.0; expected"),
        (lambda: pl.mesh.tetrahedralize(V, F, epsilon=np.nan), "epsilon = nan; expected an envelope"),
        (lambda: pl.mesh.tetrahedralize(V, F, epsilon=1.0), "epsilon = 1.0; expected an envelope"),
        # fTetWild ran for over 100 s at 1e-5 on this sphere, and aborted at 0.1.
        (lambda: pl.mesh.tetrahedralize(V, F, epsilon=1e-5), "epsilon = 1e-05; expected .* from 5e-05"),
        (lambda: pl.mesh.surface_to_tets(V, F, epsilon=0.1), "epsilon = 0.1; expected .* to 0.05"),
        (lambda: pl.mesh.tetrahedralize(V, F, threads=-1), "threads = -1; expected 0"),
        (lambda: pl.mesh.tetrahedralize(V, F, threads="all"), "threads = 'all'; expected a whole"),
        (lambda: pl.mesh.surface_to_tets(V, F, epsilon="x"), "epsilon = 'x'; expected an envelope"),
        (lambda: pl.mesh.surface_to_tets(V, F, target_faces="x"), "target_faces = 'x'; expected a whole"),
        (lambda: pl.mesh.surface_to_tets(V, F, target_faces=3), "target_faces = 3; expected >= 4"),
    ],
)
def test_tetrahedralization_arguments_are_named(call, says):
    """fTetWild's parameters checked before it runs: float("0.004") and float(True) made an edge
    of a string and of 1 m, and int("all") was Python's ValueError."""
    with pytest.raises(pl.InputError, match=says):
        call()


@pytest.mark.parametrize("call", ["tetrahedralize", "surface_to_tets"])
def test_an_edge_longer_than_the_surface_is_refused_by_its_size(call):
    """A tet edge longer than the surface's bounding-box diagonal (a length in other units than
    the surface's: 5 for a 2 cm sphere in metres) fits no tet; fTetWild ran for minutes on it
    (over 2 minutes at 6 diagonals, measured on this 1 cm sphere). Refused at once, naming both."""
    diag = float(np.linalg.norm(np.ptp(V, axis=0)))
    with pytest.raises(pl.MeshError, match=rf"edge length 5 m is longer than .* \({diag:.3g} m\)"):
        getattr(pl.mesh, call)(V, F, edge_length=5.0)


def test_ftetwild_is_given_at_most_a_quarter_of_the_diagonal(monkeypatch):
    """An edge up to the diagonal is meshed, with fTetWild's target capped at EDGE_CAP of the
    diagonal: beyond that its mesh is no coarser (the envelope keeps the surface's detail; on the
    sphere here 2,700-3,300 tets from 0.09 to 1.4 diagonals) and its run grows without bound.
    The default edge of a cube for one tet (1.2 diagonals) is meshed too, at the diagonal."""
    from pliant.mesh import ftetwild
    from pliant.mesh.tetra import EDGE_CAP

    given = []
    real = ftetwild.run

    def spy(V, F, edge_r, *rest):
        given.append(edge_r)
        return real(V, F, edge_r, *rest)

    monkeypatch.setattr(ftetwild, "run", spy)
    diag = float(np.linalg.norm(np.ptp(V, axis=0)))
    Xs, Ts = pl.mesh.tetrahedralize(V, F, edge_length=0.9 * diag, cache=False)
    assert given == [EDGE_CAP] and pl.mesh.tet_quality(Xs, Ts)["volume"].min() > 0
    import trimesh

    cube = trimesh.creation.box(extents=(0.02, 0.02, 0.02))
    Vc, Fc = np.asarray(cube.vertices), np.asarray(cube.faces)
    Xc, Tc, info = pl.mesh.surface_to_tets(Vc, Fc, target_tets=1)
    assert info["edge_length"] == pytest.approx(np.sqrt(3) * 0.02) and given[-1] == EDGE_CAP
    # Within fTetWild's envelope: faces may move by 2e-3 of the diagonal, 6 √3 · 2e-3 = 2 % of the
    # volume at most (measured 2e-5).
    assert pl.mesh.tet_quality(Xc, Tc)["volume"].sum() == pytest.approx(0.02**3, rel=0.02)


def test_a_max_volume_beyond_the_surface_meshes_it_coarsest(tmp_path):
    """`pliant mesh tetrahedralize --max-volume` is an upper bound: one larger than the surface
    (10 m³ for a 1 cm sphere) meshes it as coarsely as its diagonal allows, where its edge was
    refused as longer than the surface."""
    from typer.testing import CliRunner

    from pliant.cli import app

    surface = tmp_path / "sphere.stl"
    import trimesh

    trimesh.Trimesh(V, F).export(surface)
    r = CliRunner().invoke(
        app, ["mesh", "tetrahedralize", str(surface), str(tmp_path / "o.vtu"), "--max-volume", "10"]
    )
    assert r.exit_code == 0, r.output
    Xo, To = pl.io.read_volume_mesh(tmp_path / "o.vtu")[:2]
    assert pl.mesh.tet_quality(Xo, To)["volume"].min() > 0
