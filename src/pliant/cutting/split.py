"""Cutting a tet mesh along a surface by separating elements at their shared faces and splitting
the nodes between them (element-face separation; Wu, Westermann & Dick 2015, "A survey of
physically based simulation of cuts in deformable bodies", Comput. Graph. Forum 34(6):161, §4.2;
the node-splitting step of Forest, Delingette & Ayache 2002, "Removing tetrahedra from a
manifold mesh", Computer Animation).

A face shared by two elements is *cut* when the segment joining the two elements' centroids (in
the current, deformed configuration) crosses the cutting surface. Then, around every node of a cut
face, the elements incident to the node are grouped by the faces they still share that contain
the node; each group beyond the first gets its own copy of the node. The cut opens along element
faces: the new surface is a clean, closed triangle surface (a staircase on the scale of the
elements), no element changes shape, so no element inverts, mass is conserved exactly and the
stable time step is unchanged; where the cut ends inside the body (its front), nodes whose
elements remain connected around them are not split, and the crack stays closed there.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["interior_faces", "crossed_faces", "split_nodes", "Split"]

# Local faces of a tet (the faces opposite nodes 0..3, outward for positive tets).
LOCAL_FACES = np.array([[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]])


def interior_faces(tets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Faces shared by two elements: node triples (F, 3) (sorted) and the pair of elements (F, 2)
    sharing each (smaller element first)."""
    tets = np.asarray(tets, np.int64)
    faces = np.sort(tets[:, LOCAL_FACES].reshape(-1, 3), axis=1)
    owner = np.repeat(np.arange(len(tets)), 4)
    order = np.lexsort((owner, faces[:, 2], faces[:, 1], faces[:, 0]))
    f, o = faces[order], owner[order]
    same = np.all(f[1:] == f[:-1], axis=1)
    i = np.nonzero(same)[0]
    return f[i], np.stack([o[i], o[i + 1]], axis=1)


def _segments_cross(p: np.ndarray, q: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """Whether each segment p→q (S, 3) crosses any triangle of tri (K, 3, 3) [m]: Möller &
    Trumbore 1997 ("Fast, minimum storage ray/triangle intersection", J. Graph. Tools 2(1):21),
    with the ray parameter limited to the segment; degenerate triangles cross nothing."""
    hit = np.zeros(len(p), dtype=bool)
    d = q - p
    for a, b, c in tri:
        e1, e2 = b - a, c - a
        h = np.cross(d, e2)
        det = h @ e1
        scale = np.linalg.norm(e1) * np.linalg.norm(e2)
        if not scale > 0 or not np.linalg.norm(np.cross(e1, e2)) > 1e-12 * scale:
            continue  # a degenerate (zero-area) triangle
        ok = np.abs(det) > 1e-12 * scale * np.maximum(np.linalg.norm(d, axis=1), 1e-300)
        inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
        s = p - a
        u = inv * np.einsum("ij,ij->i", s, h)
        qv = np.cross(s, e1)
        v = inv * np.einsum("ij,ij->i", d, qv)
        t = inv * (qv @ e2)
        hit |= ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t >= 0) & (t <= 1)
    return hit


def crossed_faces(positions: np.ndarray, tets: np.ndarray, triangles, faces=None) -> np.ndarray:
    """Indices of the interior faces (of :func:`interior_faces`, or ``faces`` = its result) whose
    element-centroid segment crosses the cutting surface ``triangles`` [m] (K, 3, 3), with node
    ``positions`` [m] (N, 3) of the current configuration."""
    tri = np.asarray(triangles, float).reshape(-1, 3, 3)
    _, pairs = interior_faces(tets) if faces is None else faces
    if len(pairs) == 0 or len(tri) == 0:
        return np.zeros(0, np.int64)
    cent = positions[np.asarray(tets)].mean(axis=1)
    p, q = cent[pairs[:, 0]], cent[pairs[:, 1]]
    lo, hi = tri.reshape(-1, 3).min(axis=0), tri.reshape(-1, 3).max(axis=0)
    near = np.nonzero(np.all((np.minimum(p, q) <= hi) & (np.maximum(p, q) >= lo), axis=1))[0]
    return near[_segments_cross(p[near], q[near], tri)]


@dataclass
class Split:
    """The mesh after a cut: ``tets`` (M, 4) with split nodes renumbered, ``parent`` (K,) the node
    each new node (numbered N, N + 1, …) was copied from, ``faces`` (F, 3) the new surface
    triangles the cut opened (both sides, outward, new numbering) and ``face_elements`` (F,) the
    element of each."""

    tets: np.ndarray
    parent: np.ndarray
    faces: np.ndarray
    face_elements: np.ndarray


def _groups(elems: list[int], links: list[tuple[int, int]]) -> list[list[int]]:
    """Connected groups of ``elems`` (ascending) under ``links``; groups ordered by their smallest
    element (the first keeps the original node: deterministic)."""
    root = {e: e for e in elems}

    def find(e):
        while root[e] != e:
            root[e] = root[root[e]]
            e = root[e]
        return e

    for a, b in links:
        ra, rb = find(a), find(b)
        if ra != rb:
            root[max(ra, rb)] = min(ra, rb)
    out: dict[int, list[int]] = {}
    for e in elems:
        out.setdefault(find(e), []).append(e)
    return [out[r] for r in sorted(out)]


def _keep_fragments_whole(pairs: np.ndarray, n_elems: int, is_cut: np.ndarray, min_fragment: int) -> None:
    """Un-cut faces (in place) so that no piece cut loose has fewer than ``min_fragment`` elements:
    each such piece (elements connected through uncut faces, bounded by a cut) stays joined to the
    neighbouring piece it shares most cut faces with (ties: the lower element). A few loose
    elements would be debris, and unstable: an isolated linear tet's highest frequency exceeds the
    h_min/c_d estimate of the stable step (by 1/0.64 for a Kuhn tet), which holds inside a mesh."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    while True:
        keep = ~is_cut
        g = coo_matrix((np.ones(int(keep.sum())), (pairs[keep, 0], pairs[keep, 1])), shape=(n_elems, n_elems))
        _, label = connected_components(g, directed=False)
        size = np.bincount(label)
        c = np.nonzero(is_cut)[0]
        la, lb = label[pairs[c, 0]], label[pairs[c, 1]]
        small = np.unique(np.concatenate([la[size[la] < min_fragment], lb[size[lb] < min_fragment]]))
        if small.size == 0:
            return
        piece = int(small[np.argmin(size[small])])  # the smallest first (ties: lowest label)
        side = np.nonzero((la == piece) ^ (lb == piece))[0]
        other = np.where(la[side] == piece, lb[side], la[side])
        if side.size == 0:  # cut faces inside the piece only: nothing joins it elsewhere
            is_cut[c[(la == piece) & (lb == piece)]] = False
            continue
        counts = np.bincount(other)
        best = int(np.argmax(counts))  # the most shared faces; ties: the lowest label
        is_cut[c[side[other == best]]] = False


def split_nodes(tets: np.ndarray, n_nodes: int, cut: np.ndarray, faces=None, min_fragment: int = 8) -> Split:
    """Separate the elements at the interior faces ``cut`` (indices into :func:`interior_faces`, or
    ``faces`` = its result) and split each node whose incident elements fall apart into groups
    (connected through uncut faces that contain the node). No piece of fewer than
    ``min_fragment`` elements is cut loose (it stays with a neighbour)."""
    tets = np.array(tets, np.int64)
    F, pairs = interior_faces(tets) if faces is None else faces
    is_cut = np.zeros(len(F), dtype=bool)
    is_cut[np.asarray(cut, np.int64)] = True
    if is_cut.any() and min_fragment > 1:
        _keep_fragments_whole(pairs, len(tets), is_cut, min_fragment)
    nodes = np.unique(F[is_cut])
    # Incident elements of the affected nodes, and the uncut faces around each (as element links).
    flat = tets.ravel()
    order = np.argsort(flat, kind="stable")
    start = np.searchsorted(flat[order], nodes)
    stop = np.searchsorted(flat[order], nodes, side="right")
    links: dict[int, list[tuple[int, int]]] = {int(n): [] for n in nodes}
    uncut = np.nonzero(~is_cut & np.isin(F, nodes).any(axis=1))[0]
    for f in uncut:
        for n in F[f]:
            if int(n) in links:
                links[int(n)].append((int(pairs[f, 0]), int(pairs[f, 1])))
    parent: list[int] = []
    new_tets = tets.copy()
    for n, a, b in zip(nodes, start, stop):
        elems = sorted(int(e) for e in order[a:b] // 4)
        for grp in _groups(elems, links[int(n)])[1:]:
            copy_id = n_nodes + len(parent)
            parent.append(int(n))
            for e in grp:
                new_tets[e][tets[e] == n] = copy_id
    # The opened faces: each side of each cut face whose two elements no longer share all its
    # nodes (a cut face whose nodes all stayed whole is still closed), outward from its element.
    opened: list[np.ndarray] = []
    owner: list[int] = []
    for f in np.nonzero(is_cut)[0]:
        sides = []
        for e in pairs[f]:
            k = int(np.nonzero(~np.isin(tets[e], F[f]))[0][0])  # the local node opposite the face
            sides.append(new_tets[e][LOCAL_FACES[k]])
        if set(sides[0].tolist()) != set(sides[1].tolist()):
            opened.extend(sides)
            owner.extend(int(e) for e in pairs[f])
    return Split(
        new_tets,
        np.array(parent, np.int64),
        np.array(opened, np.int64).reshape(-1, 3),
        np.array(owner, np.int64),
    )
