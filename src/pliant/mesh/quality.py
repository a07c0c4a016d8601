"""Tetrahedron quality: radius–edge ratio, dihedral angles, volume, and the critical time step each
element implies for a material (the worst element sets the explicit solver's cost)."""

from __future__ import annotations

from typing import Any

import numpy as np

from .. import _core
from ..checks import finite_number, mesh_arrays
from ..errors import InputError
from .primitives import TET_EDGES, tet_edge_lengths


# The regular tet's radius–edge ratio (circumradius / shortest edge), the least any tet has.
REGULAR_RADIUS_EDGE = float(np.sqrt(6) / 4)


def tet_quality(nodes: np.ndarray, tets: np.ndarray) -> dict[str, np.ndarray]:
    """Per tet: ``volume`` [m³], ``radius_edge`` (circumradius / shortest edge; √6/4 ≈ 0.612 for
    the regular tet), ``min_dihedral`` and ``max_dihedral`` [degrees] (70.53 for the regular tet),
    ``min_altitude`` [m] (the length in the stable time step)."""
    X, T = mesh_arrays(nodes, tets, 4, "tet_quality", empty=True)
    X, T = np.ascontiguousarray(X), np.ascontiguousarray(T, np.int32)
    vol, alt = _core.tet_geometry(X, T)
    P = X[T]
    a, b, c = P[:, 1] - P[:, 0], P[:, 2] - P[:, 0], P[:, 3] - P[:, 0]
    # Circumcentre offset from P0: (|a|²(b×c) + |b|²(c×a) + |c|²(a×b)) / (2 a·(b×c)).
    det = 2.0 * np.einsum("ij,ij->i", a, np.cross(b, c))
    num = (
        np.einsum("ij,ij->i", a, a)[:, None] * np.cross(b, c)
        + np.einsum("ij,ij->i", b, b)[:, None] * np.cross(c, a)
        + np.einsum("ij,ij->i", c, c)[:, None] * np.cross(a, b)
    )
    with np.errstate(divide="ignore", invalid="ignore"):
        R = np.linalg.norm(num, axis=1) / np.abs(det)
    edges = tet_edge_lengths(X, T)
    # Dihedral angle at each edge from the outward normals of the two faces sharing it.
    faces = [(1, 2, 3), (0, 3, 2), (0, 1, 3), (0, 2, 1)]  # face k is opposite corner k
    n = np.stack([np.cross(P[:, f[1]] - P[:, f[0]], P[:, f[2]] - P[:, f[0]]) for f in faces], 1)
    n /= np.maximum(np.linalg.norm(n, axis=2, keepdims=True), 1e-300)
    dih_list = []
    for i, j in TET_EDGES:  # edge (i, j) is shared by the faces opposite the two other corners
        k, l = [c for c in range(4) if c not in (i, j)]
        cosang = -np.einsum("ij,ij->i", n[:, k], n[:, l])
        dih_list.append(np.degrees(np.arccos(np.clip(cosang, -1.0, 1.0))))
    dih = np.stack(dih_list, 1)
    with np.errstate(divide="ignore", invalid="ignore"):
        re = R / edges.min(axis=1)
    return {
        "volume": np.asarray(vol),
        "radius_edge": re,
        "min_dihedral": dih.min(axis=1),
        "max_dihedral": dih.max(axis=1),
        "min_altitude": np.asarray(alt),
    }


def critical_time_steps(nodes, tets, material, density: float) -> np.ndarray:
    """Stable explicit step per element [s]: h_min / √((λ + 2μ)/ρ) (Belytschko et al. 2000, §6.3)."""
    c = dilatational_wave_speed(material, density)
    return tet_quality(nodes, tets)["min_altitude"] / c


def dilatational_wave_speed(material, density: float) -> float:
    """c_d = √((λ + 2μ)/ρ) [m/s] of a pliant material at small strain and a density [kg/m³] > 0
    (InputError naming either otherwise); a tet's stable step is its smallest altitude over it."""
    from ..materials import Material

    if not isinstance(material, Material):
        raise InputError(
            f"critical_time_steps: material = {type(material).__name__}; expected a pliant material"
        )
    rho = finite_number(density, "critical_time_steps: density", "kg/m^3")
    if not rho > 0:
        raise InputError(f"critical_time_steps: density = {rho:g}; expected > 0 [kg/m^3]")
    return float(np.sqrt((material.lam + 2.0 * material.mu) / rho))


def valid_elements(q: dict[str, np.ndarray]) -> np.ndarray:
    """Elements with a positive volume that is not negligible (relative volume V / h³ above
    1e-8, h the element's size from its altitude): the others are inverted or degenerate."""
    h = np.maximum(np.abs(q["min_altitude"]), np.finfo(float).tiny)
    with np.errstate(invalid="ignore", over="ignore"):
        return (q["volume"] > 0) & (q["volume"] > 1e-8 * h**3) & np.isfinite(q["radius_edge"])


def quality_summary(q: dict[str, np.ndarray], dt: np.ndarray | None = None) -> dict:
    """Statistics of :func:`tet_quality` (min, 5th percentile, median, 95th, max) over the valid
    elements, the counts of inverted, degenerate (zero-volume) and sliver elements, and, with
    per-element critical steps ``dt`` [s], the worst valid element and its cost factor (median /
    worst step). Every number is finite (JSON-safe); ``dt_critical`` is None without a valid
    element."""
    ok = valid_elements(q)
    out: dict[str, Any] = {"tets": int(len(q["volume"])), "inverted": int((q["volume"] < 0).sum())}
    out["degenerate"] = int((~ok).sum()) - out["inverted"]
    for k in ("volume", "radius_edge", "min_dihedral", "max_dihedral", "min_altitude"):
        v = q[k][ok] if ok.any() else np.zeros(1)
        out[k] = {
            "min": float(np.min(v)),
            "p5": float(np.percentile(v, 5)),
            "median": float(np.median(v)),
            "p95": float(np.percentile(v, 95)),
            "max": float(np.max(v)),
        }
    out["slivers_min_dihedral_below_5deg"] = int((q["min_dihedral"][ok] < 5).sum())
    if dt is not None:
        out["dt_critical"] = None
        if ok.any():
            idx = np.nonzero(ok)[0]
            worst = int(idx[np.argmin(dt[idx])])
            out["dt_critical"] = {
                "min": float(dt[worst]),
                "element": worst,
                "median": float(np.median(dt[idx])),
                "cost_factor": float(np.median(dt[idx]) / dt[worst]),
            }
    return out


def quality_histogram(path, q: dict[str, np.ndarray], dt: np.ndarray | None = None) -> None:
    """PNG with histograms of radius–edge ratio, dihedral angles and (optionally) critical steps."""
    from pathlib import Path

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ok = valid_elements(q)
    q = {k: v[ok] for k, v in q.items()}
    dt = dt[ok] if dt is not None else None
    n = 3 if dt is not None else 2
    fig, ax = plt.subplots(1, n, figsize=(5 * n, 4))
    ax[0].hist(np.clip(q["radius_edge"], 0, 5), bins=60, color="tab:blue")
    ax[0].axvline(REGULAR_RADIUS_EDGE, color="k", ls="--", label="regular tet")
    ax[0].set_xlabel("radius–edge ratio (clipped at 5)")
    ax[0].legend()
    ax[1].hist(q["min_dihedral"], bins=60, alpha=0.7, label="min")
    ax[1].hist(q["max_dihedral"], bins=60, alpha=0.7, label="max")
    ax[1].set_xlabel("dihedral angle [deg]")
    ax[1].legend()
    if dt is not None:
        ax[2].hist(dt * 1e6, bins=60, color="tab:red")
        ax[2].set_xlabel("critical time step [µs]")
    for a in ax:
        a.set_ylabel("tets")
    fig.tight_layout()
    from ..io.files import atomic_write

    try:
        atomic_write(Path(path), lambda tmp: fig.savefig(tmp, dpi=90, format="png"), "picture")
    finally:
        plt.close(fig)
