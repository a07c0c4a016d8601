"""The patch of each membrane triangle for rotation-free bending (membrane.hpp,
``membrane_bending_forces``; cpp/src/model_bending.cpp): the node across each of its edges, and
the two across the other edges of each of those neighbours (the stencils of its edges' gradients)."""

from __future__ import annotations

import numpy as np

from .. import _core

__all__ = ["across_edges", "clamp_edges", "patch_nodes"]


def across_edges(faces: np.ndarray) -> np.ndarray:
    """For each triangle k of ``faces`` (K, 3) (node ids) and each edge e (opposite corner e), the
    node of the one other triangle that shares the edge, (K, 3) int64; ``_core.free_edge`` where no
    other triangle or more than one shares it (a boundary, or a non-manifold edge) or the other lies
    on the same three nodes."""
    return _across(faces)[0]


def patch_nodes(faces: np.ndarray, across: np.ndarray) -> np.ndarray:
    """The patch of each triangle (K, 9) int64 (membrane.hpp, kMembraneSlots less the corners):
    ``across`` (K, 3) (across_edges, clamped edges marked), then for each edge e with a node across
    it the nodes across that neighbour's edges opposite corners (e + 1) % 3 and (e + 2) % 3 of the
    triangle, −1 where there is none (a node may be in the patch twice)."""
    F = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    K = F.shape[0]
    out = np.full((K, 9), -1, dtype=np.int64)
    out[:, :3] = across
    if K == 0:
        return out
    neighbour = _across(F)[1]
    for e in range(3):
        nb = neighbour[:, e]
        has = (nb >= 0) & (across[:, e] >= 0)
        for side, corner in enumerate(((e + 1) % 3, (e + 2) % 3)):
            node = F[:, corner]
            # The neighbour's local index of the triangle's corner: its edge opposite it.
            loc = np.argmax(F[np.maximum(nb, 0)] == node[:, None], axis=1)
            ring = np.where(has, across[np.maximum(nb, 0), loc], -1)
            out[:, 3 + 2 * e + side] = np.maximum(ring, -1)
    return out


def _across(faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """across_edges, and the triangle across each edge (K, 3) (−1 where no node is across)."""
    F = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    out = np.full(F.shape, int(_core.free_edge), dtype=np.int64)
    tri = np.full(F.shape, -1, dtype=np.int64)
    if F.shape[0] == 0:
        return out, tri
    a, b = _edge_nodes(F)
    lo, hi = np.minimum(a, b).ravel(), np.maximum(a, b).ravel()
    order = np.lexsort((hi, lo))
    key = np.stack([lo[order], hi[order]], axis=1)
    starts = np.flatnonzero(np.r_[True, np.any(key[1:] != key[:-1], axis=1)])
    counts = np.diff(np.r_[starts, len(order)])
    pairs = starts[counts == 2]
    first, second = order[pairs], order[pairs + 1]
    opposite = F.reshape(-1)  # half-edge 3 k + e is opposite F[k, e]
    flat, tflat = out.reshape(-1), tri.reshape(-1)
    for x, y in ((first, second), (second, first)):
        fine = opposite[y] != opposite[x]
        flat[x[fine]] = opposite[y[fine]]
        tflat[x[fine]] = y[fine] // 3
    return out, tri


def clamp_edges(across: np.ndarray, faces: np.ndarray, clamped: np.ndarray) -> None:
    """Marks ``_core.clamped_edge`` in ``across`` (K, 3) (across_edges of ``faces``) each free edge
    whose two nodes ``clamped`` (a boolean mask over node ids) holds."""
    a, b = _edge_nodes(np.asarray(faces, dtype=np.int64).reshape(-1, 3))
    across[(across == int(_core.free_edge)) & clamped[a] & clamped[b]] = int(_core.clamped_edge)


def _edge_nodes(F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The two nodes (K, 3) each of edge e of each triangle: (F[k, e+1], F[k, e+2])."""
    return F[:, [1, 2, 0]], F[:, [2, 0, 1]]
