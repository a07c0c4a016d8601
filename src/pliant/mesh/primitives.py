"""Tetrahedral meshes of simple shapes, positively oriented, in metres."""

from __future__ import annotations

import itertools
import math

import numpy as np

from ..checks import as_real, finite_vector, mesh_arrays, real_array, shown, whole_number
from ..errors import InputError
from ..memory import BOX_BYTES_PER_TET, require_memory


def unit_scale(V: np.ndarray) -> float:
    """A power of two that scales points V [m] (n, 3) to a bounding-box diagonal between 0.7 and
    1.4 (exact both ways in floating point); 1 for a box of no or non-finite size. The libraries'
    absolute tolerances (trimesh's 1e-8 merge, fTetWild's) then act as on a body a metre across."""
    V = np.asarray(V, float)
    diag = float(np.linalg.norm(np.ptp(V, axis=0))) if len(V) else 0.0
    return 2.0 ** -round(math.log2(diag)) if math.isfinite(diag) and diag > 0 else 1.0


def tet_volumes(nodes: np.ndarray, tets: np.ndarray) -> np.ndarray:
    """Signed volumes [m³] (M,) of tets (M, 4) on nodes [m] (N, 3): det[X1−X0, X2−X0, X3−X0] / 6,
    positive for positively oriented tets."""
    P = np.asarray(nodes, float)[np.asarray(tets, np.int64)]
    return np.einsum("ij,ij->i", np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), P[:, 3] - P[:, 0]) / 6.0


TET_EDGES = ((0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3))  # a tet's corner pairs


def tet_edge_lengths(nodes: np.ndarray, tets: np.ndarray) -> np.ndarray:
    """The six edge lengths [m] (M, 6) of tets (M, 4) on nodes [m] (N, 3), in TET_EDGES' order."""
    X, T = np.asarray(nodes, float), np.asarray(tets, np.int64)
    out = np.empty((len(T), 6))
    for k, (i, j) in enumerate(TET_EDGES):
        out[:, k] = np.linalg.norm(X[T[:, j]] - X[T[:, i]], axis=1)
    return out


def triangle_measures(nodes: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Area [m²] and longest edge [m] of each triangle ``faces`` (F, 3) over ``nodes`` (N, 3)."""
    P = np.asarray(nodes, float)[np.asarray(faces)]
    area = 0.5 * np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), axis=1)
    return area, np.linalg.norm(P - P[:, [1, 2, 0]], axis=2).max(axis=1, initial=0.0)


def orient_positive(nodes: np.ndarray, tets: np.ndarray) -> np.ndarray:
    """Return tets (M, 4) with corners 2 and 3 swapped where det[X1−X0, X2−X0, X3−X0] < 0."""
    X, T = mesh_arrays(nodes, tets, 4, "orient_positive", empty=True)
    neg = tet_volumes(X, T) < 0
    T[neg, 2], T[neg, 3] = T[neg, 3].copy(), T[neg, 2].copy()
    return T


def _grid(xs, ys, zs):
    """Nodes (N, 3) [m] of the tensor grid on xs, ys, zs (checked: at least 2 finite, strictly
    increasing coordinates each), their index by (i, j, k), and each cell's lowest corner i, j, k."""
    g = []
    for name, c in zip("xyz", (xs, ys, zs)):
        a = real_array(c)
        if a is None or a.ndim != 1 or a.size < 2 or not np.all(np.isfinite(a)) or np.any(np.diff(a) <= 0):
            raise InputError(
                f"{name}s = {shown(c)}; expected at least 2 finite, strictly increasing coordinates [m]"
            )
        c = a
        g.append(c)
    nx, ny, nz = (c.size - 1 for c in g)
    X = np.stack(np.meshgrid(*g, indexing="ij"), axis=-1).reshape(-1, 3)
    idx = np.arange(X.shape[0]).reshape(nx + 1, ny + 1, nz + 1)
    i, j, k = (a.ravel() for a in np.meshgrid(np.arange(nx), np.arange(ny), np.arange(nz), indexing="ij"))
    return X, idx, (i, j, k)


def grid_tets(xs, ys, zs) -> tuple[np.ndarray, np.ndarray]:
    """Tensor-product mesh on the coordinate lines xs, ys, zs [m] (each strictly increasing, at
    least 2 values): every cell is split into 6 tetrahedra (Kuhn triangulation, conforming). Use it
    for graded meshes, e.g. fine near a contact and growing geometrically away from it. Returns
    nodes (N, 3) [m] and positively oriented tets (6·(nx−1)(ny−1)(nz−1), 4)."""
    X, idx, (i, j, k) = _grid(xs, ys, zs)
    tets = []
    for perm in itertools.permutations(range(3)):
        corner = np.zeros((3, i.size), dtype=np.int64)
        path = [idx[i, j, k]]
        for axis in perm:
            corner[axis] += 1
            path.append(idx[i + corner[0], j + corner[1], k + corner[2]])
        tets.append(np.stack(path, axis=1))
    return X, orient_positive(X, np.concatenate(tets))


def grid_hexahedra(xs, ys, zs) -> tuple[np.ndarray, np.ndarray]:
    """The tensor grid of :func:`grid_tets` as hexahedra: nodes (N, 3) [m] and cells (M, 8) in VTK's
    node order (the bottom face counter-clockwise seen from above, then the top face above it), for
    pliant.mesh.split and NiftySim's H8."""
    X, idx, (i, j, k) = _grid(xs, ys, zs)
    corners = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]
    return X, np.stack([idx[i + a, j + b, k + c] for a, b, c in corners], axis=1)


def graded_coordinates(h: float, fine_to: float, ratio: float, length: float) -> np.ndarray:
    """Coordinates [m] from 0 for :func:`grid_tets`: uniform spacing ``h`` up to ``fine_to``,
    then each cell ``ratio`` times the previous one until ``length`` is reached or passed (the last
    cell is kept whole). E.g. fine under a contact, coarse far from it."""
    h, fine_to, ratio, length = (as_real(v) for v in (h, fine_to, ratio, length))  # NaN: not a number
    if not (
        h > 0 and fine_to >= 0 and ratio >= 1 and length > 0 and all(np.isfinite([h, fine_to, ratio, length]))
    ):
        raise InputError(
            f"graded_coordinates(h={h}, fine_to={fine_to}, ratio={ratio}, "
            f"length={length}); expected h > 0, fine_to >= 0, ratio >= 1, length > 0"
        )
    rest = max(length - max(fine_to, h), 0.0)  # what the growing cells cover: Σ h ratioᵏ >= rest
    graded = rest / h if ratio == 1 else math.log1p(rest * (ratio - 1) / h) / math.log(ratio)
    if not fine_to / h + graded <= MAX_COORDINATES:
        raise InputError(
            f"graded_coordinates(h={h}, fine_to={fine_to}, ratio={ratio}, length={length}) makes "
            f"{fine_to / h + graded:.3g} coordinates; expected at most {MAX_COORDINATES:.0e} "
            "(a larger h or ratio)"
        )
    xs = list(np.arange(0.0, fine_to + 1e-9 * h, h)) or [0.0]
    if len(xs) == 1:
        xs.append(h)
    while xs[-1] < length * (1 - 1e-12):
        xs.append(xs[-1] + (xs[-1] - xs[-2]) * ratio)
    return np.array(xs)


MAX_BOX_TETS = 2e8  # ~50 GB of engine arrays: beyond any workstation
MAX_COORDINATES = 1e6  # graded_coordinates along one axis: a grid of 1e18 cells


def box_tets(
    size=(1.0, 1.0, 1.0), cells=(4, 4, 4), origin=(0.0, 0.0, 0.0), jitter: float = 0.0, seed: int = 0
) -> tuple[np.ndarray, np.ndarray]:
    """Box [origin, origin + size] [m] split into nx·ny·nz hexahedra of 6 tetrahedra each (Kuhn
    triangulation, conforming). ``jitter`` moves interior nodes randomly by up to that fraction of
    a cell, making the mesh unstructured (less where a move would turn an element inside out:
    _untangled). Returns nodes (N, 3) [m] and tets (M, 4)."""
    try:
        nx, ny, nz = cells
    except (TypeError, ValueError):
        raise InputError(f"cells = {cells!r}; expected three integers >= 1") from None
    # Integers only: int() made 20.5 cells 20 and True one, silently.
    if not all(isinstance(c, (int, np.integer)) and not isinstance(c, bool) and c >= 1 for c in (nx, ny, nz)):
        raise InputError(f"cells = {list(cells)}; expected three integers >= 1")
    nx, ny, nz = int(nx), int(ny), int(nz)
    if 6 * nx * ny * nz > MAX_BOX_TETS:
        raise InputError(
            f"cells = {[nx, ny, nz]} make {6 * nx * ny * nz:.3g} tets; expected at most {MAX_BOX_TETS:.0e}"
        )
    require_memory(
        6 * nx * ny * nz, BOX_BYTES_PER_TET, f"cells = {[nx, ny, nz]} ({6 * nx * ny * nz:.3g} tets)"
    )
    given, size = size, real_array(size)
    if size is None or size.shape != (3,) or not np.all(np.isfinite(size)) or np.any(size <= 0):
        raise InputError(f"size = {shown(given)}; expected three finite lengths > 0 [m]")
    shift = finite_vector(origin, 3, "origin", "m")
    if not whole_number(seed, "seed") >= 0:
        raise InputError(f"seed = {shown(seed)}; expected an integer >= 0")
    if not (0 <= as_real(jitter) < 0.5):
        raise InputError(
            f"jitter = {shown(jitter)}; expected 0 <= jitter < 0.5 (a fraction of a "
            "cell: half a cell or more can turn elements inside out)"
        )
    lines = [np.linspace(0.0, s, n + 1) for s, n in zip(size, (nx, ny, nz))]
    if any(np.any(np.diff(c) <= 0) for c in lines):  # subnormal sizes: the cells' corners coincide
        raise InputError(
            f"size = {size.tolist()} in cells = {[nx, ny, nz]} gives cells too small to tell their "
            "corners apart; expected lengths [m] of physical size"
        )
    X, T = grid_tets(*lines)
    if jitter > 0:
        h = size / np.array([nx, ny, nz])
        rng = np.random.default_rng(seed)
        interior = np.all((X > 1e-12 * size) & (X < size * (1 - 1e-12)), axis=1)
        X0 = X.copy()
        X[interior] += rng.uniform(-1, 1, (interior.sum(), 3)) * jitter * h
        X = _untangled(X0, X, T)
    return X + shift, T


def _untangled(X0: np.ndarray, X: np.ndarray, T: np.ndarray) -> np.ndarray:
    """Nodes X moved from X0 [m] (N, 3), with the moves of the nodes of any element that the
    moves turned inside out (T positively oriented on X0) halved, until none is: a Kuhn cell's
    thinnest tets turn over beyond about a fifth of a cell's jitter, and turning them back (as
    orient_positive would) makes them overlap their neighbours, a tangled mesh. Every element
    keeps its orientation, the boundary does not move: a valid mesh."""
    vol0 = tet_volumes(X0, T)
    for _ in range(64):
        bad = tet_volumes(X, T) <= 1e-6 * vol0
        if not bad.any():
            return X
        nodes = np.unique(T[bad])
        X[nodes] = X0[nodes] + 0.5 * (X[nodes] - X0[nodes])
    return X0
