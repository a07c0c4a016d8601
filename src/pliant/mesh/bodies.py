"""The closed bodies of a surface and how they nest: a body inside another is a cavity of it (its
faces pointing into the cavity) or an inclusion (pointing out, as its container's do); the files'
own orientation says which, as it does for fTetWild's winding-number filter (Jacobson et al. 2013,
"Robust inside-outside segmentation using generalized winding numbers", ACM TOG 32(4)).
"""

from __future__ import annotations

import numpy as np

# Points of a body tested against each other body: enough to tell nested from overlapping bodies.
# A body is nested when nine in ten of them are inside: a cavity that touches its container's wall,
# or pokes through it where a scan self-intersects, has a few on or beyond it.
SAMPLES = 64
NESTED = 0.9


def winding_number(V: np.ndarray, F: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Generalized winding number of the closed triangle surface V [m] (n, 3), F (f, 3) at points [m]
    (q, 3): the solid angles its triangles subtend, summed over 4π (Van Oosterom & Strackee 1983,
    IEEE TBME 30(2), eq. 8). ±1 inside (+1 for outward faces), 0 outside. Shape (q,)."""
    P = np.asarray(V, float)[np.asarray(F, np.int64)]  # (f, 3, 3)
    out = np.empty(len(points))
    for i, q in enumerate(np.asarray(points, float)):
        a, b, c = (P[:, k] - q for k in range(3))
        la, lb, lc = (np.linalg.norm(x, axis=1) for x in (a, b, c))
        num = np.einsum("ij,ij->i", a, np.cross(b, c))
        den = (
            la * lb * lc
            + np.einsum("ij,ij->i", a, b) * lc
            + np.einsum("ij,ij->i", b, c) * la
            + np.einsum("ij,ij->i", c, a) * lb
        )
        out[i] = 2.0 * np.arctan2(num, den).sum() / (4.0 * np.pi)
    return out


def parents(bodies: list) -> list[int]:
    """For closed bodies (trimesh meshes), the index of the smallest body each lies inside (at least
    ``NESTED`` of up to ``SAMPLES`` of its vertices at a winding number beyond ½), or −1."""
    with np.errstate(divide="ignore", invalid="ignore"):  # trimesh's centre of mass of a flat piece
        vols = [abs(float(b.volume)) for b in bodies]
    box = [np.asarray(b.bounds) for b in bodies]
    out = []
    for j, b in enumerate(bodies):
        Vb = np.asarray(b.vertices)
        pts = Vb[np.linspace(0, len(Vb) - 1, min(SAMPLES, len(Vb))).astype(int)]
        inside = [
            i
            for i, a in enumerate(bodies)
            if i != j
            and vols[i] > vols[j]
            and (box[i][0] <= box[j][1]).all()  # the boxes meet
            and (box[j][0] <= box[i][1]).all()
            and (np.abs(winding_number(a.vertices, a.faces, pts)) > 0.5).mean() >= NESTED
        ]
        out.append(min(inside, key=lambda i: vols[i]) if inside else -1)
    return out


def roots(parent: list[int]) -> list[int]:
    """The outermost body around each body (itself when it lies in none)."""
    out = []
    for j in range(len(parent)):
        while parent[j] >= 0:
            j = parent[j]
        out.append(j)
    return out


def groups(bodies: list, parent: list[int] | None = None) -> list[list[int]]:
    """The bodies grouped by their outermost body: each group its outer body's index first, then the
    cavities and inclusions inside it; groups in the order of their outer bodies. ``parent``: the
    bodies' parents() where known."""
    r = roots(parents(bodies) if parent is None else parent)
    return [
        [j] + [k for k in range(len(bodies)) if r[k] == j and k != j] for j in range(len(bodies)) if r[j] == j
    ]


def filled_volumes(bodies: list, parent: list[int]) -> list[float]:
    """Volume [m³] each outer body's group fills where its winding number is beyond ½ (what
    fTetWild keeps), one value per outer body (parent −1), in their order. Each body's own layer,
    inside it and outside its children, has the winding number of the signs (+1 faces out, −1 in)
    of it and every body around it (taken as if the outer body faced out); bodies nested whole and
    children apart."""
    sign = [1 if float(b.volume) > 0 else -1 for b in bodies]
    vol = [abs(float(b.volume)) for b in bodies]
    r = roots(parent)
    out = {j: 0.0 for j in range(len(bodies)) if parent[j] < 0}
    for k in range(len(bodies)):
        w, j = 0, k
        while j >= 0:
            w, j = w + sign[j], parent[j]
        layer = vol[k] - sum(vol[c] for c in range(len(bodies)) if parent[c] == k)
        out[r[k]] += layer if w * sign[r[k]] > 0 else 0.0  # an outer body facing in: as if out
    return list(out.values())
