"""Offscreen PNG of a deformed tet mesh: its boundary surface coloured by a per-element field
(von Mises stress by default), with a colour bar. Uses matplotlib's Agg backend (no display)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..mesh.topology import boundary_faces


def render_png(
    path,
    positions: np.ndarray,
    tets: np.ndarray,
    element_field: np.ndarray,
    label: str = "von Mises stress [Pa]",
    title: str = "",
    max_faces: int = 60000,
    surface: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
    sheets: np.ndarray | None = None,
) -> Path:
    """Write a PNG [path] of the surface of the mesh at ``positions`` [m] (N, 3), coloured by
    ``element_field`` (M,). ``surface``: draw this surface instead of the mesh's boundary, as
    (vertex positions [m] (V, 3), faces (F, 3), the element each face lies in (F,)): an embedded
    fine surface following a coarse simulation mesh. ``sheets``: triangles (K, 3) of ``positions``
    drawn beside it in grey (sheets of membranes apart from the tets). Written atomically."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    if surface is None:
        faces, owner = boundary_faces(np.asarray(tets))
        P = np.asarray(positions, float)
    else:
        P, faces, owner = (np.asarray(a) for a in surface)
        P = P.astype(float)
    if len(faces) > max_faces:  # keep rendering time bounded
        keep = np.linspace(0, len(faces) - 1, max_faces).astype(int)
        faces, owner = faces[keep], owner[keep]
    vals = np.asarray(element_field, float)[owner]
    fig = plt.figure(figsize=(8, 6), dpi=100)
    ax = fig.add_subplot(111, projection="3d")
    # Colour range: 1st to 99th percentile, so that a few stress peaks (at supports, tool edges)
    # do not flatten the picture; the colour bar says so.
    lo_v, hi_v = np.percentile(vals, [1, 99]) if vals.size > 100 else (vals.min(), vals.max())
    top = float(hi_v) if hi_v > lo_v else float(lo_v) + 1.0
    norm = matplotlib.colors.Normalize(vmin=float(lo_v), vmax=top)
    cmap = matplotlib.colormaps["viridis"]
    tri = P[faces]
    colours = cmap(norm(vals))
    if sheets is not None and len(sheets):  # one collection: matplotlib orders its faces by depth
        S = np.asarray(positions, float)[np.asarray(sheets)[:max_faces]]
        tri = np.concatenate([tri, S])
        colours = np.concatenate([colours, np.tile([0.75, 0.75, 0.75, 1.0], (len(S), 1))])
        P = np.concatenate([P, S.reshape(-1, 3)])
    # Simple Lambert shading from a fixed light, on top of the field colours.
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-30)
    shade = 0.55 + 0.45 * np.abs(n @ np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8]))
    colours[:, :3] *= shade[:, None]
    ax.add_collection3d(Poly3DCollection(tri, facecolors=colours, edgecolors="none"))
    lo, hi = P.min(axis=0), P.max(axis=0)
    c, r = (lo + hi) / 2, (hi - lo).max() / 2 or 1.0
    ax.set_xlim(c[0] - r, c[0] + r)
    ax.set_ylim(c[1] - r, c[1] + r)
    ax.set_zlim(c[2] - r, c[2] + r)
    ax.set_box_aspect((1, 1, 1))
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_zlabel("z [m]")
    ax.set_title(plain_title(title))
    sm = matplotlib.cm.ScalarMappable(norm=norm, cmap=cmap)
    fig.colorbar(sm, ax=ax, shrink=0.7, extend="both", label=f"{label} (1st–99th percentile)")
    from ..io.files import atomic_write

    try:
        return atomic_write(Path(path), lambda tmp: fig.savefig(tmp, format="png"), "picture")
    finally:
        plt.close(fig)


def plain_title(title: str, limit: int = 100) -> str:
    """A title matplotlib draws as plain text in bounded time: one line, control characters
    dropped, ``$`` escaped (no mathtext), at most ``limit`` characters (text layout is slow in the
    length)."""
    t = " ".join("".join(c if c.isprintable() else " " for c in str(title)[: 4 * limit]).split())
    t = t if len(t) <= limit else t[: limit - 1] + "…"
    return t.replace("$", r"\$")
