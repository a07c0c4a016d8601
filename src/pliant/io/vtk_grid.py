"""Volume meshes from legacy VTK files of DATASET UNSTRUCTURED_GRID that meshio refuses: meshio's
reader stops at point and cell attributes it does not know (NORMALS, TEXTURE_COORDINATES,
COLOR_SCALARS, GLOBAL_IDS...), which VTK's own writers emit, e.g. a vtkDelaunay3D mesh keeps its
input surface's normals. This reader takes the geometry (POINTS, CELLS, CELL_TYPES; ASCII or
BINARY, versions 2.0 to 5.1) and the one-component SCALARS of CELL_DATA (element sets such as
CellEntityIds), and skips every other attribute by its size. Format: "VTK File Formats", The VTK
User's Guide, 11th ed. (Kitware 2010), §19.3, and VTK 9's vtkDataWriter for version 5.1."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import MeshError
from .vtk_legacy import Reader, cells, count, dataset_of, open_legacy, skip_field
from .vtk_legacy import points as read_points

__all__ = ["is_vtk_grid", "read_vtk_grid", "read_meshio_or_grid"]

# VTK cell type ids → meshio's names and their point counts (vtkCellType.h).
CELL_NAMES = {
    1: ("vertex", 1),
    3: ("line", 2),
    5: ("triangle", 3),
    9: ("quad", 4),
    10: ("tetra", 4),
    12: ("hexahedron", 8),
    13: ("wedge", 6),
    14: ("pyramid", 5),
    21: ("line3", 3),
    22: ("triangle6", 6),
    23: ("quad8", 8),
    24: ("tetra10", 10),
    25: ("hexahedron20", 20),
    28: ("quad9", 9),
}

# Attribute sections of a fixed number of values a tuple, their header 'KEY name type'.
_FIXED = {"VECTORS": 3, "NORMALS": 3, "TENSORS": 9, "TENSORS6": 6, "GLOBAL_IDS": 1, "PEDIGREE_IDS": 1}


def is_vtk_grid(path) -> bool:
    """Whether ``path`` is a legacy VTK file whose dataset is UNSTRUCTURED_GRID, by its header."""
    return dataset_of(path) == "UNSTRUCTURED_GRID"


def _attribute(r: Reader, binary: bool, words: list[str], n: int) -> tuple[str, np.ndarray] | None:
    """One attribute section of n tuples, read past; (name, values) for a one-component SCALARS."""
    key = words[0].upper()
    if len(words) < 3:
        raise r.fail(f"{key}: expected '{key} name ...' with its type or size")
    name = words[1]
    if key == "SCALARS":
        comps = count(r, words[3], key) if len(words) > 3 else 1
        table = r.keyword_line()
        if not table or table[0].upper() != "LOOKUP_TABLE":
            raise r.fail(f"SCALARS {name}: expected 'LOOKUP_TABLE name' after it")
        values = r.array(binary, n * comps, words[2], f"SCALARS {name}")
        return (name, values) if comps == 1 else None
    if key in _FIXED:
        r.array(binary, _FIXED[key] * n, words[2], f"{key} {name}")
    elif key == "TEXTURE_COORDINATES":
        if len(words) < 4:
            raise r.fail("TEXTURE_COORDINATES: expected 'TEXTURE_COORDINATES name dim type'")
        r.array(binary, count(r, words[2], key) * n, words[3], f"{key} {name}")
    elif key == "COLOR_SCALARS":  # bytes when binary, numbers in [0, 1] as text
        r.array(binary, count(r, words[2], key) * n, "unsigned_char" if binary else "float", f"{key} {name}")
    elif key == "LOOKUP_TABLE":  # a table of RGBA colours, the same encoding
        r.array(binary, 4 * count(r, words[2], key), "unsigned_char" if binary else "float", f"{key} {name}")
    else:
        raise r.fail(f"unknown section {words[0]!r} in an UNSTRUCTURED_GRID file")
    return None


def _blocks(found: list[np.ndarray], types: np.ndarray):
    """The cells as meshio's blocks: runs of one type, each an (n, points) array. Returns
    [(name, data)] and each run's (begin, end)."""
    blocks, spans, k = [], [], 0
    while k < len(found):
        j = k
        while j < len(found) and types[j] == types[k]:
            j += 1
        name, m = CELL_NAMES[int(types[k])]
        blocks.append((name, np.array(found[k:j], dtype=np.int64).reshape(j - k, m)))
        spans.append((k, j))
        k = j
    return blocks, spans


def read_vtk_grid(path):
    """A legacy VTK UNSTRUCTURED_GRID file as a meshio.Mesh: points [file units] (N, 3), its cells
    in runs of one type, and each one-component CELL_DATA SCALARS as cell data. MeshError naming
    the file and line for anything malformed or truncated."""
    import meshio

    path = Path(path)
    r, binary, modern = open_legacy(path, "UNSTRUCTURED_GRID", "a volume mesh")
    points, found, types, scalars, n_data, in_cells = None, None, None, {}, 0, False
    while (words := r.keyword_line()) is not None:
        key = words[0].upper()
        if key == "METADATA":
            r.skip_metadata()
        elif key == "FIELD":
            skip_field(r, binary, words)
        elif key in ("POINT_DATA", "CELL_DATA"):
            if len(words) < 2:
                raise r.fail(f"{key}: expected '{key} n'")
            n_data, in_cells = count(r, words[1], key), key == "CELL_DATA"
        elif key == "POINTS":
            points = read_points(r, binary, words)
        elif key == "CELLS":
            found = cells(r, binary, words, modern)
        elif key == "CELL_TYPES":
            types = r.array(binary, count(r, words[1] if len(words) > 1 else "", key), "int", key)
        else:
            got = _attribute(r, binary, words, n_data)
            if got and in_cells:
                scalars[got[0]] = got[1]
    if points is None or found is None or types is None:
        missing = [s for s, v in (("POINTS", points), ("CELLS", found), ("CELL_TYPES", types)) if v is None]
        raise MeshError(f"{path}: no {' or '.join(missing)} section")
    if len(types) != len(found):
        raise MeshError(f"{path}: {len(found)} CELLS but {len(types)} CELL_TYPES")
    if not np.all(np.isfinite(points)):
        raise MeshError(f"{path}: POINTS: point {int(np.nonzero(~np.isfinite(points))[0][0])} is not finite")
    for k, (c, t) in enumerate(zip(found, types)):
        if len(c) and (c.min() < 0 or c.max() >= len(points)):
            bad = int(c[(c < 0) | (c >= len(points))][0])
            raise MeshError(
                f"{path}: CELLS: cell {k} refers to point {bad}; the file has {len(points)} points"
            )
        if int(t) not in CELL_NAMES:
            kinds = ", ".join(f"{i} ({n})" for i, (n, _) in CELL_NAMES.items())
            raise MeshError(
                f"{path}: CELL_TYPES: cell {k} has VTK cell type {int(t)}; expected one of {kinds}"
            )
        name, m = CELL_NAMES[int(t)]
        if len(c) != m:
            raise MeshError(f"{path}: CELLS: cell {k} ({name}) has {len(c)} points; a {name} has {m}")
    blocks, spans = _blocks(found, types)
    cell_data = {name: [v[b:e] for b, e in spans] for name, v in scalars.items() if len(v) == len(found)}
    return meshio.Mesh(points, blocks, cell_data=cell_data)


def read_meshio_or_grid(path, what: str):
    """meshio.read(path) (read_meshio: failures as a MeshError naming the file), and where meshio
    fails on a legacy VTK UNSTRUCTURED_GRID, read_vtk_grid. what: the mesh's kind, for the error."""
    from .files import read_meshio

    try:
        return read_meshio(path, what)
    except MeshError:
        if not is_vtk_grid(path):
            raise
        return read_vtk_grid(path)  # a legacy VTK grid with attributes meshio does not know
