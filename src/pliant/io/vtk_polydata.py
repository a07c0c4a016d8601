"""Triangle surfaces from legacy VTK files of DATASET POLYDATA (the ``.vtk`` that VTK's
vtkPolyDataWriter, NiftySim's ``<VTKSurface>`` models, ITK-SNAP and 3D Slicer write), which meshio
does not read. ASCII and BINARY (big-endian), file versions 2.0 to 5.1 (5.1 stores each cell
section as OFFSETS and CONNECTIVITY arrays): POINTS, then VERTICES and LINES (skipped), POLYGONS
(fan-triangulated) and TRIANGLE_STRIPS (split into triangles, every other one reversed, so that all
keep the strip's orientation); FIELD and METADATA blocks skipped; POINT_DATA and CELL_DATA end the
read. Format: "VTK File Formats", The VTK User's Guide, 11th ed. (Kitware 2010), §19.3, and VTK 9's
vtkDataWriter for version 5.1."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import MeshError
from .vtk_legacy import cells, dataset_of, open_legacy, skip_field
from .vtk_legacy import points as read_points

__all__ = ["is_vtk_polydata", "read_vtk_polydata"]

_CELLS = ("VERTICES", "LINES", "POLYGONS", "TRIANGLE_STRIPS")
_END = ("POINT_DATA", "CELL_DATA")


def is_vtk_polydata(path) -> bool:
    """Whether ``path`` is a legacy VTK file whose dataset is POLYDATA (a surface), by its header."""
    return dataset_of(path) == "POLYDATA"


def _triangles(name: str, polys: list[np.ndarray]) -> list[tuple[int, int, int]]:
    """POLYGONS fanned from their first point; TRIANGLE_STRIPS with every other triangle reversed."""
    out = []
    for c in polys:
        for j in range(len(c) - 2):
            if name == "POLYGONS":
                out.append((c[0], c[j + 1], c[j + 2]))
            else:
                out.append((c[j], c[j + 1], c[j + 2]) if j % 2 == 0 else (c[j + 1], c[j], c[j + 2]))
    return out


def read_vtk_polydata(path) -> tuple[np.ndarray, np.ndarray]:
    """Vertices [file units] (V, 3) float64 and triangles (F, 3) int64 of a legacy VTK POLYDATA file.
    MeshError naming the file and line for anything malformed, truncated or not POLYDATA."""
    path = Path(path)
    r, binary, modern = open_legacy(path, "POLYDATA", "a surface")
    points, tris = None, []
    while (words := r.keyword_line()) is not None:
        key = words[0].upper()
        if key in _END:
            break
        if key == "METADATA":
            r.skip_metadata()
        elif key == "FIELD":
            skip_field(r, binary, words)
        elif key == "POINTS":
            points = read_points(r, binary, words)
        elif key in _CELLS:
            found = cells(r, binary, words, modern)
            if key in ("POLYGONS", "TRIANGLE_STRIPS"):
                tris += _triangles(key, found)
        else:
            raise r.fail(f"unknown section {words[0]!r} in a POLYDATA file")
    if points is None:
        raise MeshError(f"{path}: no POINTS section")
    if not tris:
        raise MeshError(f"{path}: no POLYGONS or TRIANGLE_STRIPS (a surface needs triangles)")
    return points, np.asarray(tris, dtype=np.int64).reshape(-1, 3)
