"""Embedding a fine surface in a tet mesh: each surface vertex gets the tet that contains it (or the
nearest one) and its barycentric coordinates, so that it follows the simulated deformation:
x = Σ_a w_a (X_a + u_a) (linear interpolation, exact inside each linear tet)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..checks import mesh_arrays, whole_number
from ..errors import InputError, MeshError


@dataclass
class Embedding:
    """``tet`` (V,) containing element, ``weights`` (V, 4) barycentric coordinates, ``faces`` of
    the embedded surface, ``distance`` (V,) [m] how far outside its tet a vertex lies (0 inside)."""

    tet: np.ndarray
    weights: np.ndarray
    faces: np.ndarray
    distance: np.ndarray

    def positions(self, tets: np.ndarray, node_positions: np.ndarray) -> np.ndarray:
        """Deformed surface vertices [m] (V, 3) from node positions (N, 3)."""
        return np.einsum("vk,vkd->vd", self.weights, node_positions[tets[self.tet]])


def barycentric(P: np.ndarray, X: np.ndarray) -> np.ndarray:
    """Barycentric coordinates of points X (n, 3) in tets P (n, 4, 3)."""
    A = np.stack([P[:, 1] - P[:, 0], P[:, 2] - P[:, 0], P[:, 3] - P[:, 0]], axis=2)
    lam = np.linalg.solve(A, (X - P[:, 0])[..., None])[..., 0]
    return np.concatenate([1 - lam.sum(axis=1, keepdims=True), lam], axis=1)


def embed_surface(
    nodes: np.ndarray, tets: np.ndarray, V: np.ndarray, F: np.ndarray, candidates: int = 16
) -> Embedding:
    """Embed surface vertices V [m] (n, 3) in the tet mesh (nodes, tets). Each vertex is tested
    against the ``candidates`` tets with the nearest centroids (KD-tree); a vertex outside all of
    them (a fine surface slightly outside a coarse mesh) takes the candidate whose barycentric
    coordinates are least negative, extrapolating linearly."""
    from scipy.spatial import cKDTree

    nodes, tets = mesh_arrays(nodes, tets, 4, "embed_surface")
    V, F = mesh_arrays(V, F, 3, "embed_surface: the surface", cell="face", empty=True)
    if not whole_number(candidates, "candidates") >= 1:
        raise InputError(f"embed_surface: candidates = {candidates}; expected >= 1")
    cent = nodes[tets].mean(axis=1)
    k = min(candidates, len(tets))
    _, cand = cKDTree(cent).query(V, k=k)
    cand = cand.reshape(len(V), k)
    lost = np.nonzero(cand.max(axis=1) >= len(tets))[0]  # a distance that overflowed: no neighbour
    if lost.size:
        raise MeshError(
            f"embed_surface: surface vertex {int(lost[0])} at {V[lost[0]].tolist()} is too far from the "
            "tets to measure; expected a surface near the mesh [m]"
        )
    best_w = np.zeros((len(V), 4))
    best_t = np.zeros(len(V), dtype=np.int64)
    best_score = np.full(len(V), -np.inf)
    for j in range(k):
        t = cand[:, j]
        w = barycentric(nodes[tets[t]], V)
        score = w.min(axis=1)
        better = score > best_score
        best_score[better], best_t[better], best_w[better] = score[better], t[better], w[better]
    inside_pt = np.einsum(
        "vk,vkd->vd",
        np.clip(best_w, 0, None) / np.clip(best_w, 0, None).sum(1, keepdims=True),
        nodes[tets[best_t]],
    )
    dist = np.where(best_score >= -1e-9, 0.0, np.linalg.norm(V - inside_pt, axis=1))
    return Embedding(best_t, best_w, np.asarray(F, np.int64), dist)
