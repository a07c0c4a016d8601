"""Surface files written by other programs: ASCII STL (trimesh's writer, and the quirks of CAD
writers: keywords in capitals, CRLF, tabs, blank lines, polygons, several solids) and glTF 2.0
(trimesh's .glb, with a node's transform). References: the writer's own mesh, and closed forms of
the volume enclosed and of where a transform puts the vertices."""

import re

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


@pytest.mark.parametrize("cut", [-20, 50], ids=["truncated", "more-data"])
def test_binary_stl_of_the_wrong_size_is_refused_with_both_sizes(tmp_path, cut):
    """A binary STL is 84 bytes + 50 a facet its header counts (meshio said "UnicodeDecodeError")."""
    data = trimesh.creation.icosphere(subdivisions=1).export(file_type="stl")  # 80 facets: 4,084 bytes
    p = tmp_path / "b.stl"
    p.write_bytes(data[:cut] if cut < 0 else data + b"\0" * cut)
    with pytest.raises(MeshError, match=f"counts 80 facets is 4,084 bytes; this one is {4084 + cut:,}"):
        read_surface(p)


def test_binary_stl_is_the_writers_mesh(tmp_path):
    m = trimesh.creation.icosphere(subdivisions=2, radius=0.05)
    p = tmp_path / "b.stl"
    m.export(p, file_type="stl")
    V, F = read_surface(p)
    assert len(V) == len(m.vertices) and len(F) == len(m.faces)  # the corners joined
    assert np.allclose(V[F], m.vertices[m.faces], rtol=0, atol=1e-8)  # float32 in the file


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


def _split_first_vertex(text: str) -> str:
    """The first vertex line with its last number moved to a line of its own."""
    line = next(ln for ln in text.splitlines() if ln.strip().startswith("vertex"))
    return text.replace(line, "\n".join(line.rsplit(" ", 1)), 1)


@pytest.mark.parametrize(
    "damage, says",
    [
        (lambda t: t.replace("facet normal", "facett normal", 1), "ico.stl:2: unexpected 'facett'"),
        (lambda t: _split_first_vertex(t), "ico.stl:4: expected 'vertex x y z'"),
    ],
    ids=["first-facet", "vertex-over-two-lines"],
)
def test_trimeshs_ascii_stl_damaged_is_refused_naming_the_line(tmp_path, damage, says):
    """The bulk reader took words at their places: it dropped a first facet whose keyword was
    damaged, and read a vertex whose numbers ran over two lines. Both are read line by line now,
    and refused there, as every other damaged line."""
    m = trimesh.creation.icosphere(subdivisions=1, radius=0.05)
    p = tmp_path / "ico.stl"
    p.write_text(damage(trimesh.exchange.stl.export_stl_ascii(m)))
    with pytest.raises(MeshError, match=re.escape(says)):
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


def test_a_glb_index_beyond_its_vertices_is_refused_naming_it(tmp_path):
    """A glTF index accessor may name a vertex the file does not hold (found by changing single
    bytes of a .glb); trimesh, asked not to process the mesh, passes the index on, and the join of
    coincident vertices ended in numpy's IndexError. A .glb of one triangle (0, 1, 7) over 3
    vertices, written by trimesh."""
    bad = trimesh.Trimesh(np.eye(3), np.array([[0, 1, 7]]), process=False, validate=False)
    p = tmp_path / "oor.glb"
    p.write_bytes(bad.export(file_type="glb"))
    with pytest.raises(MeshError, match=r"oor.glb: face index out of range 0..2 \(a glTF index accessor\)"):
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


# --- PLY and OFF -------------------------------------------------------------------------------
CUBE = (
    np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]]) * 0.05
)
QUADS = [[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [2, 3, 7, 6], [0, 4, 7, 3], [1, 2, 6, 5]]  # outward


@pytest.mark.parametrize("colours", [True, False], ids=["face-colours", "plain"])
@pytest.mark.parametrize("encoding", ["binary", "ascii"])
def test_trimeshs_ply_is_its_mesh(tmp_path, encoding, colours):
    """trimesh's PLY: binary with a colour a face (meshio refused it: "buffer size must be a
    multiple of element size") or plain; ASCII plain (read in bulk) or with colours (record by
    record)."""
    m = trimesh.creation.icosphere(subdivisions=2, radius=0.05)
    if colours:
        m.visual.face_colors = [200, 30, 30, 255]
    p = tmp_path / "s.ply"
    m.export(p, encoding=encoding)
    V, F = read_surface(p)
    assert np.allclose(V[F], m.vertices[m.faces], rtol=0, atol=1e-8)  # the file's float32 corners
    assert enclosed_volume(V, F) == pytest.approx(m.volume, rel=1e-6)


def ply_text(faces=QUADS, vertices=len(CUBE), drop=0):
    """An ASCII PLY of the 5 cm cube in the specification's other type names (uint8, uint32,
    float64), a colour a vertex; its last ``drop`` lines cut."""
    head = (
        f"ply\nformat ascii 1.0\ncomment written by hand\nelement vertex {vertices}\nproperty float64 x\n"
        "property float64 y\nproperty float64 z\nproperty uint8 red\n"
        f"element face {len(faces)}\nproperty list uint8 uint32 vertex_indices\nend_header\n"
    )
    rows = [f"{x:g} {y:g} {z:g} 255" for x, y, z in CUBE] + [
        f"{len(q)} " + " ".join(map(str, q)) for q in faces
    ]
    return head + "\n".join(rows[: len(rows) - drop]) + "\n"


def test_ascii_ply_of_quads_in_the_specifications_type_names(tmp_path):
    """Six quads become twelve triangles enclosing the cube's 1.25e-4 m³ (meshio refused the type
    names: KeyError ('uint8', 'uint32'))."""
    p = tmp_path / "c.ply"
    p.write_text(ply_text())
    V, F = read_surface(p)
    assert len(F) == 12 and enclosed_volume(V, F) == pytest.approx(0.05**3, rel=1e-12)


@pytest.mark.parametrize(
    "text, says",
    [
        (ply_text(drop=2), "counts 8 vertex, 6 face records; the file holds 12 (truncated?)"),
        (ply_text(vertices=10**12), "counts 1,000,000,000,000 vertex, 6 face records; the file holds 14"),
        (ply_text() + "3 0 1 2\n", "the file holds 15 (more than it says)"),
        (ply_text(faces=[]), "8 vertices and 0 faces in its header; expected a surface"),
        (ply_text().replace("end_header", "end"), "has no end_header"),
        (ply_text().replace("ascii", "utf8"), "PLY format 'utf8'"),
        (ply_text(faces=[*QUADS[:5], [1, 2]]), "c.ply:25: a face of 2 vertices; expected 3 or more"),
        (
            ply_text().replace("4 0 3 2 1", "4 0 3 2 1.5"),
            "c.ply:20: face record '4 0 3 2 1.5' does not match",
        ),
        (ply_text().replace("property uint8 red\n", ""), "c.ply:11: vertex record '0 0 0 255' has values"),
        (ply_text().replace("uint8 uint32 vertex", "uint8 float32 vertex"), "vertex_indices of type float32"),
        (
            ply_text().replace("4 0 3 2 1", "4 0 3 2 99999999999999999999"),
            "c.ply:20: vertex index out of range 0..7",
        ),
    ],
    ids=[
        "truncated",
        "counts-too-many",
        "extra-record",
        "points-only",
        "no-end-header",
        "bad-format",
        "two-vertex-face",
        "fractional-index",
        "unnamed-value",
        "float-indices",
        "index-beyond-int64",
    ],
)
def test_malformed_ply_is_refused_naming_what_is_wrong(tmp_path, text, says):
    """trimesh alone read these as far as it could and said nothing: 7 of the 12 faces of a
    truncated box; a face of two vertices dropped; an index of 1.5 read as 1."""
    p = tmp_path / "c.ply"
    p.write_text(text)
    with pytest.raises(MeshError, match=re.escape(says)):
        read_surface(p)


def off_text(header="OFF", colours=True, drop=0):
    rows = [f"{x:g} {y:g} {z:g}" for x, y, z in CUBE]
    rows += [f"{len(q)} " + " ".join(map(str, q)) + (" 255 0 0" if colours else "") for q in QUADS]
    return (
        f"{header}\n# a comment\n\n{len(CUBE)} {len(QUADS)} 12\n" + "\n".join(rows[: len(rows) - drop]) + "\n"
    )


@pytest.mark.parametrize(
    "text",
    [
        off_text(),
        off_text(colours=False).replace("OFF\n# a comment\n\n8", "OFF 8"),  # counts on the header line
        off_text(colours=False).replace("OFF\n# a comment\n\n8", "OFF8"),  # glued, as ModelNet's files
        off_text(header="COFF", colours=False)
        .replace(" 0.05\n", " 0.05 255 0 0 255\n")
        .replace(" 0\n", " 0 9 9 9 9\n"),
        off_text(header="nOFF\n3"),
    ],
    ids=["face-colours", "counts-inline", "counts-glued", "coff", "noff"],
)
def test_off_variants_give_the_cube(tmp_path, text):
    """Quads with a colour after each face, COFF's colour after each vertex, the counts on the
    header's line: twelve triangles enclosing 1.25e-4 m³ (meshio refused all but plain triangles)."""
    p = tmp_path / "c.off"
    p.write_text(text)
    V, F = read_surface(p)
    assert len(V) == 8 and len(F) == 12
    assert enclosed_volume(V, F) == pytest.approx(0.05**3, rel=1e-12)


@pytest.mark.parametrize(
    "text, says",
    [
        (off_text(drop=3), "the file ends after 3 of its 6 faces (truncated?)"),
        (
            off_text().replace("8 6 12", "80000000000 6 12"),
            "the file ends after 14 of its 80,000,000,000 vertices",
        ),
        (off_text().replace("0.05 0 0", "0.05 zero 0"), "c.off:6: expected a vertex 'x y z'"),
        (off_text().replace("4 0 3 2 1", "4 0 3 2 8"), "c.off:13: vertex index out of range 0..7"),
        (off_text().replace("4 0 3 2 1", "2 0 3"), "c.off:13: a face of 2 vertices"),
        (off_text() + "1 2 3\n", "c.off:19: more data after the 8 vertices and 6 faces"),
        (off_text(header="OFF BINARY"), "binary OFF is not read"),
        (off_text(header="PLY"), "'PLY' is not an OFF header"),
        (
            off_text(colours=False).replace("4 0 3 2 1", "4 0 3 2 99999999999999999999"),
            "c.off:13: vertex index out of range 0..7",
        ),
    ],
    ids=[
        "truncated",
        "counts-too-many",
        "bad-vertex",
        "bad-index",
        "two-vertex-face",
        "extra",
        "binary",
        "not-off",
        "index-beyond-int64",
    ],
)
def test_malformed_off_is_refused_naming_the_line(tmp_path, text, says):
    p = tmp_path / "c.off"
    p.write_text(text)
    with pytest.raises(MeshError, match=re.escape(says)):
        read_surface(p)


TRIS = [[q[0], q[j], q[j + 1]] for q in QUADS for j in (1, 2)]
TRI_OFF = f"OFF\n{len(CUBE)} {len(TRIS)} 0\n" + "".join(f"{x:g} {y:g} {z:g}\n" for x, y, z in CUBE)
TRI_OFF += "".join(f"3 {a} {b} {c}\n" for a, b, c in TRIS)


@pytest.mark.parametrize(
    "suffix, text, says",
    [
        (".off", TRI_OFF.replace("0 0 0\n0.05 0 0", "0 0\n0 0.05 0 0"), "c.off:3: expected a vertex 'x y z'"),
        (".off", TRI_OFF.replace("3 0 3 2\n", "3 0 3\n2 "), "c.off:11: a face of 3 vertices with 2 given"),
        (
            ".ply",
            ply_text(faces=TRIS).replace("0 0 0 255\n0.05 0 0 255", "0 0 0\n255 0.05 0 0 255"),
            "c.ply:12: vertex record '0 0 0' does not match",
        ),
        (
            ".ply",
            ply_text(faces=TRIS).replace("0 0 0 255", "0 0 0 25.5"),
            "c.ply:12: vertex record '0 0 0 25.5' does not match",
        ),
    ],
    ids=["off-vertex-split", "off-face-split", "ply-vertex-split", "ply-fractional-uint8"],
)
def test_triangle_files_read_in_bulk_are_refused_by_the_line_at_fault(tmp_path, suffix, text, says):
    """The bulk parsers counted the numbers of a block: a vertex short of a value on one line and
    one with a value too many on the next read as two good vertices (shifted), and a fractional
    uint8 as a number. Each row is now checked to hold its words alone and of its type, and the
    file falls back to the line-by-line reader, which names the line."""
    p = tmp_path / f"c{suffix}"
    p.write_text(text)
    with pytest.raises(MeshError, match=re.escape(says)):
        read_surface(p)


def test_obj_lines_in_any_spacing(tmp_path):
    """Tab-separated and indented OBJ lines (the format separates by white space) were skipped:
    this unit tetrahedron read as one vertex. Its outward faces enclose 1/6 m³."""
    p = tmp_path / "t.obj"
    p.write_bytes(
        b"v\t0 0 0\r\nv\t1\t0\t0\r\n  v 0 1 0\r\nv 0 0 1\r\n"
        b"f\t1 3 2\r\n  f 1 2 4\r\n\tf 1/1/1 4/1/1 3/1/1\r\nf -3 -2 -1\r\n"
    )
    V, F = read_surface(p)
    assert len(V) == 4 and len(F) == 4 and enclosed_volume(V, F) == pytest.approx(1 / 6, rel=1e-15)


def test_join_coincident_is_numpys_unique_rows():
    """The corner joining of STL and glTF against np.unique(axis=0): the same vertices in the same
    order and the same renumbered faces, -0.0 and 0.0 one position."""
    from pliant.io.stl import join_coincident

    rng = np.random.default_rng(1)
    V = rng.integers(0, 5, size=(2000, 3)).astype(float)
    V[::7] *= -1.0  # -0.0 where a coordinate is 0
    F = rng.integers(0, 2000, size=(3000, 3))
    want, inv = np.unique(V, axis=0, return_inverse=True)
    got, G = join_coincident(V, F)
    assert np.array_equal(got, want) and np.array_equal(G, inv.reshape(-1)[F])


def test_a_repaired_surface_is_written_as_glb_and_read_back(tmp_path):
    """`pliant mesh repair IN OUT.glb` writes binary glTF (meshio writes none): the same triangles
    read back, to float32 (glTF stores positions as float32)."""
    from typer.testing import CliRunner

    from pliant.cli import app

    m = trimesh.creation.icosphere(subdivisions=2, radius=0.05)
    src, out = tmp_path / "s.obj", tmp_path / "r.glb"
    m.export(src)
    r = CliRunner().invoke(app, ["mesh", "repair", str(src), str(out)])
    assert r.exit_code == 0, r.output
    V, F = read_surface(out)
    W, G = read_surface(src)
    assert len(F) == len(G)
    assert triangles(np.float32(V).astype(float), F) == triangles(np.float32(W).astype(float), G)


def test_trimeshs_off_is_its_mesh_in_bulk_and_line_by_line(tmp_path):
    """A plain triangle OFF is parsed in bulk; a comment in it sends it line by line: both give
    the writer's mesh."""
    m = trimesh.creation.icosphere(subdivisions=2, radius=0.05)
    plain, commented = tmp_path / "s.off", tmp_path / "c.off"
    m.export(plain)
    text = plain.read_text().splitlines()
    commented.write_text("\n".join(text[:5] + ["# a comment among the vertices"] + text[5:]) + "\n")
    for p in (plain, commented):
        V, F = read_surface(p)
        # trimesh writes 10 decimals: within 5e-11 m
        assert np.allclose(V, m.vertices, rtol=0, atol=1e-10) and np.array_equal(F, m.faces)
