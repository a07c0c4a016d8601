"""Surfaces of several closed bodies (a teapot's body, lid, handle and spout; two organs): meshed as
their union by default, or separately, or refused; checked against the closed-form volume of two
overlapping spheres (a lens subtracted)."""

import math
import re
import subprocess
import sys

import meshio
import numpy as np
import pytest
import trimesh

import pliant as pl

R = 0.05  # sphere radius [m]
D = 0.05  # distance between the two overlapping spheres' centres [m]


def _spheres():
    """Two spheres overlapping (centres D apart) and a third one apart, as one surface."""
    parts = [
        trimesh.creation.icosphere(subdivisions=4, radius=R).apply_translation(c)
        for c in ((0, 0, 0), (D, 0, 0), (0, 0.3, 0))
    ]
    m = trimesh.util.concatenate(parts)
    return np.asarray(m.vertices), np.asarray(m.faces), parts


def _tet_volume(X, T):
    e = X[T]
    return float(
        np.einsum("ij,ij->i", np.cross(e[:, 1] - e[:, 0], e[:, 2] - e[:, 0]), e[:, 3] - e[:, 0]).sum() / 6
    )


def _components(T):
    from pliant.mesh.tetra import largest_component

    sizes = []
    rest = T
    while len(rest):
        big = largest_component(rest)
        sizes.append(len(big))
        keep = ~np.isin(np.arange(len(rest)), _rows(rest, big))
        rest = rest[keep]
    return sizes


def _rows(A, B):
    index = {tuple(r): i for i, r in enumerate(A.tolist())}
    return [index[tuple(r)] for r in B.tolist()]


@pytest.fixture(scope="module")
def spheres():
    return _spheres()


def test_union_volume_matches_the_closed_form(spheres):
    """Union of three spheres, two overlapping: V = 3 V_s − V_lens with V_lens = π (4R + d)
    (2R − d)² / 12 (two equal spheres of radius R, centres d apart). Polyhedral spheres (5,120
    faces) hold 0.5 % less volume than true ones, and fTetWild's envelope (2e-3 of the diagonal)
    moves the boundary by ~0.1 % of R: 2 % covers both with margin."""
    V, F, parts = spheres
    X, T, info = pl.mesh.surface_to_tets(V, F, target_tets=20000)
    exact = 3 * 4 / 3 * math.pi * R**3 - math.pi * (4 * R + D) * (2 * R - D) ** 2 / 12
    assert info["bodies"] == 3 and info["bodies_mode"] == "union"
    assert _tet_volume(X, T) == pytest.approx(exact, rel=0.02)
    # One conforming mesh: the overlapping pair is one piece, the third sphere another.
    assert len(_components(T)) == 2
    assert np.all(pl.mesh.tet_quality(X, T)["volume"] > 0)


def test_separate_bodies_each_get_a_mesh(spheres):
    """'separate': three meshes that share no node; their volumes add up to the three spheres'
    (the overlap counted twice), within the same 2 %."""
    V, F, parts = spheres
    X, T, info = pl.mesh.surface_to_tets(V, F, target_tets=20000, bodies="separate")
    assert info["bodies"] == 3 and len(_components(T)) == 3
    assert _tet_volume(X, T) == pytest.approx(3 * 4 / 3 * math.pi * R**3, rel=0.02)


def test_one_body_refuses_and_largest_keeps_one(spheres):
    V, F, _ = spheres
    with pytest.raises(pl.MeshError, match="3 separate bodies"):
        pl.mesh.surface_to_tets(V, F, bodies="one")
    with pytest.raises(pl.MeshError, match="bodies = 'all'; expected one of"):
        pl.mesh.surface_to_tets(V, F, bodies="all")


def test_tetrahedralize_command_reports_the_union(spheres, tmp_path):
    V, F, _ = spheres
    src = tmp_path / "three.stl"
    meshio.write(src, meshio.Mesh(V, [("triangle", F)]))
    out = tmp_path / "three.vtu"
    exe = str(__import__("pathlib").Path(sys.executable).with_name("pliant"))
    r = subprocess.run(
        [exe, "mesh", "tetrahedralize", str(src), str(out), "--target-tets", "5000"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert r.returncode == 0, r.stderr
    assert "3 bodies meshed as their union" in r.stdout
    m = meshio.read(out)
    assert len(m.cells_dict["tetra"]) > 1000
    # The overlap it reports is the lens; within 10 %: the lens is 10 % of the bodies' volume and
    # the tets miss the polyhedral surface's volume by about 0.5 % of the whole (fTetWild's envelope).
    merged = float(re.search(r"\(([0-9.e+-]+) m\^3, \d+ %, of overlap merged\)", r.stdout)[1])
    assert merged == pytest.approx(math.pi * (4 * R + D) * (2 * R - D) ** 2 / 12, rel=0.1)


def test_tetrahedralize_command_on_apart_bodies_in_millimetres(tmp_path):
    """Two spheres apart: no overlap is reported as merged (the tets' and the surface's volumes
    differ by the meshing alone); given in millimetres (radius 50), the command warns of the units."""
    parts = [
        trimesh.creation.icosphere(3, radius=50.0).apply_translation(c) for c in ((0, 0, 0), (150, 0, 0))
    ]
    src = tmp_path / "two_mm.stl"
    trimesh.util.concatenate(parts).export(src)
    exe = str(__import__("pathlib").Path(sys.executable).with_name("pliant"))
    r = subprocess.run(
        [exe, "mesh", "tetrahedralize", str(src), str(tmp_path / "two.vtu"), "--target-tets", "3000"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert r.returncode == 0, r.stderr
    assert "no overlap beyond the meshing's 1 %" in r.stdout and "of overlap merged" not in r.stdout
    assert "250 m across" in r.stderr and "millimetres" in r.stderr


def test_scene_from_a_surface_of_several_bodies_says_so(spheres, tmp_path):
    """Scenes that start from surfaces mesh the union too, and the run reports it (stdout and
    summary.json)."""
    import json

    V, F, _ = spheres
    src = tmp_path / "three.stl"
    meshio.write(src, meshio.Mesh(V, [("triangle", F)]))
    scene = tmp_path / "s.toml"
    scene.write_text(f"""[mesh]
file = "{src}"
target_tets = 5000
[[material]]
type = "neo-hookean"
E = 1e4
nu = 0.4
density = 1000.0
[solver]
duration = 0.0005
[output]
png = false
""")
    exe = str(__import__("pathlib").Path(sys.executable).with_name("pliant"))
    r = subprocess.run(
        [exe, "run", str(scene), "-o", str(tmp_path / "o"), "--no-progress"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert r.returncode == 0, r.stderr
    assert "3 bodies in the surface, meshed as their union" in r.stdout
    s = json.loads((tmp_path / "o" / "summary.json").read_text())
    assert s["mesh_pipeline"]["bodies"] == 3 and s["mesh_pipeline"]["bodies_mode"] == "union"
