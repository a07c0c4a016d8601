"""Legacy VTK UNSTRUCTURED_GRID volume meshes that meshio refuses (pliant.io.vtk_grid): files VTK
9.3.1 itself wrote with point normals, texture coordinates and a field array beside the cells, and
malformed files refused by name (exit 2 on the CLI)."""

from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

import pliant as pl
from pliant.cli import app
from pliant.errors import MeshError
from pliant.io.files import read_meshio
from pliant.io.vtk_grid import is_vtk_grid, read_vtk_grid

DATA = Path(__file__).parent / "data"

# tests/data/README.md: vtkDelaunay3D of a vtkSphereSource (radius 2 cm, 12 × 8), with CELL_DATA
# CellEntityIds (1 where a tet's centroid has x < 0, else 2), POINT_DATA normals (the sphere
# source's), texture coordinates and a FIELD array; written by vtkUnstructuredGridWriter. The
# volumes are VTK's (vtkMeshQuality's tet volume, summed) over the same cells.
POINTS, TETS, REGION_1 = 74, 164, 82
VOLUME, VOLUME_1 = 3.041550458153816e-05, 1.520775229076908e-05


def _volumes(X, T):
    a, b, c, d = (X[T[:, i]] for i in range(4))
    return np.einsum("ij,ij->i", b - a, np.cross(c - a, d - a)) / 6


@pytest.mark.parametrize("name", ["vtk93_grid_bin51.vtk", "vtk93_grid_ascii42.vtk"])
def test_grids_vtk_wrote(name):
    """meshio stops at their NORMALS; they read as VTK reads them: its counts, its element sets,
    its volumes. 1e-12 relative for the binary file (its float32 coordinates are VTK's; the sums'
    order differs); 1e-5 for the ASCII one, whose 6 significant digits move each coordinate by up
    to 5e-7 of itself (the sphere's volume moves by 1.2e-6 of itself)."""
    path = DATA / name
    with pytest.raises(MeshError, match="NORMALS|decode"):
        read_meshio(path)
    assert is_vtk_grid(path)
    X, T, sets = pl.io.read_volume_mesh(path)
    assert X.shape == (POINTS, 3) and T.shape == (TETS, 4)
    assert len(sets["CellEntityIds=1"]) == REGION_1 and len(sets["CellEntityIds=2"]) == TETS - REGION_1
    v = _volumes(X, T)
    rel = 1e-12 if "bin" in name else 1e-5
    assert v.sum() == pytest.approx(VOLUME, rel=rel)
    assert v[sets["CellEntityIds=1"]].sum() == pytest.approx(VOLUME_1, rel=rel)
    assert np.all(X[T].mean(axis=1)[sets["CellEntityIds=1"], 0] < 0)


def test_a_vtk_grid_in_a_scene_is_checked_like_any_mesh(tmp_path):
    """A scene whose [mesh] file is such a grid reads it, and the model's checks see its cells:
    vtkDelaunay3D left flat slivers on the sphere's surface (volume ~1e-15 m³ for edges of 1 cm,
    min dihedral 1e-6°, `pliant mesh quality`), which the builder refuses by element, exit 2."""
    scene = tmp_path / "s.toml"
    scene.write_text(
        f'[mesh]\nfile = "{DATA / "vtk93_grid_bin51.vtk"}"\n'
        '[[material]]\ntype = "neo-hookean"\nE = 3000.0\nnu = 0.45\ndensity = 1000.0\n'
        "[solver]\nduration = 0.002\n"
        '[[constraint]]\ntype = "fix"\n'
        'nodes = { plane = { point = [0.0, 0.0, -0.015], normal = [0.0, 0.0, 1.0], side = "below" } }\n'
    )
    result = CliRunner().invoke(app, ["run", str(scene), "-o", str(tmp_path / "out")])
    assert result.exit_code == 2 and "vtk93_grid_bin51.vtk: element" in result.output
    assert "degenerate" in result.output and "Traceback" not in result.output


def _grid(tmp_path, cells: str, types: str, tail: str = "", points: str | None = None) -> Path:
    p = tmp_path / "g.vtk"
    pts = points or "POINTS 5 float\n0 0 0 1 0 0 0 1 0 0 0 1 1 1 1\n"
    p.write_text(
        "# vtk DataFile Version 4.2\ng\nASCII\nDATASET UNSTRUCTURED_GRID\n"
        + pts
        + cells
        + types
        + "POINT_DATA 5\nNORMALS n float\n"
        + "0 0 1 " * 5
        + "\n"
        + tail
    )
    return p


def test_a_hexahedron_is_split_and_a_quadratic_one_taken_by_its_corners(tmp_path):
    """A hexahedron beside a tet in such a file: split into 6 tets that fill the unit cube (closed
    form; pliant.mesh.split), the tet kept; a quadratic hexahedron (VTK type 25) is taken by its
    8 corners: the same 6 tets' volume."""
    cube = "POINTS 8 float\n0 0 0 1 0 0 1 1 0 0 1 0 0 0 1 1 0 1 1 1 1 0 1 1\n"
    head = "# vtk DataFile Version 4.2\nh\nASCII\nDATASET UNSTRUCTURED_GRID\n" + cube
    normals = "POINT_DATA 8\nNORMALS n float\n" + "0 0 1 " * 8 + "\n"
    p = tmp_path / "h.vtk"
    p.write_text(head + "CELLS 2 14\n8 0 1 2 3 4 5 6 7\n4 0 1 3 4\nCELL_TYPES 2\n12 10\n" + normals)
    X, T, _ = pl.io.read_volume_mesh(p)
    v = pl.mesh.primitives.tet_volumes(X, T)
    assert len(T) == 7 and v.min() > 0 and v[:6].sum() == pytest.approx(1.0, abs=1e-12)
    p.write_text(head + "CELLS 1 21\n20" + " 0 1 2 3 4 5 6 7 0 1" * 2 + "\nCELL_TYPES 1\n25\n" + normals)
    X, T, _ = pl.io.read_volume_mesh(p)
    v = pl.mesh.primitives.tet_volumes(X, T)
    assert len(T) == 6 and v.min() > 0 and v.sum() == pytest.approx(1.0, abs=1e-12)


@pytest.mark.parametrize(
    "cells, types, tail, says",
    [
        ("CELLS 1 5\n4 0 1 2 3\n", "CELL_TYPES 2\n10 10\n", "", "1 CELLS but 2 CELL_TYPES"),
        ("CELLS 1 5\n4 0 1 2 9\n", "CELL_TYPES 1\n10\n", "", "cell 0 refers to point 9"),
        ("CELLS 1 5\n4 0 1 2 3\n", "CELL_TYPES 1\n10\n", "WIBBLE w float\n", "unknown section 'WIBBLE'"),
        ("CELLS 1 5\n4 0 1 2 3\n", "CELL_TYPES 1\n10\n", "SCALARS s float\n1 2 3 4 5\n", "LOOKUP_TABLE"),
        ("CELLS 1 5\n4 0 1 2 3\n", "CELL_TYPES 1\n10\n", "VECTORS v float\n1 2 3\n", "VECTORS v: 15 values"),
        ("CELLS 2 5\n4 0 1 2 3\n", "CELL_TYPES 1\n10\n", "", "2 cells announced in 5 values"),
        ("", "CELL_TYPES 1\n10\n", "", "no CELLS section"),
        ("CELLS 1 4\n3 0 1 2\n", "CELL_TYPES 1\n10\n", "", "has 3 points; a tetra has 4"),
        ("CELLS 1 5\n4 0 1 2 3\n", "CELL_TYPES 1\n77\n", "", "VTK cell type 77"),
    ],
)
def test_malformed_grids_are_refused_naming_file_and_line(tmp_path, cells, types, tail, says):
    p = _grid(tmp_path, cells, types, tail)
    with pytest.raises(MeshError, match=says) as e:
        read_vtk_grid(p)
    assert str(p) in str(e.value)
    result = CliRunner().invoke(app, ["mesh", "quality", str(p)])
    assert result.exit_code == 2 and says.split(":")[0] in result.output and "Traceback" not in result.output


def test_non_finite_points_are_named(tmp_path):
    p = _grid(
        tmp_path,
        "CELLS 1 5\n4 0 1 2 3\n",
        "CELL_TYPES 1\n10\n",
        points="POINTS 5 float\n0 0 0 1 0 0 0 1 0 0 0 nan 1 1 1\n",
    )
    with pytest.raises(MeshError, match="point 3 is not finite"):
        read_vtk_grid(p)


def test_a_triangle_surface_in_such_a_grid_reads_as_a_surface():
    """A surface VTK wrote as an UNSTRUCTURED_GRID of triangles with point normals (vtkAppendFilter of
    a vtkSphereSource, radius 1 cm, 10 × 6): meshio refuses it; read_surface reads it as VTK does,
    its 42 points and 80 triangles, closed and outward, with VTK's volume and area
    (vtkMassProperties; 1e-5 relative: the ASCII file's 6 significant digits)."""
    path = DATA / "vtk93_sphere_surface_grid51.vtk"
    V, F = pl.mesh.read_surface(path)
    assert V.shape == (42, 3) and F.shape == (80, 3)
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    assert np.einsum("ij,ij->", a, np.cross(b, c)) / 6 == pytest.approx(3.544378528791399e-06, rel=1e-5)
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1).sum()
    assert area == pytest.approx(0.0011558783754087505, rel=1e-5)
    report = pl.mesh.check_surface(V, F)
    assert report.watertight and report.outward and not report.problems
