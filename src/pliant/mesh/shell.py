"""The solid inside a thin-walled surface: an organ's capsule (HuBMAP's liver and kidney, an
atlas's membranes) is a closed surface of two sheets a millimetre apart, the outer one facing out
and the inner one facing the organ, joined along the rims of its openings (the liver's bare area,
the kidney's hilum). As a surface it encloses the wall alone: a hollow organ. ``outer_sheet`` keeps
the outer sheet, whose openings repair then closes (minimum-area triangulation), so that the
tetrahedra fill the organ.

Method:

1. each face's *opposite*: the nearest face whose plane a ray from its centroid along its inward
   normal crosses, facing back, within a few edges (Möller & Trumbore 1997 ray–triangle test); where
   too few faces find one so near (a wall thicker than its triangles), among the faces nearest to
   points along the ray, as deep as a tenth of the surface's size;
2. the two sheets: faces joined by an edge lie on one sheet, a face and its opposite on two, and the
   signs of the smallest eigenvector of that signed graph's Laplacian split the faces into the two
   sides with the fewest relations broken (the rims; Kunegis et al. 2010, "Spectral analysis of
   signed graphs for clustering, prediction and visualization", SIAM SDM, §4);
3. the outer sheet: the one whose generalized winding number (bodies.winding_number) is near one
   at the other sheet's faces: the inner sheet lies inside it, not it inside the inner one;
4. the outer sheet's largest piece, its rim trimmed of faces that hang by a vertex or an edge.
"""

from __future__ import annotations

import numpy as np

from ..errors import MeshError
from .topology import unique_rows
from .bodies import winding_number

# A face's opposite is looked for among the nearest faces within this many median edges (a
# capsule's wall is thinner than its triangles: the liver's 0.9 mm under edges of 4.3 mm).
REACH = 3.0
NEAREST = 32
# Where too few faces find one (a wall thicker than its triangles), among the PROBED faces nearest to
# each of the points one median edge, then 1.5 times as deep, and so on along the ray, as deep as
# DEEP × the bounding box's diagonal (a ball's faces, whose rays cross it, find none so near).
PROBED = 8
DEEP = 0.1
SAMPLED = 500  # faces tried first: the deep search runs on all only if half of these find one
# At least this share of a body's faces must find their opposite: a solid's faces mostly find none.
PAIRED = 0.8
# The outer sheet's winding number at the inner sheet's faces is near 1 (liver 0.95, kidney 1.00)
# and the inner sheet's at the outer one's near 0 (0.04, −0.01); two sheets that do not nest (a
# thin plate: about ½ both ways) are refused.
OUTER = 0.75
SAMPLES = 64
CHUNK = 20_000  # faces whose rays are cast at once


def outer_sheet(V: np.ndarray, F: np.ndarray) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """The outer sheet of each thin-walled body of the closed, outward surface V [m] (n, 3), F (f,
    3) (``repair_surface``'s output), as faces of V: an open surface whose openings
    ``repair_surface`` closes. Returns (V, F, actions). Raises MeshError naming the body when its
    faces do not pair across a wall (a solid) or its two sheets do not nest (a thin plate)."""
    import trimesh

    m = trimesh.Trimesh(np.asarray(V, float), np.asarray(F, np.int64), process=True, validate=False)
    V, F = np.asarray(m.vertices), np.asarray(m.faces)
    adj = np.asarray(m.face_adjacency)
    opposite, depth = opposite_faces(V, F)
    sampled = ""
    if np.mean(opposite >= 0) < PAIRED:  # a wall thicker than a few triangles: look deeper
        sampled = _look_deeper(V, F, opposite, depth)
    bodies = _bodies(len(F), adj, opposite)
    keep, actions = [], []
    for k, faces in enumerate(bodies):
        who = f"body {k + 1} of {len(bodies)}" if len(bodies) > 1 else "the surface"
        paired = float(np.mean(opposite[faces] >= 0))
        if paired < PAIRED:
            raise MeshError(
                f"fill_shell: {who} is not a thin-walled shell: {100 * paired:.0f} % of its faces face "
                f"another {sampled or 'across a wall'} thinner than {DEEP:.0%} of its size (expected >= "
                f"{100 * PAIRED:.0f} %); mesh it as it is"
            )
        side = sheets(faces, adj, opposite)
        outer = _outer_side(V, F, faces, side, who)
        kept = trim_rim(F, faces[outer])
        wall = float(np.median(depth[faces][opposite[faces] >= 0]))
        actions.append(
            f"kept the outer sheet of {who} ({len(kept)} of {len(faces)} faces; wall {wall:.3g} m)"
        )
        keep.append(kept)
    return V, F[np.sort(np.concatenate(keep))], actions


def _look_deeper(V: np.ndarray, F: np.ndarray, opposite: np.ndarray, depth: np.ndarray) -> str:
    """``opposite_faces(probed=True)`` for the faces that found no opposite near (in place), if it
    finds one for at least half of a sample of SAMPLED of them: probes deep inside a solid (where
    the faces of a ball or a bunny find none) make the nearest-face search slow (4 s on the bunny's
    69,664 faces at 2 cm deep). Returns what a refusal adds when only the sample was looked at."""
    missing = np.flatnonzero(opposite < 0)
    sample = missing[np.unique(np.linspace(0, len(missing) - 1, min(SAMPLED, len(missing))).astype(int))]
    share = float(np.mean(opposite_faces(V, F, probed=True, faces=sample)[0][sample] >= 0))
    if share < 0.5:
        return (
            f"within {REACH:g} triangles, and {100 * share:.0f} % of {len(sample)} others tried across a wall"
        )
    deep, deep_depth = opposite_faces(V, F, probed=True, faces=missing)
    opposite[missing], depth[missing] = deep[missing], deep_depth[missing]
    return ""


def _bodies(n: int, adj: np.ndarray, opposite: np.ndarray) -> list[np.ndarray]:
    """The faces of each body, sorted, bodies in the order of their first face: faces joined by an
    edge or across a wall (a face and its opposite), so that two closed sheets a wall apart (a
    hollow sphere: its outer surface and its cavity's) are one shell."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    o = np.flatnonzero(opposite >= 0)
    e = np.r_[adj.reshape(-1, 2), np.c_[o, opposite[o]]]
    _, label = connected_components(
        coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n, n)), directed=False
    )
    first = np.unique(label, return_index=True)[1]
    return [np.flatnonzero(label == label[f]) for f in np.sort(first)]


def opposite_faces(
    V: np.ndarray, F: np.ndarray, probed: bool = False, faces: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Per face, the nearest face (−1: none) that a ray from its centroid along its inward normal
    hits, facing back (normals apart by more than 90°), among the ``NEAREST`` faces whose centroids
    lie within ``REACH`` median edges, or, if ``probed``, among the ``PROBED`` nearest to each point
    along the ray (one median edge deep, then 1.5 times deeper each, to ``DEEP`` × the diagonal), no
    farther than that; and the hit's distance [m] (inf: none). Shapes (f,); only ``faces`` (indices)
    are looked at if given (−1 and inf for the others)."""
    from scipy.spatial import cKDTree

    P = V[F]
    C = P.mean(axis=1)
    N = np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0])
    N /= np.maximum(np.linalg.norm(N, axis=1), 1e-300)[:, None]
    h = float(np.median(np.linalg.norm(P[:, 1] - P[:, 0], axis=1)))
    deepest = DEEP * float(np.linalg.norm(np.ptp(V, axis=0)))
    depths = h * 1.5 ** np.arange(int(np.log(max(deepest / h, 1.0)) / np.log(1.5)) + 1)
    k = min(PROBED if probed else NEAREST, len(F))
    tree = cKDTree(C)
    opposite = np.full(len(F), -1, np.int64)
    dist = np.full(len(F), np.inf)
    step = max(CHUNK * NEAREST // (k * len(depths) if probed else k), 1)
    todo = np.arange(len(F)) if faces is None else np.asarray(faces, np.int64)
    for lo in range(0, len(todo), step):  # (rows, candidates, 3) arrays: about 100 MB at a time
        rows = todo[lo : lo + step]
        if probed:
            # The faces a probe looks for lie nearer to it than its own face (its depth): a bound
            # that keeps the search from wandering over the whole tree from deep inside a solid.
            near = np.concatenate(
                [
                    tree.query(C[rows] - d * N[rows], k=k, distance_upper_bound=d)[1].reshape(len(rows), -1)
                    for d in depths
                ],
                axis=1,
            )
        else:
            _, near = tree.query(C[rows], k=k, distance_upper_bound=REACH * h)
        near = np.asarray(near, np.int64).reshape(len(rows), -1)
        ok = (near < len(F)) & (near != rows[:, None])  # len(F): none within the reach
        near = np.where(ok, near, 0)
        t = _ray_hits(C[rows], -N[rows], P, near)
        ok &= np.isfinite(t) & (np.einsum("fd,fkd->fk", N[rows], N[near]) < 0.0)
        t = np.where(ok & (t <= deepest if probed else True), t, np.inf)
        j = np.argmin(t, axis=1)
        best = t[np.arange(len(rows)), j]
        dist[rows] = best
        opposite[rows] = np.where(np.isfinite(best), near[np.arange(len(rows)), j], -1)
    return opposite, dist


def _ray_hits(O: np.ndarray, D: np.ndarray, P: np.ndarray, near: np.ndarray) -> np.ndarray:
    """Distance along each ray O + t D (f, 3) to each of its candidate triangles P[near] (f, k),
    inf where it misses or t <= 0 (Möller & Trumbore 1997, JGT 2(1))."""
    A, B, Cc = P[near, 0], P[near, 1], P[near, 2]  # (f, k, 3)
    e1, e2 = B - A, Cc - A
    p = np.cross(D[:, None, :], e2)
    det = np.einsum("fkd,fkd->fk", e1, p)
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / det
        s = O[:, None, :] - A
        u = np.einsum("fkd,fkd->fk", s, p) * inv
        q = np.cross(s, e1)
        v = np.einsum("fd,fkd->fk", D, q) * inv
        t = np.einsum("fkd,fkd->fk", e2, q) * inv
        hit = (np.abs(det) > 0) & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0)
    return np.where(hit, t, np.inf)


def sheets(faces: np.ndarray, adj: np.ndarray, opposite: np.ndarray) -> np.ndarray:
    """The two sheets of one body's faces (sorted indices): True for one side, False for the other.
    Relations: +1 between faces sharing an edge, −1 between a face and its opposite; the signs of
    the eigenvector of the smallest eigenvalue of the signed Laplacian D − A (D the absolute row
    sums) break the fewest of them (Kunegis et al. 2010, §4)."""
    import scipy.sparse as sp
    from scipy.sparse.linalg import eigsh

    n = len(faces)
    local = np.full(len(opposite), -1)
    local[faces] = np.arange(n)
    a = adj[(local[adj[:, 0]] >= 0) & (local[adj[:, 1]] >= 0)]
    o = faces[opposite[faces] >= 0]
    pairs = np.c_[local[o], local[opposite[o]]]
    pairs = pairs[pairs[:, 1] >= 0]
    rows = np.r_[local[a[:, 0]], local[a[:, 1]], pairs[:, 0], pairs[:, 1]]
    cols = np.r_[local[a[:, 1]], local[a[:, 0]], pairs[:, 1], pairs[:, 0]]
    vals = np.r_[np.ones(2 * len(a)), -np.ones(2 * len(pairs))]
    A = sp.coo_matrix((vals, (rows, cols)), shape=(n, n)).tocsr()
    L = (sp.diags(np.asarray(abs(A).sum(axis=1)).ravel()) - A).tocsc()
    # Shift-invert about a point below the spectrum (L is positive semi-definite); a fixed start
    # vector: the same split on every run.
    try:
        _, vec = eigsh(L, k=1, sigma=-1e-3, which="LM", v0=np.linspace(1.0, 2.0, n))
    except (ArithmeticError, RuntimeError, ValueError) as e:  # ARPACK's errors are RuntimeErrors
        raise MeshError(f"fill_shell: the sheets of {n} faces could not be told apart ({e})") from None
    return vec[:, 0] > 0


def _outer_side(V, F, faces, side, who: str) -> np.ndarray:
    """Which side of ``sheets`` is the outer sheet (a mask over faces); MeshError if they don't nest."""
    C = V[F[faces]].mean(axis=1)
    w = []
    for mine, other in ((side, ~side), (~side, side)):
        pts = C[other][np.linspace(0, int(other.sum()) - 1, min(SAMPLES, int(other.sum()))).astype(int)]
        w.append(float(np.mean(winding_number(V, F[faces[mine]], pts))) if len(pts) else 0.0)
    hi = int(np.argmax(w))
    if not (w[hi] >= OUTER and w[1 - hi] <= 1 - OUTER):
        raise MeshError(
            f"fill_shell: the two sheets of {who} do not nest (winding numbers {w[0]:.2f} and {w[1]:.2f}"
            f" at each other's faces; a capsule's outer sheet has >= {OUTER:g} at the inner one's): "
            "a thin plate, not a capsule; mesh it as it is"
        )
    return side if hi == 0 else ~side


def trim_rim(F: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """The largest edge-connected piece of ``faces`` (indices into F), then, repeatedly, faces with
    two or three open edges, or at a vertex where the open edges pinch (more than two meet),
    dropped: what is left has simple openings for ``fill_loop``. Sorted indices into F."""
    import trimesh

    while True:
        if len(faces) == 0:
            raise MeshError("fill_shell: nothing is left of the outer sheet once its rim is trimmed")
        sub = F[faces]
        adjacent = trimesh.graph.face_adjacency(faces=sub)
        pieces = trimesh.graph.connected_components(adjacent, nodes=np.arange(len(sub)), min_len=1)
        faces = np.sort(faces[max(pieces, key=len)])
        sub = F[faces]
        e = np.sort(np.stack([sub[:, [0, 1]], sub[:, [1, 2]], sub[:, [2, 0]]], axis=1), axis=2)
        _, inv, count = unique_rows(e.reshape(-1, 2), return_inverse=True, return_counts=True)
        open_edge = (count[inv] == 1).reshape(-1, 3)
        ends = np.bincount(e[open_edge].ravel(), minlength=int(F.max()) + 1)
        drop = (open_edge.sum(axis=1) >= 2) | (ends[sub] > 2).any(axis=1)
        if not drop.any():
            return faces
        faces = faces[~drop]
