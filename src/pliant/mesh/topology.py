"""Topology of tet meshes: boundary faces and nodes."""

from __future__ import annotations

import numpy as np


def boundary_faces(tets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Boundary triangles (F, 3), outward for positive tets, and the element of each (F,)."""
    tets = np.asarray(tets)
    local = np.array([[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]])
    faces = tets[:, local].reshape(-1, 3)
    owner = np.repeat(np.arange(len(tets)), 4)
    key = np.sort(faces, axis=1)
    _, inv, count = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    once = count[inv.ravel()] == 1
    return faces[once], owner[once]


def boundary_nodes(tets: np.ndarray) -> np.ndarray:
    """Indices of the nodes on the boundary faces, ascending."""
    return np.unique(boundary_faces(tets)[0])
