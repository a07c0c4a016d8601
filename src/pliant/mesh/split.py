"""Linear hexahedra, wedges and pyramids split into tetrahedra, conforming across shared faces.

pliant's element is the linear tetrahedron. A cell with quadrilateral faces is split by the
*pulling* triangulation from its vertex of smallest global index v (De Loera, Rambau & Santos,
"Triangulations", Springer 2010, §4.3.2): one tetrahedron (v, a, b, c) for every triangle abc of
the faces that do not contain v, each quadrilateral face cut along its diagonal through the face's
vertex of smallest global index (Dompierre, Labbé, Vallet & Camarero 1999, "How to subdivide
pyramids, prisms and hexahedra into tetrahedra", 8th International Meshing Roundtable). The faces
that contain v are cut through v, which is their smallest vertex too, so every quadrilateral is
cut by the same rule from both cells that share it: the tetrahedra of neighbouring cells meet on
whole triangles, and a tetrahedron beside the cell meets its triangular faces as before. A
hexahedron gives 6 tetrahedra, a wedge 3, a pyramid 2; a cell with repeated nodes (a wedge written
as a hexahedron) drops the tetrahedra those make flat. For a convex cell every tetrahedron of the
cone lies inside it with one orientation; a cell whose tetrahedra disagree in sign or have no
volume is too distorted to split and is named in the error.

Node orders are VTK's (meshio's, NiftySim's H8: the bottom face 0-1-2-3, then the top face 4-7
above it; a wedge's triangles 0-1-2 and 3-4-5; a pyramid's base 0-1-2-3 and apex 4); either
orientation of a cell is accepted and its tetrahedra come out positive."""

from __future__ import annotations

import numpy as np

from ..checks import real_array, shown
from ..errors import MeshError
from .primitives import tet_volumes

__all__ = ["SPLIT_CELLS", "refine_tetra10", "split_cells", "split_quads"]

# Faces of each cell kind by local node, wound outward for VTK's node order (a cell given in the
# mirrored order has them all wound inward, and its tetrahedra all negative until turned over).
SPLIT_CELLS: dict[str, tuple[int, tuple[tuple[int, ...], ...]]] = {
    "hexahedron": (
        8,
        ((0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)),
    ),
    "wedge": (6, ((0, 1, 2), (3, 5, 4), (0, 3, 4, 1), (1, 4, 5, 2), (2, 5, 3, 0))),
    "pyramid": (5, ((0, 3, 2, 1), (0, 1, 4), (1, 2, 4), (2, 3, 4), (3, 0, 4))),
}


def split_cells(
    nodes: np.ndarray, kind: str, cells: np.ndarray, what: str = "cell", first: int = 0
) -> tuple[np.ndarray, np.ndarray]:
    """Tetrahedra of linear cells of one ``kind`` ("hexahedron", "wedge", "pyramid"; node orders in
    the module's docstring). nodes [m] (N, 3), cells (M, n) node indices. Returns positively oriented
    tets (K, 4), in cell order, and the cell of each (K,). Raises MeshError naming the first cell
    (``what`` first + k) whose tetrahedra are flat or of mixed orientation."""
    n, faces = SPLIT_CELLS[kind]
    C = np.asarray(cells, np.int64).reshape(-1, n)
    v = C.min(axis=1)
    parts, owners, order = [], [], []
    for f, face in enumerate(faces):
        F = C[:, face]
        keep = ~np.any(F == v[:, None], axis=1)  # faces through v add nothing to the cone
        for t, tri in enumerate(_triangles(F)):
            ok = keep & (tri[:, 0] != tri[:, 1]) & (tri[:, 1] != tri[:, 2]) & (tri[:, 2] != tri[:, 0])
            rows = np.nonzero(ok)[0]
            parts.append(np.column_stack([v[rows], tri[rows]]))
            owners.append(rows)
            order.append(np.full(rows.size, 2 * f + t))
    owner = np.concatenate(owners)
    rank = np.lexsort((np.concatenate(order), owner))  # cell by cell, faces in their listed order
    tets, owner = np.concatenate(parts)[rank], owner[rank]
    if C.size and (C.min() < 0 or C.max() >= len(nodes)):
        return tets, owner  # indices beyond the nodes: the mesh's own check names them
    vol = tet_volumes(nodes, tets)
    _check_cells(vol, C, owner, kind, what, first)
    flip = vol < 0
    tets[flip, 2], tets[flip, 3] = tets[flip, 3].copy(), tets[flip, 2].copy()
    return tets, owner


def split_quads(Q: np.ndarray) -> np.ndarray:
    """Triangles (2 F, 3) of quadrilaterals Q (F, 4), each cut along its diagonal through its
    smallest node as split_cells cuts the faces of cells (in their winding; two a quad, in order)."""
    a = real_array(Q)
    if a is None or a.ndim != 2 or a.shape[1] != 4 or not np.all(a >= 0) or not np.all(np.mod(a, 1) == 0):
        raise MeshError(f"split_quads: quads = {shown(Q)}; expected an (F, 4) array of node indices >= 0")
    t1, t2 = _triangles(a.astype(np.int64))
    return np.stack([t1, t2], axis=1).reshape(-1, 3)


def _triangles(F: np.ndarray) -> tuple[np.ndarray, ...]:
    """A face's triangles (rows of F, (M, 3) or (M, 4)): a quadrilateral a-b-c-d cut along a–c
    where a or c is its smallest node, else along b–d."""
    if F.shape[1] == 3:
        return (F,)
    a, b, c, d = F.T
    through_ac = np.minimum(a, c) < np.minimum(b, d)
    t1 = np.where(through_ac[:, None], np.column_stack([a, b, c]), np.column_stack([b, c, d]))
    t2 = np.where(through_ac[:, None], np.column_stack([a, c, d]), np.column_stack([b, d, a]))
    return t1, t2


def _check_cells(vol: np.ndarray, C: np.ndarray, owner: np.ndarray, kind: str, what: str, first: int) -> None:
    """MeshError naming the first cell C[k] with no tetrahedron, a flat one, or tetrahedra of both
    orientations (a cell too distorted, or not convex enough, to be split), from the signed volumes
    ``vol`` of its tets (``owner``: the cell of each, sorted). Non-finite coordinates are left to
    the mesh's own checks, which name them."""
    m = len(C)
    count = np.bincount(owner, minlength=m)
    has = count > 0
    starts = np.cumsum(count) - count  # owner is sorted: each cell's tets are one run
    scale = np.zeros(m)
    if has.any():
        scale[has] = np.maximum.reduceat(np.abs(vol), starts[has])
    pos = np.bincount(owner, weights=(vol > 0).astype(float), minlength=m)
    flat = np.bincount(owner, weights=~(np.abs(vol) > 1e-12 * scale[owner]), minlength=m) > 0
    finite = np.bincount(owner, weights=(~np.isfinite(vol)).astype(float), minlength=m) == 0
    bad = finite & ((count == 0) | flat | ((pos > 0) & (pos < count)))
    if bad.any():
        k = int(np.argmax(bad))
        why = (
            "all its nodes on too few distinct points"
            if count[k] == 0
            else "a flat tetrahedron"
            if flat[k]
            else "tetrahedra of both orientations (twisted or not convex)"
        )
        raise MeshError(
            f"{what} {first + k} ({kind}): split into tetrahedra it gives {why}; expected a convex "
            f"cell with its nodes in VTK order (nodes {[int(i) for i in C[k]]})"
        )


# A quadratic tet's corners and mid-edge nodes (VTK's order, meshio's): 4 = (0, 1), 5 = (1, 2),
# 6 = (0, 2), 7 = (0, 3), 8 = (1, 3), 9 = (2, 3). Its 8 linear tets: one at each corner, and the
# inner octahedron cut along one of its three diagonals, each with its 4 other vertices in cyclic
# order around it; every tet listed with the orientation of the cell (0, 1, 2, 3).
_T10_CORNERS = ((0, 4, 6, 7), (4, 1, 5, 8), (6, 5, 2, 9), (7, 8, 9, 3))
_T10_DIAGONALS = (((4, 9), (7, 8, 5, 6)), ((6, 8), (4, 5, 9, 7)), ((7, 5), (6, 9, 8, 4)))


def refine_tetra10(nodes: np.ndarray, cells: np.ndarray, what: str = "cell", first: int = 0):
    """The 8 linear tetrahedra of each quadratic tet (M, 10) through its mid-edge nodes (the red
    refinement: Bey 1995, Computing 55:355), the inner octahedron cut along its shortest diagonal,
    so every node of the file is used and a face meets its neighbour's in the same 4 triangles.
    Returns positively oriented tets (8 M, 4), in cell order, and the cell of each; MeshError
    naming the first cell (``what`` first + k) whose tetrahedra are flat or of both orientations
    (mid-edge nodes far off their edges)."""
    C = np.asarray(cells, np.int64).reshape(-1, 10)
    X = np.asarray(nodes, float)
    parts = [C[:, list(t)] for t in _T10_CORNERS]
    if C.size and (C.min() < 0 or C.max() >= len(X)):
        diagonal = np.zeros(len(C), np.int64)  # indices beyond the nodes: the mesh's check names them
    else:
        length = [np.linalg.norm(X[C[:, a]] - X[C[:, b]], axis=1) for (a, b), _ in _T10_DIAGONALS]
        diagonal = np.argmin(np.column_stack(length), axis=1)
    inner = np.zeros((len(C), 4, 4), np.int64)
    for d, ((a, b), ring) in enumerate(_T10_DIAGONALS):
        rows = diagonal == d
        for i in range(4):
            inner[rows, i] = C[rows][:, [a, b, ring[i], ring[(i + 1) % 4]]]
    tets = np.concatenate([np.stack(parts, axis=1), inner], axis=1).reshape(-1, 4)
    owner = np.repeat(np.arange(len(C)), 8)
    if C.size and (C.min() < 0 or C.max() >= len(X)):
        return tets, owner
    vol = tet_volumes(X, tets)
    _check_cells(vol, C, owner, "tetra10", what, first)
    flip = vol < 0
    tets[flip, 2], tets[flip, 3] = tets[flip, 3].copy(), tets[flip, 2].copy()
    return tets, owner
