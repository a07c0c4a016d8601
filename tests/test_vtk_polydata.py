"""Legacy VTK POLYDATA surfaces (pliant.io.vtk_polydata): NiftySim's own files, files VTK 9.3.1
wrote, binary and version 5.1 files written here byte by byte from the format's description (The
VTK User's Guide, §19.3; VTK 9's vtkDataWriter for OFFSETS / CONNECTIVITY), and malformed files
refused by name."""

import math
import struct
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

import pliant as pl
from pliant.cli import app
from pliant.errors import MeshError
from pliant.io.vtk_polydata import is_vtk_polydata, read_vtk_polydata
from pliant.scene import load_scene

DATA = Path(__file__).parent / "data"


def test_niftysims_sphere_surface():
    """NiftySim's sphere_surface.vtk: an icosphere of 3 subdivisions has 10·4³ + 2 vertices and
    20·4³ triangles, all vertices at radius 1 (the file's 6 digits: 1e-5), closed, outward; an
    inscribed polyhedron of that fineness holds 98–100 % of the ball's volume (level 3: about 98.8 %)."""
    V, F = pl.mesh.read_surface(DATA / "niftysim_sphere_surface.vtk")
    assert V.shape == (10 * 4**3 + 2, 3) and F.shape == (20 * 4**3, 3)
    np.testing.assert_allclose(np.linalg.norm(V, axis=1), 1.0, atol=1e-5)
    report = pl.mesh.check_surface(V, F)
    assert report.watertight and report.outward and not report.problems
    assert 0.98 < report.volume / (4 / 3 * math.pi) < 1.0


def test_niftysims_box_surface():
    """NiftySim's box_surface.vtk (a contact surface of its models): the unit cube about the
    origin, closed, volume 1 (exact for any triangulation of the cube's faces)."""
    assert is_vtk_polydata(DATA / "niftysim_box_surface.vtk")
    assert not is_vtk_polydata(DATA / "niftysim_sphere.vtk")  # an UNSTRUCTURED_GRID (meshio's)
    V, F = pl.mesh.read_surface(DATA / "niftysim_box_surface.vtk")
    np.testing.assert_array_equal(V.min(axis=0), -0.5)
    np.testing.assert_array_equal(V.max(axis=0), 0.5)
    report = pl.mesh.check_surface(V, F)
    assert report.watertight and report.outward
    assert report.volume == pytest.approx(1.0, rel=1e-6)  # float32 coordinates of ±0.5: exact


# Written by VTK 9.3.1's vtkPolyDataWriter (tests/data/README.md): a vtkSphereSource (radius 2 cm,
# 16 × 12) as triangles in a binary version 4.2 file, and through vtkStripper as triangle strips
# in a binary version 5.1 file (OFFSETS / CONNECTIVITY of vtktypeint64); a vtkCubeSource of 3 × 2 ×
# 1 cm as six quads in an ASCII version 4.2 file with normals and texture coordinates. Volume and
# area from VTK's vtkMassProperties over its vtkTriangleFilter's triangles of the same data.
VTK_SPHERE = (162, 320, 3.1994260657508096e-05, 0.004911717311496176)
VTK_BOX = (24, 12, 5.999999597668654e-06, 0.002199999901652337)


def _volume_area(V, F):
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    return np.einsum("ij,ij->", a, np.cross(b, c)) / 6, 0.5 * np.linalg.norm(
        np.cross(b - a, c - a), axis=1
    ).sum()


def _oriented(F):
    """Each triangle as its vertex cycle started at its smallest index: orientation kept."""
    return {tuple(np.roll(f, -int(np.argmin(f)))) for f in F.tolist()}


@pytest.mark.parametrize(
    "name, counts",
    [
        ("vtk93_sphere_bin42.vtk", VTK_SPHERE),
        ("vtk93_sphere_strips_bin51.vtk", VTK_SPHERE),
        ("vtk93_box_quads_ascii42.vtk", VTK_BOX),
    ],
)
def test_files_vtk_wrote(name, counts):
    """Files VTK itself wrote read as VTK reads them: its point and triangle counts, and its
    volume and area (positive volume: outward, the strips' alternate triangles turned back). 1e-9
    relative: the binary files' float32 coordinates are what VTK summed in another order; the
    ASCII file's text holds the box's corners exactly (±0.015, ±0.01, ±0.005), VTK's float32 not."""
    n_points, n_triangles, volume, area = counts
    V, F = pl.mesh.read_surface(DATA / name)
    assert V.shape == (n_points, 3) and F.shape == (n_triangles, 3)
    vol, ar = _volume_area(V, F)
    rel = 1e-9 if "bin" in name else 1e-7
    assert vol == pytest.approx(volume, rel=rel) and ar == pytest.approx(area, rel=rel)
    if "box" in name:  # VTK writes each face with its own 4 corners (for its normals): 6 bodies
        assert pl.mesh.check_surface(V, F).bodies == 6
        V, F = pl.mesh.repair_surface(V, F)[:2]  # welded: the closed box
    report = pl.mesh.check_surface(V, F)
    assert report.watertight and report.outward and not report.problems


def test_vtks_strips_are_its_triangles():
    """vtkStripper's strips of the sphere are the sphere's own triangles, each in its orientation."""
    _, F = read_vtk_polydata(DATA / "vtk93_sphere_bin42.vtk")
    _, S = read_vtk_polydata(DATA / "vtk93_sphere_strips_bin51.vtk")
    assert _oriented(S) == _oriented(F)


# A unit right tetrahedron's four outward faces, a square (as one quad polygon) and a strip.
TET_POINTS = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
TET_FACES = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]


def _binary_file(path: Path, point_type="float", extra_before_points=b"") -> None:
    """Version 3.0, BINARY: big-endian arrays, each followed by a newline (vtkDataWriter)."""
    f = point_type == "double" and ">d" or ">f"
    out = [b"# vtk DataFile Version 3.0\nwritten by hand\nBINARY\nDATASET POLYDATA\n", extra_before_points]
    pts = TET_POINTS + [(2, 0, 0), (3, 0, 0), (3, 1, 0), (2, 1, 0)]
    out.append(f"POINTS {len(pts)} {point_type}\n".encode())
    out.append(b"".join(struct.pack(f, c) for p in pts for c in p) + b"\n")
    out.append(b"METADATA\nINFORMATION 0\n\n")
    out.append(b"LINES 1 3\n" + struct.pack(">3i", 2, 0, 1) + b"\n")  # skipped: not a surface
    polys = [(3, *t) for t in TET_FACES] + [(4, 4, 5, 6, 7)]
    size = sum(len(p) for p in polys)
    out.append(f"POLYGONS {len(polys)} {size}\n".encode())
    out.append(b"".join(struct.pack(">i", v) for p in polys for v in p) + b"\n")
    out.append(b"TRIANGLE_STRIPS 1 5\n" + struct.pack(">5i", 4, 4, 5, 7, 6) + b"\n")
    out.append(
        b"POINT_DATA 8\nSCALARS s float 1\nLOOKUP_TABLE default\n" + struct.pack(">8f", *range(8)) + b"\n"
    )
    path.write_bytes(b"".join(out))


def test_binary_file_with_every_section(tmp_path):
    """Points as float and as double; a quad polygon fanned from its first point; a strip's second
    triangle reversed to keep the strip's orientation; LINES, METADATA, a FIELD block before POINTS
    and the POINT_DATA after the cells skipped."""
    field = b"FIELD FieldData 1\nlabels 1 2 int\n" + struct.pack(">2i", 7, 9) + b"\n"
    for point_type in ("float", "double"):
        p = tmp_path / f"s_{point_type}.vtk"
        _binary_file(p, point_type, field)
        V, F = read_vtk_polydata(p)
        assert V.shape == (8, 3) and V.dtype == np.float64
        np.testing.assert_array_equal(V[:4], TET_POINTS)
        expect = TET_FACES + [(4, 5, 6), (4, 6, 7)] + [(4, 5, 7), (7, 5, 6)]
        np.testing.assert_array_equal(F, expect)
        # the four faces alone close the tetrahedron: volume 1/6
        assert pl.mesh.check_surface(V[:4], F[:4]).volume == pytest.approx(1 / 6)


def test_version_5_1_offsets_and_connectivity(tmp_path):
    """VTK 9's layout: a cell section's counts are its offsets (cells + 1) and its connectivity."""
    conn = [i for t in TET_FACES for i in t]
    text = (
        "# vtk DataFile Version 5.1\nvtk output\nASCII\nDATASET POLYDATA\n"
        "POINTS 4 float\n" + " ".join(str(c) for p in TET_POINTS for c in p) + "\n\n"
        "POLYGONS 5 12\nOFFSETS vtktypeint64\n0 3 6 9 12\nCONNECTIVITY vtktypeint64\n"
        + " ".join(map(str, conn))
        + "\nCELL_DATA 4\n"
    )
    p = tmp_path / "v51.vtk"
    p.write_text(text)
    V, F = pl.mesh.read_surface(p)
    np.testing.assert_array_equal(F, TET_FACES)
    assert pl.mesh.check_surface(V, F).volume == pytest.approx(1 / 6)


def _ascii(body: str) -> str:
    return "# vtk DataFile Version 3.0\nt\nASCII\nDATASET POLYDATA\n" + body


@pytest.mark.parametrize(
    "body, says",
    [
        ("POINTS 4 float\n0 0 0 1 0 0 0 1 0\n", ":6: POINTS: 12 values announced, the file has 18 bytes"),
        ("POINTS 4 float\n0 0 0 1 0 0 0 1 0" + " " * 40 + "\n", "12 values announced, the file ends after 9"),
        ("POINTS 99999999999 float\n0 0 0\n", "299999999997 values announced, the file has 6 bytes"),
        ("POINTS 1 float\n0 0 zero\nPOLYGONS 1 4\n3 0 0 0\n", "POINTS: a value that is not a number"),
        ("POINTS 1 quaternion\n0 0 0\n", "data type 'quaternion'"),
        ("POINTS 3 float\n0 0 0 1 0 0 0 1 0\nPOLYGONS 2 4\n3 0 1 2\n", "2 cells announced in 4 values"),
        (
            "POINTS 3 float\n0 0 0 1 0 0 0 1 0\nPOLYGONS 1 5\n3 0 1 2 9\n",
            "5 values announced, the 1 cells take 4",
        ),
        ("POINTS 3 float\n0 0 0 1 0 0 0 1 0\nLINES 1 3\n2 0 1\n", "no POLYGONS or TRIANGLE_STRIPS"),
        ("POINTS 3 float\n0 0 0 1 0 0 0 1 0\nVOXELS 1 2\n", "unknown section 'VOXELS'"),
        ("POLYGONS 1 4\n3 0 1 2\n", "no POINTS section"),
        ("POINTS 3 float\n0 0 0 1 0 0 0 1 0\nPOLYGONS 1 4\n3 0 1 7\n", "face index out of range"),
        ("POINTS 3 float\n0 0 0 1 0 nan 0 1 0\nPOLYGONS 1 4\n3 0 1 2\n", "non-finite vertex"),
    ],
)
def test_malformed_files_are_refused_naming_file_and_line(tmp_path, body, says):
    p = tmp_path / "bad.vtk"
    p.write_text(_ascii(body))
    with pytest.raises(MeshError, match="bad.vtk") as e:
        pl.mesh.read_surface(p)
    assert says in str(e.value)
    r = CliRunner().invoke(app, ["mesh", "check", str(p)])
    assert r.exit_code == 2 and says in r.output and "Traceback" not in r.output


def test_xml_polydata_is_named_as_not_read(tmp_path):
    p = tmp_path / "s.vtp"
    p.write_text('<VTKFile type="PolyData"></VTKFile>')
    with pytest.raises(
        MeshError, match=r"s.vtp: VTK XML PolyData \(.vtp\) is not read; expected a legacy .vtk"
    ):
        pl.mesh.read_surface(p)


@pytest.mark.parametrize("keep", [30, 83, 1])
def test_truncated_binary_file(tmp_path, keep):
    """The POLYGONS' 21 values (84 bytes) cut after ``keep`` bytes of the section: 83, one byte
    short, once read past the end (fuzzing found it)."""
    p = tmp_path / "cut.vtk"
    _binary_file(p)
    data = p.read_bytes()
    start = data.index(b"\n", data.index(b"POLYGONS")) + 1
    p.write_bytes(data[: start + keep])
    with pytest.raises(
        MeshError, match=rf"cut.vtk:\d+: POLYGONS: 21 values announced, the file has {keep} bytes left"
    ):
        read_vtk_polydata(p)


def test_a_polydata_scene_mesh_is_tetrahedralized(tmp_path):
    """A scene's [mesh] file in VTK POLYDATA is a surface, meshed like an .obj: NiftySim's unit box
    becomes tets filling its volume (1 m³; fTetWild's envelope keeps the boundary within 1e-3 of
    the diagonal, so the volume within a few per mille)."""
    scene = tmp_path / "box.toml"
    src = (DATA / "niftysim_box_surface.vtk").resolve()
    scene.write_text(
        f'[mesh]\nfile = "{src}"\nedge_length = 0.25\n[[material]]\ntype = "neo-hookean"\nE = 1e3\n'
        "nu = 0.3\ndensity = 1000.0\n[solver]\nduration = 0.001\n"
    )
    model = load_scene(scene).builder
    X, T = model.nodes, model.tets
    e1, e2, e3 = (X[T[:, k]] - X[T[:, 0]] for k in (1, 2, 3))
    volume = np.einsum("ij,ij->i", np.cross(e1, e2), e3).sum() / 6
    assert volume == pytest.approx(1.0, rel=5e-3)


def test_a_signalling_nan_point_is_refused_without_a_numpy_warning(tmp_path):
    """A binary float whose bits are a signalling NaN made numpy print "RuntimeWarning: invalid
    value encountered in cast" (found by fuzzing) before the refusal of the non-finite point; the
    refusal alone is shown now."""
    import warnings

    p = tmp_path / "snan.vtk"
    _binary_file(p)
    data = p.read_bytes()
    first = data.index(b"POINTS 8 float\n") + len(b"POINTS 8 float\n")
    p.write_bytes(data[:first] + struct.pack(">I", 0x7FA00000) + data[first + 4 :])  # point 0's x
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(MeshError, match="non-finite vertex"):
            pl.mesh.read_surface(p)
