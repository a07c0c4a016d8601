"""Surface files written by other programs: ASCII STL (trimesh's writer, and the quirks of CAD
writers: keywords in capitals, CRLF, tabs, blank lines, polygons, several solids) and glTF 2.0
(trimesh's .glb, with a node's transform). References: the writer's own mesh, and closed forms of
the volume enclosed and of where a transform puts the vertices."""

import numpy as np
import pytest
import trimesh

from pliant.errors import MeshError
from pliant.mesh import read_surface


def enclosed_volume(V, F):
    """Σ over faces of a · (b × c) / 6 [m³]: the divergence theorem on a closed, outward surface."""
    a, b, c = (V[F[:, k]] for k in range(3))
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


def triangles(V, F):
    """The faces as sets of corner positions, rounded to 1e-12 m: independent of vertex numbering
    and of where each face starts."""
    return sorted(tuple(sorted(map(tuple, np.round(V[f], 12)))) for f in F)


def test_trimeshs_ascii_stl_is_its_mesh(tmp_path):
    """trimesh writes a blank line before `endsolid`, which broke meshio's reader ("cannot reshape
    array of size 144 into shape (0)"): the faces read are trimesh's, corners joined."""
    m = trimesh.creation.icosphere(subdivisions=2, radius=0.05)
    p = tmp_path / "ico.stl"
    m.export(p, file_type="stl_ascii")
    V, F = read_surface(p)
    assert len(V) == len(m.vertices) and len(F) == len(m.faces)  # every shared corner joined
    assert triangles(V, F) == triangles(m.vertices, m.faces)
    assert enclosed_volume(V, F) == pytest.approx(m.volume, rel=1e-12)  # the winding kept: outward


CAD = """SOLID cube\r
  FACET NORMAL 0 0 -1\r
\tOUTER LOOP\r
   VERTEX 0 0 0\r
   VERTEX 0 1 0\r
   VERTEX 1 1 0\r
   VERTEX 1 0 0\r
  ENDLOOP\r
 ENDFACET\r
\r
ENDSOLID cube\r
solid second\r
facet normal 0 0 1\r
outer loop\r
vertex 0 0 1\r
vertex 1 0 1\r
vertex 1 1 1\r
endloop\r
endfacet\r
endsolid second\r
"""


def test_cad_quirks_capitals_crlf_polygons_and_two_solids(tmp_path):
    """A quad facet is fanned from its first vertex (two triangles, its orientation kept); the
    second solid's triangle follows; shared corners are one vertex."""
    p = tmp_path / "cad.stl"
    p.write_bytes(CAD.encode())
    V, F = read_surface(p)
    assert len(V) == 7 and len(F) == 3
    n = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    assert np.allclose(n[:, 2], [-1, -1, 1])  # the facets' windings: down, down, up (unit areas × 2)
    assert triangles(V, F[:2]) == triangles(
        np.array([[0, 0, 0], [0, 1, 0], [1, 1, 0], [1, 0, 0.0]]), np.array([[0, 1, 2], [0, 2, 3]])
    )


def test_binary_stl_whose_header_says_solid_is_read_as_binary(tmp_path):
    """The binary header is free text, and some writers begin it with `solid`: the file's size
    (84 bytes + 50 a facet) tells it from ASCII."""
    m = trimesh.creation.box(extents=[0.1, 0.05, 0.02])
    p = tmp_path / "b.stl"
    data = m.export(file_type="stl")
    p.write_bytes(b"solid written by a CAD program".ljust(80) + data[80:])
    V, F = read_surface(p)
    assert enclosed_volume(V, F) == pytest.approx(0.1 * 0.05 * 0.02, rel=1e-6)  # float32 corners


@pytest.mark.parametrize(
    "cut, says",
    [
        (lambda t: t[: t.index("ENDLOOP")], "ends inside the facet of line 2"),
        (lambda t: t.replace("VERTEX 0 1 0", "VERTEX 0 one 0"), "cad.stl:5: expected 'vertex x y z'"),
        (
            lambda t: t.replace("   VERTEX 0 1 0\r\n   VERTEX 1 1 0\r\n   VERTEX 1 0 0\r\n", ""),
            "cad.stl:2: facet with 1",
        ),
        (lambda t: t.replace("OUTER LOOP", "INNER LOOP"), "cad.stl:3: unexpected 'INNER'"),
    ],
    ids=["truncated", "bad-number", "one-vertex", "unknown-keyword"],
)
def test_malformed_ascii_stl_is_refused_naming_the_line(tmp_path, cut, says):
    p = tmp_path / "cad.stl"
    p.write_bytes(cut(CAD).encode())
    with pytest.raises(MeshError, match=says.replace("(", r"\(")):
        read_surface(p)


def test_gltf_meshes_are_placed_by_their_nodes(tmp_path):
    """A .glb of a 24-sided cylinder (r = 2 cm, h = 10 cm) at node translation (1, 2, 3) m, scaled
    by 0.5: its vertices where the transform puts them, and the prism's volume
    (n/2) r² sin(2π/n) h scaled by 0.5³ (the closed surface, corners joined)."""
    n, r, h = 24, 0.02, 0.1
    cyl = trimesh.creation.cylinder(radius=r, height=h, sections=n)
    T = np.diag([0.5, 0.5, 0.5, 1.0])
    T[:3, 3] = [1.0, 2.0, 3.0]
    scene = trimesh.Scene()
    scene.add_geometry(cyl, transform=T)
    p = tmp_path / "c.glb"
    p.write_bytes(scene.export(file_type="glb"))
    V, F = read_surface(p)
    assert len(V) == len(cyl.vertices)  # the seams glTF may split are joined again
    assert np.allclose(V.min(axis=0), [1 - 0.5 * r, 2 - 0.5 * r, 3 - 0.25 * h], atol=1e-7)  # float32
    exact = 0.5 * n * r**2 * np.sin(2 * np.pi / n) * h * 0.125
    assert enclosed_volume(V, F) == pytest.approx(exact, rel=1e-6)  # float32 coordinates in the file


def test_a_broken_glb_is_refused_naming_it(tmp_path):
    p = tmp_path / "x.glb"
    p.write_bytes(b"glTF" + b"\x02\x00\x00\x00" + b"\xff" * 40)
    with pytest.raises(MeshError, match="x.glb: cannot read as a glTF surface"):
        read_surface(p)


def test_a_glb_scene_mesh_is_tetrahedralized(tmp_path):
    """A scene's [mesh] file in glTF is a surface, meshed like an .obj: a 10 × 5 × 2 cm box becomes
    tets filling its volume (fTetWild's envelope keeps the boundary within 1e-3 of the diagonal,
    so the volume within a few per mille)."""
    from pliant.scene import load_scene

    (tmp_path / "b.glb").write_bytes(trimesh.creation.box(extents=[0.1, 0.05, 0.02]).export(file_type="glb"))
    scene = tmp_path / "s.toml"
    scene.write_text(
        '[mesh]\nfile = "b.glb"\nedge_length = 0.01\n[[material]]\ntype = "neo-hookean"\nE = 1e3\n'
        "nu = 0.3\ndensity = 1000.0\n[solver]\nduration = 0.001\n"
    )
    b = load_scene(scene).builder
    X, T = b.nodes, b.tets
    e1, e2, e3 = (X[T[:, k]] - X[T[:, 0]] for k in (1, 2, 3))
    assert np.einsum("ij,ij->i", np.cross(e1, e2), e3).sum() / 6 == pytest.approx(1e-4, rel=5e-3)
