"""A blade: a cutting edge (a segment) or a flat blade (a rectangle) with a keyframed trajectory,
which cuts the elements it sweeps through (pliant.cutting). It pushes nothing: an ideal,
sharp blade; it is not a contact tool."""

from __future__ import annotations

import numpy as np

from ..checks import as_real, shown
from ..contact.tools import RigidTool
from ..errors import InputError

__all__ = ["Blade"]

MAX_SIZE = 1e150  # [m]: a blade's length and depth, whose squares (its swept areas) stay finite


class Blade(RigidTool):
    """A blade in its own frame: the cutting edge along x from −length/2 to +length/2 at z = 0,
    and, for ``depth`` > 0 [m], the flat of the blade in the plane y = 0 up to z = depth (a scalpel
    that moves edge first along −z, or slides along its own plane). Keyframes as any tool
    (:meth:`at`: time [s], position [m], rotation). ``depth`` = 0: the edge alone (it cuts only
    the surface it sweeps; moving along its own length it cuts nothing)."""

    kind = None  # not a contact tool: the engine never sees it

    def __init__(self, length: float, depth: float = 0.0, **kw):
        self.length = as_real(length)  # a bool or a string is not a length
        self.depth = as_real(depth)
        # The swept triangles' areas (a length squared) must be finite: at most MAX_SIZE.
        if not (0 < self.length <= MAX_SIZE):
            raise InputError(
                f"Blade: length = {shown(length)}; expected a length > 0 [m], at most {MAX_SIZE:g}"
            )
        if not (0 <= self.depth <= MAX_SIZE):
            raise InputError(
                f"Blade: depth = {shown(depth)}; expected a length >= 0 [m], at most {MAX_SIZE:g}"
            )
        kw.setdefault("name", "blade")
        super().__init__(**kw)

    def corners(self, t: float) -> np.ndarray:
        """The blade's corners [m] (4, 3) at time t: edge ends, then the back's (equal to the edge's
        for depth 0)."""
        R, p = self.pose(t)
        h = self.length / 2
        local = np.array([[-h, 0, 0], [h, 0, 0], [h, 0, self.depth], [-h, 0, self.depth]])
        return local @ R.T + p

    def swept(self, t0: float, t1: float) -> np.ndarray:
        """Triangles [m] (K, 3, 3) of the surface the blade cut from t0 to t1 [s]: what its edge
        swept (cutting edge first) and the flat where it is at t1 (slicing along its own plane;
        cut every few steps, the flats' union covers the slice). The blunt back and sides cut
        nothing. Zero-area triangles (a segment blade's flat, a still edge's sweep) are left out."""
        a, b = self.corners(t0), self.corners(t1)
        T = np.array([[a[0], a[1], b[1]], [a[0], b[1], b[0]], [b[0], b[1], b[2]], [b[0], b[2], b[3]]])
        area = np.linalg.norm(np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0]), axis=1)
        scale = max(self.length, self.depth) ** 2
        return T[area > 1e-12 * scale]
