"""Topology of tet meshes and surfaces: boundary faces, unique rows, coincident nodes."""

from __future__ import annotations

import numpy as np

from .primitives import tet_edge_lengths


def boundary_faces(tets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Boundary triangles (F, 3), outward for positive tets, and the element of each (F,)."""
    tets = np.asarray(tets)
    local = np.array([[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]])
    faces = tets[:, local].reshape(-1, 3)
    owner = np.repeat(np.arange(len(tets)), 4)
    key = np.sort(faces, axis=1)
    _, inv, count = unique_rows(key, return_inverse=True, return_counts=True)
    once = count[inv] == 1
    return faces[once], owner[once]


def _row_keys(keys: np.ndarray) -> np.ndarray:
    """One sortable value per row of ``keys`` (R, k), non-negative integers: equal rows, equal
    values (an integer in base max + 1 where it fits in 62 bits, else the row's bytes)."""
    keys = np.ascontiguousarray(keys, dtype=np.int64)
    n = int(keys.max()) + 1 if keys.size else 1
    if float(n) ** keys.shape[1] < 2.0**62:
        flat = np.zeros(len(keys), np.int64)
        for c in range(keys.shape[1]):
            flat = flat * n + keys[:, c]
        return flat
    return keys.view(np.dtype((np.void, 8 * keys.shape[1]))).ravel()


def unique_rows(rows: np.ndarray, return_inverse: bool = False, return_counts: bool = False):
    """``np.unique(rows, axis=0, ...)`` for rows (R, k) of non-negative integers, with the same
    results (the distinct rows in lexicographic order; the inverse flat, shape (R,)), sorted as one
    int64 a row where (max + 1)^k fits in 62 bits. np.unique sorts rows as records, field by field:
    12 s for the 3.9 M edges of a 1.3 M-face surface, where one key a row takes under a second."""
    rows = np.asarray(rows, dtype=np.int64)
    one_key = (
        rows.ndim == 2 and rows.size and rows.min() >= 0 and float(rows.max() + 1) ** rows.shape[1] < 2.0**62
    )
    if one_key:
        _, first, inv, count = np.unique(
            _row_keys(rows), return_index=True, return_inverse=True, return_counts=True
        )
        uniq = rows[first]
    else:
        uniq, inv, count = np.unique(rows, axis=0, return_inverse=True, return_counts=True)
    out = [uniq] + ([inv.reshape(-1)] if return_inverse else []) + ([count] if return_counts else [])
    return out[0] if len(out) == 1 else tuple(out)


def _first_repeat(keys: np.ndarray, run: int) -> np.ndarray | None:
    """Indices (run,) of the first run of ``run`` equal rows of ``keys`` (R, k) non-negative
    integers, in ascending order of the rows' first index; None if no row occurs ``run`` times."""
    flat = _row_keys(keys)
    order = np.argsort(flat, kind="stable")
    f = flat[order]
    same = f[run - 1 :] == f[: len(f) - run + 1]
    if not same.any():
        return None
    starts = np.nonzero(same)[0]
    first = starts[np.argmin(order[starts])]  # the run whose first row comes first
    return np.sort(order[first : first + run])


def repeated_element(tets: np.ndarray) -> tuple[int, int] | None:
    """The first pair (i, j), i < j, of tetrahedra (M, 4) made of the same four nodes, or None."""
    pair = _first_repeat(np.sort(np.asarray(tets), axis=1), 2)
    return None if pair is None else (int(pair[0]), int(pair[1]))


def overshared_face(tets: np.ndarray) -> tuple[list[int], list[int]] | None:
    """A triangle shared by more than two tetrahedra (M, 4), as (its three nodes, ascending; three
    of the elements), or None. In a conforming tet mesh an interior face belongs to two elements
    and a boundary face to one: a third overlaps them."""
    key = np.sort(np.asarray(tets), axis=1)
    faces = key[:, [[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]]].reshape(-1, 3)
    rows = _first_repeat(faces, 3)
    return None if rows is None else (faces[rows[0]].tolist(), (rows // 4).tolist())


def folded_face(nodes: np.ndarray, tets: np.ndarray) -> tuple[list[int], list[int]] | None:
    """A triangle whose two tetrahedra lie on the same side of it (elements that overlap: a
    tangled mesh), as (its three nodes, ascending; the two elements), or None. Whatever each
    tetrahedron's orientation: its faces' windings are taken outward from its signed volume, and
    the two windings of a shared face must be opposite. Tets of zero volume are left out.
    nodes: [m] (N, 3); tets: (M, 4)."""
    from .primitives import tet_volumes

    T = np.asarray(tets, np.int64)
    det = tet_volumes(nodes, T)
    local = np.array([[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]])  # outward for det > 0
    faces = T[:, local].reshape(-1, 3)
    owner = np.repeat(np.arange(len(T)), 4)
    keep = np.repeat(det != 0, 4)
    faces, owner = faces[keep], owner[keep]
    order = np.argsort(faces, axis=1, kind="stable")
    # Parity of the permutation that sorts each winding (a, b, c): even for the cyclic orders.
    even = ((order[:, 1] - order[:, 0]) % 3) == 1
    outward = even ^ (det[owner] < 0)
    key = np.sort(faces, axis=1)
    flat = _row_keys(key)
    sort = np.argsort(flat, kind="stable")
    f, o = flat[sort], outward[sort]
    same = (f[1:] == f[:-1]) & (o[1:] == o[:-1])
    if not same.any():
        return None
    i = int(np.argmax(same))
    return key[sort[i]].tolist(), sorted((int(owner[sort[i]]), int(owner[sort[i + 1]])))


def conformity_problem(nodes: np.ndarray, tets: np.ndarray) -> str | None:
    """Why tetrahedra (M, 4) on nodes [m] (N, 3) are not one conforming mesh, naming the elements
    and the face, or None: an element given twice (its material and mass counted twice), a face
    of three elements, or two elements on the same side of their face (they overlap)."""
    T = np.asarray(tets)
    pair = repeated_element(T)
    if pair is not None:
        i, j = pair
        return (
            f"element {j} has the same four nodes as element {i}: {T[j].tolist()}; expected each "
            "tetrahedron once"
        )
    shared = overshared_face(T)
    if shared is not None:
        face, (a, b, c) = shared
        return (
            f"face {face} belongs to elements {a}, {b} and {c}; expected at most two (elements that overlap)"
        )
    folded = folded_face(nodes, T)
    if folded is not None:
        face, (a, b) = folded
        return (
            f"elements {a} and {b} lie on the same side of their common face {face}: they overlap (a "
            "tangled mesh); expected the two elements of a face on either side of it"
        )
    return None


def faces_off(faces: np.ndarray, tets: np.ndarray) -> np.ndarray:
    """Indices of the faces (K, 3) with a node that no tet (M, 4) uses: a sheet of its own, not a
    skin on the solid, ascending."""
    F = np.asarray(faces, np.int64).reshape(-1, 3)
    return np.nonzero(~np.isin(F, np.asarray(tets, np.int64)).all(axis=1))[0]


def boundary_nodes(tets: np.ndarray) -> np.ndarray:
    """Indices of the nodes on the boundary faces, ascending."""
    return np.unique(boundary_faces(tets)[0])


def _sorted_positions(P: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Positions (N, 3) in lexicographic order (-0.0 and 0.0 alike; np.unique(axis=0)'s order,
    by lexsort, where np.unique's row sort takes seconds a million rows): the positions as float64
    with -0.0 made 0.0 (N, 3), the order (N,) and whether each position in it equals the one
    before (N − 1,)."""
    P = np.asarray(P, dtype=np.float64) + 0.0
    order = np.lexsort(P.T[::-1])
    return P, order, np.all(P[order[1:]] == P[order[:-1]], axis=1)


def join_coincident(V: np.ndarray, F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (V, 3) at exactly one position made one, as np.unique(V, axis=0) orders them (-0.0
    and 0.0 alike), faces (F, 3) renumbered: formats that store each facet's corners on their own
    (STL) or split vertices at seams (glTF)."""
    if not len(V):
        return V, F
    P, order, same = _sorted_positions(V)
    new = np.concatenate([[True], ~same])
    rank = np.empty(len(V), dtype=np.int64)
    rank[order] = np.cumsum(new) - 1
    return P[order[new]], rank[F]


# Nodes closer than this fraction of the mesh's shortest element edge are taken as one position
# written twice (a writer's rounding: 6 significant digits move a node by up to 5e-7 of its
# coordinates), not as two: no element of a sound mesh comes near so short an edge.
CLOSE_FRACTION = 1e-3


def coincident_nodes(nodes: np.ndarray, tets: np.ndarray) -> tuple[int, int, int, float]:
    """Nodes of tetrahedra (M, 4) at, or closer than CLOSE_FRACTION of the shortest element edge
    to, the position [m] (N, 3) of another node of theirs: (how many nodes have such a
    lower-numbered partner, the first such pair a < b, the largest distance of such a pair [m]), or
    (0, -1, -1, 0.0). Such nodes do not join the elements on either side: a file written one node
    per element corner (its positions rounded, or not), or bodies meant to be separate."""
    from scipy.spatial import cKDTree

    T = np.asarray(tets, np.int64).reshape(-1, 4)
    X = np.asarray(nodes, float)
    if not len(T) or T.min() < 0 or T.max() >= len(X):
        return 0, -1, -1, 0.0  # no elements, or indices the mesh's own check names
    used = used_nodes(T, len(X))
    if not np.all(np.isfinite(X[used])):
        return 0, -1, -1, 0.0  # the builder names a non-finite node
    # Candidates within the fraction of a sample's median edge (at least the shortest edge's), then
    # the pairs within the fraction of the shortest edge of all, measured only when there are any.
    sample = T[np.linspace(0, len(T) - 1, min(len(T), 1000)).astype(np.int64)]
    wide = CLOSE_FRACTION * float(np.median(tet_edge_lengths(X, sample)))
    pairs = used[cKDTree(X[used]).query_pairs(wide, output_type="ndarray")]
    d = np.linalg.norm(X[pairs[:, 0]] - X[pairs[:, 1]], axis=1)
    if len(pairs):
        keep = d <= CLOSE_FRACTION * tet_edge_lengths(X, T).min()
        pairs, d = pairs[keep], d[keep]
    if not len(pairs):
        return 0, -1, -1, 0.0
    lower, later = pairs.min(axis=1), pairs.max(axis=1)
    first = np.lexsort((lower, later))[0]
    return int(np.unique(later).size), int(lower[first]), int(later[first]), float(d.max())


def used_nodes(tets: np.ndarray, n_nodes: int) -> np.ndarray:
    """The nodes tets (M, 4) refer to, ascending (K,): what np.unique(tets) gives, by counting
    (indices checked to lie in 0..n_nodes − 1)."""
    return np.flatnonzero(np.bincount(np.asarray(tets, np.int64).ravel(), minlength=n_nodes))


def drop_unused(nodes: np.ndarray, tets: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Nodes (N, 3) no tet (M, 4) refers to removed: (the nodes kept, the tets renumbered, each old
    node's new number (N,), −1 for one removed)."""
    used = used_nodes(tets, len(nodes))
    new = np.full(len(nodes), -1, dtype=np.int64)
    new[used] = np.arange(used.size)
    return nodes[used], new[tets], new
