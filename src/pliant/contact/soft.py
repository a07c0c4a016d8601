"""Contact between deformable bodies (and of a body with itself): which bodies touch which, with
what friction, and the surface the engine needs (cpp/include/pliant/soft_contact.hpp).

A *body* is a connected part of the mesh (elements joined through shared nodes), numbered in the
order of its first element: :func:`body_labels`. Two meshes added with ``ModelBuilder.add_mesh``
are two bodies; NiftySim sub-models that are not merged are bodies too. Pieces cut from a body
keep its number (they touch each other if that body has self contact).

Method (docs/contact.md): node-to-triangle kinematic contact with Coulomb friction, momentum
conserved by each pair; every surface node of a body is checked against the triangles of the
bodies it may touch (the boundary triangles of the tetrahedra, so the simulation surface, not an
embedded visual one, collides).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..checks import as_index, finite_number, real_array, shown
from ..errors import InputError

__all__ = ["SoftContact", "body_labels", "sheet_labels", "sheets_apart"]

# Most bodies soft contact takes (its pair table holds one entry per ordered pair of bodies).
MAX_BODIES = 2048

# Verlet skin as a fraction of the median surface edge (soft_contact.hpp: candidate lists are
# rebuilt when a node has moved half of it; larger skins rebuild less often and list more).
SKIN_FRACTION = 0.3


def body_labels(tets: np.ndarray, n_nodes: int) -> np.ndarray:
    """Body of each element (M,): connected components of the mesh through shared nodes, numbered
    in the order of their first element (tets (M, 4), or any cells: a sheet's triangles (K, 3))."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    T = np.asarray(tets, np.int64)
    M = T.shape[0]
    if M == 0:  # membranes alone: no tets, no bodies of them
        return np.zeros(0, np.int64)
    rows = np.repeat(np.arange(M), T.shape[1])
    g = coo_matrix((np.ones(T.size), (rows, T.ravel())), shape=(M, n_nodes)).tocsr()
    _, comp = connected_components(g @ g.T, directed=False)
    first = np.full(comp.max() + 1, M)
    np.minimum.at(first, comp, np.arange(M))
    rank = np.empty_like(first)
    rank[np.argsort(first, kind="stable")] = np.arange(first.size)
    return rank[comp]


@dataclass
class SoftContact:
    """Contact between bodies (``ModelBuilder.set_soft_contact``).

    mu_s, mu_k: Coulomb friction (static, kinetic) between soft surfaces; pairs: the pairs of
    bodies (a, b) that touch, or None for every pair of different bodies; self_contact: True for
    every body, or the bodies that touch themselves; skin: the broad phase's Verlet skin [m]
    (default SKIN_FRACTION × the median surface edge); labels: body per element, fixed (set by
    ``ModelBuilder.split`` so that cut pieces keep their body), or None (computed at finalize);
    names: what messages call each body number (a scene's body names), where known.
    """

    mu_s: float = 0.0
    mu_k: float = 0.0
    pairs: tuple[tuple[int, int], ...] | None = None
    self_contact: bool | tuple[int, ...] = False
    skin: float | None = None
    labels: np.ndarray | None = None
    names: dict[int, str] | None = None

    def name(self, body: int) -> str:
        """How messages name body number ``body``: its scene name, or 'body N'."""
        known = (self.names or {}).get(body)
        return f"body {body} ({known!r})" if known else f"body {body}"

    @staticmethod
    def make(friction=0.0, pairs=None, self_contact=False, skin=None) -> SoftContact:
        """Checked settings; friction: μ or (μs, μk)."""
        mu = real_array(friction)
        mu = None if mu is None else np.atleast_1d(mu)
        if mu is None or mu.shape not in ((1,), (2,)) or not np.all(np.isfinite(mu)) or np.any(mu < 0):
            raise InputError(
                f"soft contact friction = {shown(friction)}; expected μ or (μs, μk), finite, >= 0"
            )
        mu_s, mu_k = (float(mu[0]), float(mu[-1]))
        if mu_k > mu_s:
            raise InputError(f"soft contact friction = {shown(friction)}: kinetic μk above static μs")
        if pairs is not None:
            try:
                pairs = tuple((as_index(a), as_index(b)) for a, b in pairs)
            except (TypeError, ValueError):
                raise InputError(
                    f"soft contact pairs = {shown(pairs)}; expected pairs of body numbers [(a, b), ...]"
                ) from None
        if isinstance(self_contact, np.bool_):
            self_contact = bool(self_contact)
        if not isinstance(self_contact, bool):
            try:
                self_contact = tuple(as_index(b) for b in self_contact)
            except (TypeError, ValueError):
                raise InputError(
                    f"self_contact = {shown(self_contact)}; expected True, False or a list of body numbers"
                ) from None
        if skin is not None:
            skin = finite_number(skin, "soft contact skin", "m")
            if not skin > 0:
                raise InputError(f"soft contact skin = {shown(skin)}; expected > 0 [m]")
        return SoftContact(mu_s, mu_k, pairs, self_contact, skin)

    def pair_table(
        self, n_bodies: int, n_solid: int | None = None
    ) -> tuple[np.ndarray, list[tuple[int, int]]]:
        """The engine's pair table (n_bodies, n_bodies): pair index of (slave body, master body), −1
        where they do not touch; and the pairs (a ≤ b) in index order. Bodies from ``n_solid`` on
        are sheets of membranes (``n_solid`` is kept for messages)."""
        n_solid = n_bodies if n_solid is None else n_solid
        if n_bodies > MAX_BODIES:
            raise InputError(
                f"soft contact: the mesh has {n_bodies} separate bodies (connected parts); expected at "
                f"most {MAX_BODIES} (check for loose elements: pliant mesh quality)"
            )
        wanted: set[tuple[int, int]] = set()
        if self.pairs is None:
            wanted |= {(a, b) for a in range(n_bodies) for b in range(a + 1, n_bodies)}
        else:
            for a, b in self.pairs:
                for x in (a, b):
                    if not 0 <= x < n_bodies:
                        raise InputError(
                            f"soft contact pair ({a}, {b}): body {x} does not exist; the mesh has "
                            f"{n_bodies} bodies (0 to {n_bodies - 1}; ModelBuilder.bodies())"
                        )
                wanted.add((min(a, b), max(a, b)))
        selfs = range(n_bodies) if self.self_contact is True else (self.self_contact or ())
        for b in selfs:
            if not 0 <= b < n_bodies:
                raise InputError(
                    f"self_contact body {b} does not exist; the mesh has {n_bodies} bodies"
                    + (f" (sheets of membranes from {n_solid})" if n_solid < n_bodies else "")
                )
            wanted.add((b, b))
        order = sorted(wanted)
        table = np.full((n_bodies, n_bodies), -1, np.int64)
        for k, (a, b) in enumerate(order):
            table[a, b] = table[b, a] = k
        return table, order


def on_rollers(X: np.ndarray, faces: np.ndarray, held: np.ndarray) -> np.ndarray:
    """Per boundary face (F, 3): whether it lies on a roller or a symmetry plane, i.e. its
    reference normal is a coordinate axis d and each of its nodes has DOF d held while some DOF
    of the face stays free. Such a face is a mirror or a support, not a surface another body can
    reach; in contact it would be (a node on a quarter model's symmetry plane lies on the other
    body's symmetry face: at distance zero, never inside). X: nodes [m] (N, 3); held: (N, 3)
    bool, DOF held by a constraint."""
    n = np.cross(X[faces[:, 1]] - X[faces[:, 0]], X[faces[:, 2]] - X[faces[:, 0]])
    n /= np.maximum(np.linalg.norm(n, axis=1), 1e-300)[:, None]
    axis = np.argmax(np.abs(n), axis=1)
    aligned = np.abs(n[np.arange(len(n)), axis]) > 1.0 - 1e-9
    held_normal = held[faces, axis[:, None]].all(axis=1)
    all_held = held[faces].all(axis=(1, 2))
    return aligned & held_normal & ~all_held


def sheets_apart(F: np.ndarray, tets: np.ndarray, n_nodes: int) -> tuple[np.ndarray, np.ndarray]:
    """Of membranes F (K, 3) with a node off the tets (M, 4), (ModelBuilder.free_membranes): the
    indices of those in sheets apart from the tets, which take part in soft contact as bodies of
    their own, and of those in sheets that share a node with the tets (a flap on a solid), which
    do not (their nodes would belong to two bodies). Both ascending."""
    from ..mesh.topology import faces_off

    F = np.asarray(F, np.int64).reshape(-1, 3)
    off = faces_off(F, tets)
    if not off.size:
        return off, off
    comp = body_labels(F[off], n_nodes)
    touches = np.isin(F[off], np.asarray(tets, np.int64)).any(axis=1)
    joined = np.zeros(int(comp.max()) + 1, bool)
    joined[comp[touches]] = True
    return off[~joined[comp]], off[joined[comp]]


def sheet_labels(F: np.ndarray, n_nodes: int, n_solid: int) -> np.ndarray:
    """Body number (K,) of each membrane of the sheets apart from the tets, F (K, 3) (sheets_apart):
    each connected sheet a body, numbered after the ``n_solid`` bodies of the tets in the order of
    its first membrane."""
    F = np.asarray(F, np.int64).reshape(-1, 3)
    return n_solid + body_labels(F, n_nodes) if len(F) else np.zeros(0, np.int64)


def engine_surface(
    contact: SoftContact,
    X: np.ndarray,
    T: np.ndarray,
    node_rank: np.ndarray,
    held: np.ndarray | None = None,
    sheets: tuple[np.ndarray, np.ndarray] | None = None,
) -> dict:
    """The engine's soft-contact arrays (Model → _core.Engine): the boundary triangles of the bodies
    that touch something (outward) but those on rollers or symmetry planes (:func:`on_rollers`;
    ``held``: (N, 3) bool, DOFs held), their nodes in engine numbering with body labels, the pair
    table and friction per pair, the skin [m]. ``sheets``: membranes apart from the tets, as their
    triangles (K, 3) and thicknesses [m] (K,): each connected sheet is a body, numbered after the
    tets' bodies, two-sided (soft_contact.hpp, soft_sheet_target), its half thickness the largest
    of its membranes'. Also 'pairs' (the pairs in index order) and 'labels' (body per element)."""
    from ..mesh.topology import boundary_faces

    labels = contact.labels if contact.labels is not None else body_labels(T, X.shape[0])
    n_solid = int(labels.max()) + 1 if labels.size else 0
    sheet_F, sheet_t = sheets if sheets is not None else (np.zeros((0, 3), np.int64), np.zeros(0))
    sheet_body = sheet_labels(sheet_F, X.shape[0], n_solid)
    n_bodies = int(sheet_body.max()) + 1 if sheet_body.size else n_solid
    table, pairs = contact.pair_table(n_bodies, n_solid)
    if not pairs:  # one body without self contact: nothing to touch
        return dict(
            no_surface(), pairs=[], labels=labels, sheet_nodes=None, sheet_labels=None, sheet_faces=None
        )
    active = np.nonzero((table >= 0).any(axis=1))[0]
    faces, owner = boundary_faces(T)
    touching = np.isin(labels[owner], active)
    if held is not None:
        touching &= ~on_rollers(X, faces, held)
    on_sheet = np.isin(sheet_body, active)
    faces = np.vstack([faces[touching], np.asarray(sheet_F, np.int64)[on_sheet]])
    face_body = np.concatenate([labels[owner[touching]], sheet_body[on_sheet]])
    half = np.zeros(n_bodies)
    np.maximum.at(half, sheet_body, 0.5 * np.asarray(sheet_t, float))
    sheet_node_body = np.full(X.shape[0], -1, np.int64)  # for initial_overlap
    sheet_node_body[np.asarray(sheet_F, np.int64).ravel()] = np.repeat(sheet_body, 3)
    sheet_nodes = np.nonzero(sheet_node_body >= 0)[0]
    nodes = np.unique(faces)
    node_body = np.zeros(X.shape[0], np.int64)
    node_body[faces.ravel()] = np.repeat(face_body, 3)
    order = np.argsort(node_rank[nodes], kind="stable")  # engine order: sequential access
    nodes = nodes[order]
    index = np.full(X.shape[0], -1, np.int64)
    index[nodes] = np.arange(nodes.size)
    edges = np.linalg.norm(X[faces] - X[np.roll(faces, 1, axis=1)], axis=-1)
    median_edge = float(np.median(edges))
    skin = contact.skin if contact.skin is not None else SKIN_FRACTION * median_edge
    if not (math.isfinite(skin) and skin > 0):
        raise InputError("soft contact: the bodies have no surface to touch")
    across = float(np.linalg.norm(np.ptp(X[nodes], axis=0)))
    if skin > across:  # every node would list the 32 nearest triangles of everything: slow, and a units slip
        raise InputError(
            f"soft contact skin = {shown(skin)} m is larger than the contact surfaces ({across:.3g} m "
            f"across); expected a fraction of an element (default {SKIN_FRACTION} × the median "
            f"surface edge: {SKIN_FRACTION * median_edge:.3g} m)"
        )
    return dict(
        soft_nodes=[int(n) for n in node_rank[nodes]],
        soft_label=[int(b) for b in node_body[nodes]],
        soft_tris=[int(i) for i in index[faces].ravel()],
        soft_pair=[int(p) for p in table.ravel()],
        soft_labels=int(n_bodies),
        soft_mu=[m for _ in pairs for m in (contact.mu_s, contact.mu_k)],
        soft_skin=float(skin),
        soft_sheet_h=[float(h) for h in half],
        pairs=pairs,
        labels=labels,
        sheet_nodes=sheet_nodes,
        sheet_labels=sheet_node_body[sheet_nodes],
        sheet_faces=(np.asarray(sheet_F, np.int64)[on_sheet], sheet_body[on_sheet]),
    )


def initial_overlap(
    X: np.ndarray, T: np.ndarray, labels: np.ndarray, pairs, sheet_nodes=None, sheet_labels=None
) -> dict | None:
    """The deepest node that starts inside another body it touches: a dict with ``node``,
    its ``body``, the ``other`` body, ``depth`` [m] (distance to the other's surface) and ``band``
    [m] (the soft-contact band at the closest triangle: ``_core.soft_band`` × its mean edge, the
    deepest a node inside counts as a contact); None if no node starts inside. X: reference nodes
    [m] (N, 3); T: tets (M, 4); labels: body per element (M,); pairs: the touching (a, b), a <= b
    (pairs of one body, self contact, are not checked: a body's own surface is where it starts);
    sheet_nodes, sheet_labels: the nodes of sheets of membranes and their bodies (a sheet that
    starts through a solid has nodes inside it; a solid's nodes cannot be inside a sheet). Each
    node is located among the 8 tets with the nearest centroids, of all bodies at once."""
    from scipy.spatial import cKDTree

    from .. import _core
    from ..mesh.embed import barycentric
    from ..mesh.topology import boundary_faces

    sheet_nodes = np.zeros(0, np.int64) if sheet_nodes is None else np.asarray(sheet_nodes, np.int64)
    sheet_labels = np.zeros(0, np.int64) if sheet_labels is None else np.asarray(sheet_labels, np.int64)
    n_bodies = max(int(labels.max(initial=-1)) + 1, int(sheet_labels.max(initial=-1)) + 1)
    touch = np.zeros((n_bodies, n_bodies), bool)
    for a, b in pairs:
        touch[a, b] = touch[b, a] = a != b
    if not touch.any() or len(T) == 0:  # sheets alone: nothing to start inside
        return None
    faces, owner = boundary_faces(T)
    face_body = labels[owner]
    node_body = np.full(X.shape[0], -1, np.int64)
    node_body[T.ravel()] = np.repeat(labels, 4)
    node_body[sheet_nodes] = sheet_labels
    # Every node, not only the surface's: a body given twice (a copied [[body]] without its
    # translate) has its surface on the other's, and its inner nodes deep inside.
    nodes = np.nonzero(node_body >= 0)[0]
    nodes = nodes[touch[node_body[nodes]].any(axis=1)]
    k = min(8, len(T))
    _, cand = cKDTree(X[T].mean(axis=1)).query(X[nodes], k=k)
    cand = cand.reshape(len(nodes), k)
    inside = np.full(len(nodes), -1, np.int64)  # the body a node lies in (−1: none)
    for j in range(k):
        other = labels[cand[:, j]]
        w = barycentric(X[T[cand[:, j]]], X[nodes])
        hit = (inside < 0) & touch[node_body[nodes], other] & (w.min(axis=1) >= -1e-9)  # faces too
        inside[hit] = other[hit]
    worst = None
    for other in np.unique(inside[inside >= 0]):
        sel = nodes[inside == other]
        worst = _deepest(X, sel, node_body, faces[face_body == other], int(other), _core.soft_band, worst)
    return worst


def on_a_sheet(X, T, labels, pairs, sheet_nodes, sheet_labels, sheet_faces) -> dict | None:
    """The lowest-numbered node that starts on the mid-surface of a sheet of membranes its body
    touches (within 1e-9 of the sheet's median edge: round-off): a dict with ``node``, its
    ``body``, the ``sheet`` and the ``distance`` [m]; None if no node does. Contact keeps a node on
    the side of a sheet it was on (soft_sheet_target), and a node on the mid-surface is on neither:
    two sheets laid in one plane, or a sheet on a solid's face, would tangle. X: reference nodes [m]
    (N, 3); T: tets (M, 4) and labels: body per element (M,) (their boundary's nodes are a solid's);
    pairs: the touching (a, b); sheet_nodes, sheet_labels: the sheets' nodes and bodies;
    sheet_faces: their triangles (K, 3) and each one's body (K,)."""
    from scipy.spatial import cKDTree

    from ..mesh.topology import boundary_faces
    from .sdf import point_triangle_distance

    if sheet_faces is None or not len(sheet_faces[0]):
        return None
    tris, tri_body = sheet_faces
    node_body = np.full(X.shape[0], -1, np.int64)
    if len(T):
        faces, owner = boundary_faces(T)
        node_body[faces.ravel()] = np.repeat(labels[owner], 3)
    node_body[np.asarray(sheet_nodes, np.int64)] = sheet_labels
    found = None
    for sheet, other in [(a, b) for a, b in pairs if a != b] + [(b, a) for a, b in pairs if a != b]:
        tri = X[tris[tri_body == sheet]]
        nodes = np.nonzero(node_body == other)[0]
        if not len(tri) or not len(nodes):
            continue
        k = min(16, len(tri))
        _, cand = cKDTree(tri.mean(axis=1)).query(X[nodes], k=k)
        cand = cand.reshape(len(nodes), k)
        d = np.full(len(nodes), np.inf)
        for j in range(k):
            d = np.minimum(d, point_triangle_distance(X[nodes], *(tri[cand[:, j], c] for c in range(3)))[0])
        edge = float(np.median(np.linalg.norm(tri - np.roll(tri, 1, axis=1), axis=-1)))
        on = np.nonzero(d <= 1e-9 * edge)[0]
        if len(on) and (found is None or nodes[on[0]] < found["node"]):
            found = dict(node=int(nodes[on[0]]), body=int(other), sheet=int(sheet), distance=float(d[on[0]]))
    return found


def _deepest(X, nodes, node_body, faces, other: int, band_fraction: float, worst: dict | None) -> dict | None:
    """initial_overlap's record for the deepest of ``nodes`` below ``faces`` (body ``other``'s
    surface), if deeper than ``worst`` and than round-off (a node on that surface touches)."""
    from scipy.spatial import cKDTree

    from .sdf import point_triangle_distance

    tri, P = X[faces], X[nodes]
    kf = min(16, len(tri))
    _, fc = cKDTree(tri.mean(axis=1)).query(P, k=kf)
    fc = fc.reshape(len(P), kf)
    depth, near = np.full(len(P), np.inf), np.zeros(len(P), np.int64)
    for j in range(kf):
        d, _ = point_triangle_distance(P, *(tri[fc[:, j], c] for c in range(3)))
        better = d < depth
        depth[better], near[better] = d[better], fc[better, j]
    # The candidates' nearest faces bound each depth from above; the deepest few get it exactly,
    # against every face of the other body (a large face among small ones can be missed).
    top = np.argsort(depth)[-32:]
    for j in top:
        d, _ = point_triangle_distance(
            np.repeat(P[j : j + 1], len(tri), axis=0), tri[:, 0], tri[:, 1], tri[:, 2]
        )
        depth[j], near[j] = d.min(), int(np.argmin(d))
    i = int(top[np.argmax(depth[top])])  # exact depths only: never deeper than the truth
    t = tri[near[i]]
    band = band_fraction * float(np.linalg.norm(t - np.roll(t, 1, axis=0), axis=1).mean())
    if depth[i] <= 1e-9 * band or (worst is not None and depth[i] <= worst["depth"]):
        return worst
    return dict(
        node=int(nodes[i]), body=int(node_body[nodes[i]]), other=other, depth=float(depth[i]), band=band
    )


def no_surface() -> dict:
    """The engine's soft-contact arrays of a model without soft contact."""
    return dict(
        soft_nodes=[],
        soft_label=[],
        soft_tris=[],
        soft_pair=[],
        soft_labels=0,
        soft_mu=[],
        soft_skin=0.0,
        soft_sheet_h=[],
    )
