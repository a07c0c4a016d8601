"""Volume meshes from files (any format meshio reads: .vtu, .vtk, .msh, .mesh, .xdmf...)."""

from __future__ import annotations

import warnings
from functools import partial
from pathlib import Path
from typing import NamedTuple

import numpy as np

from ..errors import MeshError, PliantWarning
from ..mesh.split import SPLIT_CELLS, refine_tetra10, split_cells
from ..mesh.topology import CLOSE_FRACTION, coincident_nodes, drop_unused
from .vtk_grid import read_meshio_or_grid


# Cells of lower dimension that volume-mesh files carry beside their tets (boundary faces, edges,
# points): not simulated, and not an error.
SURFACE_CELLS = {"vertex", "line", "line3", "triangle", "triangle6", "quad", "quad8", "quad9"}
# Quadratic cells taken by their corners (VTK's order lists them first): kind → (linear kind, corners).
LINEARIZED = {
    "hexahedron20": ("hexahedron", 8),
    "hexahedron27": ("hexahedron", 8),
    "wedge15": ("wedge", 6),
    "wedge18": ("wedge", 6),
    "pyramid13": ("pyramid", 5),
    "pyramid14": ("pyramid", 5),
}
# Cells simulated: tetrahedra, and the cells split into them.
VOLUME_CELLS = {"tetra", "tetra10", *SPLIT_CELLS, *LINEARIZED}
# Nodes a cell (VTK's and meshio's cell types): the volume cells, and the surface cells surfaces take.
_CELL_NODES = {"tetra": 4, "tetra10": 10, "hexahedron": 8, "wedge": 6, "pyramid": 5}
_CELL_NODES |= {"hexahedron20": 20, "hexahedron27": 27, "wedge15": 15, "wedge18": 18, "pyramid13": 13}
_CELL_NODES |= {"pyramid14": 14, "triangle": 3, "quad": 4}


class VolumeMeshFile(NamedTuple):
    """A volume mesh file's contents (read_volume_mesh_file)."""

    nodes: np.ndarray  # [file units] (N, 3)
    tets: np.ndarray  # (M, 4): the file's tetrahedra and its other cells' (pliant.mesh.split), in file order
    element_sets: dict[str, np.ndarray]  # {name: tet indices}
    node_sets: dict[str, np.ndarray]  # {name: node indices}
    split: dict[str, int]  # {"hexahedron": cells, "tetra10": ...}: the file's cells split into tets


def read_volume_mesh(path) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
    """Read a volume mesh. Returns nodes [file units] (N, 3), tets (M, 4) and element sets
    {name: element indices} from cell data named like 'gmsh:physical' or 'CellEntityIds' (and a
    gmsh file's physical volumes by their names). Linear hexahedra, wedges and pyramids are split
    into tetrahedra (read_volume_mesh_file)."""
    return read_volume_mesh_file(path)[:3]


def read_volume_mesh_sets(
    path,
) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray], dict[str, np.ndarray]]:
    """read_volume_mesh's nodes, tets and element sets, and the file's node sets {name: node
    indices}: the nodes of its tagged lower-dimensional cells (triangles, quads, lines, vertices)
    by their tag, 'gmsh:physical=5', 'CellEntityIds=3', 'medit:ref=2', and a gmsh file's physical
    surfaces, curves and points by their names (a physical surface "fixed": the nodes of its
    triangles)."""
    return read_volume_mesh_file(path)[:4]


def read_volume_mesh_file(path) -> VolumeMeshFile:
    """read_volume_mesh_sets's nodes, tets, element sets and node sets, and how many of the file's
    cells of each kind were split into tetrahedra. A file's linear hexahedra, wedges and pyramids
    become 6, 3 and 2 tetrahedra each, conforming across shared faces (pliant.mesh.split); its
    quadratic tets (tetra10) the 8 linear ones through their mid-edge nodes; its quadratic
    hexahedra, wedges and pyramids (Abaqus C3D20, gmsh's incomplete order 2) are linearized, their
    mid-edge nodes dropped (and the nodes no element uses then left out, node sets renumbered),
    and split. An element set holds the tetrahedra of its cells. Other cells are refused by name."""
    path = Path(path)
    mesh = read_meshio_or_grid(path, "volume mesh")
    other = sorted({c.type for c in mesh.cells} - VOLUME_CELLS - SURFACE_CELLS)
    if other:
        counts = ", ".join(f"{sum(len(c.data) for c in mesh.cells if c.type == t)} {t}" for t in other)
        raise MeshError(
            f"{path}: has {counts} cells; pliant simulates linear tetrahedra (and splits "
            "hexahedra, wedges, pyramids and quadratic tets into them; convert the mesh, e.g. "
            "re-mesh its surface with pliant mesh tetrahedralize)"
        )
    blocks = [(i, c) for i, c in enumerate(mesh.cells) if c.type in VOLUME_CELLS]
    if not blocks:
        kinds = sorted({c.type for c in mesh.cells}) or ["none"]
        raise MeshError(
            f"{path}: no volume cells (cell types: {', '.join(kinds)}); expected 'tetra' cells (or "
            "linear hexahedra, wedges, pyramids; surface meshes go through the mesh pipeline)"
        )
    X = mesh_points(mesh, path)
    tets, owner, split = _volume_tets(path, mesh, X, blocks)
    sets = {
        k: np.nonzero(np.isin(owner, cells))[0]
        for k, cells in _element_sets(mesh, [i for i, _ in blocks]).items()
    }
    node_sets = _node_sets(mesh)
    if set(split) & set(LINEARIZED):  # mid-edge nodes dropped: keep the nodes the tets use
        X, tets, new = drop_unused(X, tets)  # indices checked
        node_sets = {k: new[v[new[v] >= 0]] for k, v in node_sets.items() if np.any(new[v] >= 0)}
    _warn_coincident(path, X, tets)
    return VolumeMeshFile(X, tets, sets, node_sets, split)


def _warn_coincident(path: Path, X: np.ndarray, tets: np.ndarray) -> None:
    """Warn of element nodes at another's position, or all but at it (topology.coincident_nodes):
    the elements on either side are not joined there, which a file written with one node per
    element corner does silently (every element then moves on its own)."""
    n, a, b, d = coincident_nodes(X, tets)
    if n:
        where = (
            "lie exactly where another node lies"
            if d == 0
            else f"lie where another node lies or closer to it than {CLOSE_FRACTION:.1%} of the "
            f"shortest element edge (up to {d:.3g} apart)"
        )
        warnings.warn(
            PliantWarning(
                f"{path}: {n} node(s) {where} (first: nodes {a} and {b} at {X[a].tolist()}), so the "
                "elements on either side are not joined there; merge duplicate nodes if the mesh is "
                "one body (separate bodies may touch this way)"
            ),
            stacklevel=3,
        )


def mesh_points(mesh, source) -> np.ndarray:
    """A meshio mesh's points as (N, 3) floats [file units] (2-D points get z = 0; a file without
    points gives none, and its cells then refer to nodes it lacks). MeshError naming ``source``
    for points of another shape, and the first node with a non-finite coordinate (a value beyond
    float64's range, "1e+900", reads as infinite)."""
    X = np.asarray(mesh.points if mesh.points is not None else np.zeros((0, 3)), dtype=float)
    if X.size == 0:
        return np.zeros((0, 3))
    if X.ndim != 2 or not 1 <= X.shape[1] <= 3:
        shape = f"points of shape {X.shape}" if X.ndim else "no points"
        raise MeshError(f"{source}: {shape}; expected (N, 3) node coordinates")
    if not np.all(np.isfinite(X)):
        node = int(np.argwhere(~np.isfinite(X))[0, 0])
        raise MeshError(
            f"{source}: node {node} has a non-finite coordinate {X[node].tolist()}; expected finite"
        )
    return np.pad(X, ((0, 0), (0, 3 - X.shape[1])))


def cell_array(source, block) -> np.ndarray:
    """A meshio cell block's (volume cells', triangles' or quads') node numbers (cells, nodes a
    cell) int64; an empty block as (0, nodes a cell). MeshError naming ``source`` for a block of
    another shape (meshio reads some truncated files into one)."""
    width = _CELL_NODES[block.type]
    try:
        data = np.asarray(block.data, np.int64)
    except (OverflowError, ValueError, TypeError) as e:  # meshio's Tecplot reader keeps Python ints
        raise MeshError(f"{source}: {block.type} node numbers unreadable ({e}); expected integers") from None
    if data.size == 0:
        return data.reshape(0, width)
    if data.ndim != 2 or data.shape[1] != width:
        raise MeshError(
            f"{source}: a block of {block.type} cells holds {data.size} node numbers in rows of "
            f"{data.shape[-1]}; expected {width} a cell (a truncated or malformed file?)"
        )
    return data


def _volume_tets(path: Path, mesh, X: np.ndarray, blocks):
    """The tetrahedra (M, 4) of the volume cell blocks in file order, the volume cell (numbered
    over the blocks) each comes from (M,), and the count of cells split per kind."""
    first = np.cumsum([0] + [len(c.data) for c in mesh.cells])  # a block's first cell in the file
    tets: list[np.ndarray] = []
    owner: list[np.ndarray] = []
    split: dict[str, int] = {}
    n = 0
    for i, c in blocks:
        data = cell_array(path, c)
        if data.size == 0:  # an empty block (an Abaqus *ELEMENT line with no elements after it)
            continue
        bad = np.nonzero(np.any((data < 0) | (data >= len(X)), axis=1))[0]
        if bad.size:  # meshio reads such files as they are
            k = int(bad[0])
            node = int(data[k][(data[k] < 0) | (data[k] >= len(X))][0])
            raise MeshError(
                f"{path}: cell {int(first[i]) + k} ({c.type}) refers to node {node}; the file has "
                f"{len(X)} nodes (expected 0 <= index < {len(X)})"
            )
        if c.type == "tetra":
            t, o = data.reshape(-1, 4), np.arange(len(data))
        else:
            kind, corners = LINEARIZED.get(c.type, (c.type, data.shape[1]))
            cut = refine_tetra10 if kind == "tetra10" else partial(split_cells, kind=kind)
            t, o = cut(X, cells=data[:, :corners], what=f"{path}: cell", first=int(first[i]))
            split[c.type] = split.get(c.type, 0) + len(data)
        tets.append(t)
        owner.append(o + n)
        n += len(data)
    if not tets:
        kinds = ", ".join(sorted({c.type for _, c in blocks}))
        raise MeshError(f"{path}: its {kinds} blocks hold no cells; expected at least one volume element")
    return np.concatenate(tets), np.concatenate(owner), split


def _element_sets(mesh, blocks: list[int]) -> dict[str, np.ndarray]:
    """{'KEY=v': element indices} from the tets' first cell data of KEY 'gmsh:physical',
    'CellEntityIds', 'medit:ref' or 'cell_sets'; and by their names, unless a name is taken, a gmsh
    file's named physical volumes and the file's named sets that hold tets (meshio's cell_sets: an
    Abaqus ELSET)."""
    sets: dict[str, np.ndarray] = {}
    for key in ("gmsh:physical", "CellEntityIds", "medit:ref", "cell_sets"):
        if key in mesh.cell_data:
            ids = np.concatenate([np.asarray(mesh.cell_data[key][i]).ravel() for i in blocks])
            for v in np.unique(ids):
                sets[f"{key}={int(v)}"] = np.nonzero(ids == v)[0]
            break
    for name, tag in _physical_names(mesh, lambda dim: dim == 3):
        if name not in sets and f"gmsh:physical={tag}" in sets:
            sets[name] = sets[f"gmsh:physical={tag}"]
    offsets = np.cumsum([0] + [len(mesh.cells[i].data) for i in blocks])
    for name, per_block in _named_sets(mesh):
        parts = [offsets[k] + np.asarray(per_block[i], np.int64) for k, i in enumerate(blocks)]
        tets = np.concatenate(parts) if parts else np.zeros(0, np.int64)
        if tets.size and name not in sets:
            sets[name] = np.unique(tets)
    return sets


def _physical_names(mesh, keep):
    """(name, tag) of a gmsh file's named physical groups ($PhysicalNames, meshio's field_data
    name → [tag, dimension]) whose dimension ``keep`` accepts."""
    for name, value in getattr(mesh, "field_data", {}).items():
        v = np.ravel(value)
        if v.size >= 2 and keep(int(v[1])):
            yield name, int(v[0])


def _named_sets(mesh):
    """(name, indices per cell block) of meshio's cell_sets (gmsh's internal ones left out)."""
    for name, per_block in getattr(mesh, "cell_sets", {}).items():
        if not name.startswith("gmsh:") and len(per_block) == len(mesh.cells):
            yield name, [np.zeros(0, np.int64) if b is None else np.asarray(b).ravel() for b in per_block]


def _node_sets(mesh) -> dict[str, np.ndarray]:
    """{'KEY=v': node indices} of the lower-dimensional cells tagged v in the first cell data of
    KEY 'gmsh:physical', 'CellEntityIds' or 'medit:ref'; and by their names, unless a name is
    taken, a gmsh file's named physical surfaces, curves and points, the nodes of the file's named
    sets of lower-dimensional cells (meshio's cell_sets) and its named node sets (point_sets: an
    Abaqus NSET)."""
    low = [i for i, c in enumerate(mesh.cells) if c.type in SURFACE_CELLS]
    sets: dict[str, np.ndarray] = {}
    for key in ("gmsh:physical", "CellEntityIds", "medit:ref") if low else ():
        if key not in mesh.cell_data:
            continue
        tagged: dict[int, list[np.ndarray]] = {}
        for i in low:
            ids = np.asarray(mesh.cell_data[key][i]).ravel()
            if len(ids) != len(mesh.cells[i].data):  # a tag per cell, or none for the block
                continue
            cells = np.asarray(mesh.cells[i].data).reshape(len(ids), -1)
            for v in np.unique(ids):
                tagged.setdefault(int(v), []).append(cells[ids == v].ravel())
        sets = {f"{key}={v}": np.unique(np.concatenate(c)).astype(np.int64) for v, c in tagged.items()}
        break
    for name, tag in _physical_names(mesh, lambda dim: dim < 3):
        if name not in sets and f"gmsh:physical={tag}" in sets:
            sets[name] = sets[f"gmsh:physical={tag}"]
    n = len(mesh.points)
    for name, per_block in _named_sets(mesh):
        parts = [np.asarray(mesh.cells[i].data)[per_block[i]].ravel() for i in low if per_block[i].size]
        if parts and name not in sets:
            sets[name] = np.unique(np.concatenate(parts)).astype(np.int64)
    for name, idx in getattr(mesh, "point_sets", {}).items():
        idx = np.unique(np.asarray(idx, np.int64).ravel())
        if idx.size and name not in sets and idx.min() >= 0 and idx.max() < n:
            sets[name] = idx
    return sets
