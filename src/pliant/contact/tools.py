"""Rigid tools: shapes with friction and a trajectory (keyframes or poses set between steps), and
the quaternion helpers they use. See the package docstring."""

from __future__ import annotations

import math

import numpy as np

from .. import _core
from ..checks import as_real, finite_number, finite_vector, real_array, shown
from ..errors import InputError

__all__ = [
    "RigidTool",
    "Plane",
    "Sphere",
    "Capsule",
    "Cylinder",
    "Box",
    "MeshTool",
    "quat_from_matrix",
    "quat_from_axis_angle",
    "quat_align_z",
]


def quat_from_axis_angle(axis, angle: float) -> np.ndarray:
    """Unit quaternion (w, x, y, z) of a rotation by ``angle`` [rad] about ``axis``."""
    a = np.asarray(axis, float)
    a = a / np.linalg.norm(a)
    return np.concatenate([[math.cos(angle / 2)], math.sin(angle / 2) * a])


def quat_align_z(direction) -> np.ndarray:
    """Quaternion rotating +z onto ``direction``."""
    d = np.asarray(direction, float)
    n = np.linalg.norm(d)
    if not n > 0:
        raise InputError(f"direction {shown(direction)} has zero length")
    d = d / n
    z = np.array([0.0, 0.0, 1.0])
    c = float(z @ d)
    if c < -1 + 1e-12:
        return np.array([0.0, 1.0, 0.0, 0.0])
    axis = np.cross(z, d)
    q = np.concatenate([[1.0 + c], axis])
    return q / np.linalg.norm(q)


def quat_from_matrix(R) -> np.ndarray:
    R = np.asarray(R, float)
    w = math.sqrt(max(0.0, 1 + R[0, 0] + R[1, 1] + R[2, 2])) / 2
    x = math.copysign(math.sqrt(max(0.0, 1 + R[0, 0] - R[1, 1] - R[2, 2])) / 2, R[2, 1] - R[1, 2])
    y = math.copysign(math.sqrt(max(0.0, 1 - R[0, 0] + R[1, 1] - R[2, 2])) / 2, R[0, 2] - R[2, 0])
    z = math.copysign(math.sqrt(max(0.0, 1 - R[0, 0] - R[1, 1] + R[2, 2])) / 2, R[1, 0] - R[0, 1])
    q = np.array([w, x, y, z])
    return q / np.linalg.norm(q)


def _quat(rotation) -> np.ndarray:
    q = real_array(rotation)
    q = np.full(0, np.nan) if q is None else q.ravel()  # a bool or a string is no rotation
    if q.shape == (9,) and np.all(np.isfinite(q)):
        R = q.reshape(3, 3)
        # A rotation: orthonormal (to float32 round-off, as a scene's or a device's matrix may be
        # given) with det +1; a scaled or mirrored matrix made some other rotation silently.
        if not (np.allclose(R @ R.T, np.eye(3), atol=1e-5) and np.linalg.det(R) > 0):
            raise InputError(
                f"rotation {shown(rotation)}: not a rotation matrix (orthonormal with det +1); "
                "expected a quaternion (w, x, y, z) or a 3×3 rotation matrix"
            )
        return quat_from_matrix(R)
    if q.shape != (4,) or not np.all(np.isfinite(q)) or not np.linalg.norm(q) > 0:
        raise InputError(f"rotation {shown(rotation)}: expected a quaternion (w, x, y, z) or a 3×3 matrix")
    return q / np.linalg.norm(q)


class RigidTool:
    """Base class. ``mu_s``/``mu_k``: static/kinetic friction coefficients (μk ≤ μs; 0 for
    frictionless). Trajectory: :meth:`at` adds keyframes (time [s], position [m], rotation);
    between keyframes positions are linear and rotations normalized-linear; held outside. Any
    tool can grasp (:meth:`grasp`, :meth:`release`): a grasper's jaws are its shape."""

    kind: _core.ToolKind | None = None

    def __init__(
        self,
        mu_s: float = 0.0,
        mu_k: float | None = None,
        position=(0.0, 0.0, 0.0),
        rotation=(1.0, 0.0, 0.0, 0.0),
        name: str | None = None,
    ):
        self.mu_s = as_real(mu_s)
        self.mu_k = self.mu_s if mu_k is None else as_real(mu_k)
        if not (0 <= self.mu_k <= self.mu_s) or not math.isfinite(self.mu_s):
            raise InputError(
                f"{type(self).__name__}: friction mu_s = {shown(mu_s)}, mu_k = {shown(mu_k)}; "
                "expected 0 <= mu_k <= mu_s"
            )
        self.name = name or type(self).__name__.lower()
        self.keys: list[np.ndarray] = []
        self.at(0.0, position, rotation)
        self._fixed = True
        self.grips: list[float] = []  # times [s] it closes, opens, closes… (grasp, release)
        self.reach = 0.0  # a closing tool grasps the surface nodes within this distance [m]

    def at(self, t: float, position, rotation=(1.0, 0.0, 0.0, 0.0)) -> "RigidTool":
        """Add a keyframe: at time t [s] the tool is at ``position`` [m] with ``rotation``."""
        p = finite_vector(position, 3, f"{self.name}: position", "m")
        t = finite_number(t, f"{self.name}: keyframe time", "s")
        key = np.concatenate([[t], p, _quat(rotation)])
        if getattr(self, "_fixed", False):  # the first explicit keyframe replaces the initial pose
            self.keys, self._fixed = [], False
        if self.keys and t <= self.keys[-1][0]:
            raise InputError(f"{self.name}: keyframe times must increase ({t} after {self.keys[-1][0]})")
        self.keys.append(key)
        return self

    def grasp(self, t: float, reach: float | None = None) -> "RigidTool":
        """Close the tool at time t [s]: from the next step on, it holds the surface nodes within
        ``reach`` [m] of its surface (inside it, or up to reach outside) and moves them with it
        until :meth:`release`; the force that takes is part of the tool's reported force."""
        t = finite_number(t, f"{self.name}: grasp time", "s")
        if reach is not None:
            self.set_reach(reach)
        if len(self.grips) % 2:
            raise InputError(f"{self.name}: grasp at t = {t:g} s, but it is already closed; release it first")
        return self._grip_event(t, "grasp")

    def set_reach(self, reach: float) -> "RigidTool":
        """How far from its surface a closing tool grasps [m] (>= 0)."""
        reach = finite_number(reach, f"{self.name}: reach", "m")
        if reach < 0:
            raise InputError(f"{self.name}: reach = {shown(reach)}; expected a distance >= 0 [m]")
        self.reach = reach
        return self

    def release(self, t: float) -> "RigidTool":
        """Open the tool at time t [s]: the nodes it holds are free again."""
        t = finite_number(t, f"{self.name}: release time", "s")
        if len(self.grips) % 2 == 0:
            raise InputError(f"{self.name}: release at t = {t:g} s, but it is not closed; grasp first")
        return self._grip_event(t, "release")

    def _grip_event(self, t: float, what: str) -> "RigidTool":
        if self.grips and t <= self.grips[-1]:
            raise InputError(
                f"{self.name}: {what} at t = {t:g} s; expected a time after {self.grips[-1]:g} s"
            )
        self.grips.append(float(t))
        return self

    def closed(self, t: float) -> bool:
        """Whether the tool is closed (holding) at time t [s], as the engine sees it."""
        return sum(g < t for g in self.grips) % 2 == 1

    def move_to(self, t: float, position, rotation, max_step: float, dt: float) -> "RigidTool":
        """From its pose at time t [s], move to ``position`` [m] with ``rotation``, then stay: the
        trajectory restarts at t, and the move takes at least one step of ``dt`` [s] and no less
        than the distance over ``max_step`` [m] per step (a jump deeper than an element would
        invert it; a blade would skip elements)."""
        R, p = self.pose(t)
        target = finite_vector(position, 3, f"{self.name}: position", "m")
        duration = max(dt, float(np.linalg.norm(target - p)) / (max_step / dt))
        self.keys = [np.concatenate([[t], p, quat_from_matrix(R)])]
        self._fixed = False
        return self.at(t + duration, target, rotation)

    def key_array(self) -> np.ndarray:
        return np.concatenate(self.keys)

    def params(self) -> list[float]:
        return [0.0, 0.0, 0.0, 0.0]

    def grid(self) -> tuple[list[int], np.ndarray]:
        return [0, 0, 0], np.zeros(0)

    def _sdf_local(self, y: np.ndarray) -> np.ndarray:
        """φ [m] of points y (n, 3) in the tool's frame; each kind defines it."""
        raise NotImplementedError

    def signed_distance(self, x, t: float = 0.0) -> np.ndarray:
        """φ [m] of world points x (n, 3) at time t (NumPy, for checks and tests)."""
        R, p = self.pose(t)
        return self._sdf_local((np.asarray(x, float) - p) @ R)

    def pose(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """(R (3, 3), position (3,)) at time t, interpolated like the engine does."""
        K = np.array(self.keys)
        if len(K) == 1 or t <= K[0, 0]:
            k = K[0]
        elif t >= K[-1, 0]:
            k = K[-1]
        else:
            i = int(np.searchsorted(K[:, 0], t)) - 1
            w = (t - K[i, 0]) / (K[i + 1, 0] - K[i, 0])
            qb = K[i + 1, 4:] * (1 if K[i, 4:] @ K[i + 1, 4:] >= 0 else -1)
            k = np.concatenate([[t], (1 - w) * K[i, 1:4] + w * K[i + 1, 1:4], (1 - w) * K[i, 4:] + w * qb])
        w, x, y, z = k[4:] / np.linalg.norm(k[4:])
        R = np.array(
            [
                [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
            ]
        )
        return R, k[1:4]


def _positive(cls, name, v):
    x = as_real(v)  # a bool or a string is not a length
    if not (math.isfinite(x) and x > 0):
        raise InputError(f"{cls}: {name} = {shown(v)}; expected a length > 0 [m]")
    return x


class Plane(RigidTool):
    """Half-space below the plane through ``point`` with outward ``normal`` (e.g. the ground)."""

    kind = _core.ToolKind.Plane

    def __init__(self, point=(0.0, 0.0, 0.0), normal=(0.0, 0.0, 1.0), **kw):
        super().__init__(position=point, rotation=quat_align_z(normal), **kw)

    def _sdf_local(self, y):
        return y[:, 2]


class Sphere(RigidTool):
    kind = _core.ToolKind.Sphere

    def __init__(self, radius: float, **kw):
        self.radius = _positive("Sphere", "radius", radius)
        super().__init__(**kw)

    def params(self):
        return [self.radius, 0.0, 0.0, 0.0]

    def _sdf_local(self, y):
        return np.linalg.norm(y, axis=1) - self.radius


class Capsule(RigidTool):
    """Cylinder with hemispherical ends (most laparoscopic tools): axis along the tool's z, from
    −length/2 to +length/2 (segment), radius ``radius``."""

    kind = _core.ToolKind.Capsule

    def __init__(self, radius: float, length: float, **kw):
        self.radius = _positive("Capsule", "radius", radius)
        self.length = as_real(length)
        if not (math.isfinite(self.length) and self.length >= 0):
            raise InputError(f"Capsule: length = {shown(length)}; expected >= 0 [m]")
        super().__init__(**kw)

    def params(self):
        return [self.radius, self.length / 2, 0.0, 0.0]

    def _sdf_local(self, y):
        c = np.zeros_like(y)
        c[:, 2] = np.clip(y[:, 2], -self.length / 2, self.length / 2)
        return np.linalg.norm(y - c, axis=1) - self.radius


class Cylinder(RigidTool):
    """Cylinder with flat ends (a rod, a retractor blade's edge): axis along the tool's z, from
    −length/2 to +length/2, radius ``radius``."""

    kind = _core.ToolKind.Cylinder

    def __init__(self, radius: float, length: float, **kw):
        self.radius = _positive("Cylinder", "radius", radius)
        self.length = _positive("Cylinder", "length", length)
        super().__init__(**kw)

    def params(self):
        return [self.radius, self.length / 2, 0.0, 0.0]

    def _sdf_local(self, y):
        q = np.stack([np.hypot(y[:, 0], y[:, 1]) - self.radius, np.abs(y[:, 2]) - self.length / 2], axis=1)
        return np.linalg.norm(np.maximum(q, 0), axis=1) + np.minimum(q.max(axis=1), 0)


class Box(RigidTool):
    kind = _core.ToolKind.Box

    def __init__(self, half_extents, **kw):
        h = real_array(half_extents)
        h = None if h is None else h.ravel()
        if h is None or h.shape != (3,) or not np.all(np.isfinite(h) & (h > 0)):
            raise InputError(f"Box: half_extents {shown(half_extents)}; expected 3 lengths > 0 [m]")
        self.half = h
        super().__init__(**kw)

    def params(self):
        return [*self.half.tolist(), 0.0]

    def _sdf_local(self, y):
        q = np.abs(y) - self.half
        return np.linalg.norm(np.maximum(q, 0), axis=1) + np.minimum(q.max(axis=1), 0)


MAX_GRID_CELLS = 2**22  # a mesh tool's distance grid (160³; about 1.5 GB while it is computed)


def _closed_mesh(vertices, faces) -> tuple[np.ndarray, np.ndarray]:
    """A mesh tool's vertices [m] (n, 3), finite, not all at one point, and its triangles (m, 3)
    indexing them; InputError naming what is wrong."""
    V = real_array(vertices)
    if V is None or V.ndim != 2 or V.shape[1] != 3 or len(V) < 4 or not np.all(np.isfinite(V)):
        raise InputError(f"MeshTool: vertices {shown(vertices)}; expected (n >= 4, 3) finite positions [m]")
    F = np.asarray(faces)
    if F.dtype.kind not in "iu" or F.ndim != 2 or F.shape[1] != 3 or len(F) < 4:
        raise InputError(f"MeshTool: faces {shown(faces)}; expected (m >= 4, 3) vertex indices")
    if F.min() < 0 or F.max() >= len(V):
        bad = int(np.argmax((F < 0).any(axis=1) | (F >= len(V)).any(axis=1)))
        raise InputError(f"MeshTool: face {bad} = {F[bad].tolist()} indexes beyond the {len(V)} vertices")
    if not np.ptp(V, axis=0).max() > 0:
        raise InputError("MeshTool: every vertex at one point; expected a closed surface")
    return V, F.astype(np.int64)


class MeshTool(RigidTool):
    """Any closed triangle mesh (vertices [m] in the tool frame, faces), through a signed-distance
    grid of spacing ``spacing`` [m] (default: 1/64 of its largest extent) interpolated trilinearly;
    beyond the grid (the surface's box and 4 cells more), the distance to the grid's box is added
    to the value at its nearest point."""

    kind = _core.ToolKind.Grid

    def __init__(self, vertices, faces, spacing: float | None = None, **kw):
        from .sdf import signed_distance_grid

        V, F = _closed_mesh(vertices, faces)
        ext = float(np.ptp(V, axis=0).max())
        h = ext / 64 if spacing is None else as_real(spacing)
        if not (math.isfinite(h) and h > 0):
            raise InputError(f"MeshTool: spacing = {shown(spacing)}; expected a length > 0 [m]")
        cells = np.prod(np.ceil((np.ptp(V, axis=0) + 8 * h) / h) + 1)
        if cells > MAX_GRID_CELLS:
            raise InputError(
                f"MeshTool: spacing {h:.3g} m makes a grid of {cells:.3g} cells over the tool's "
                f"{ext:.3g} m; expected at most {MAX_GRID_CELLS:,} (a larger spacing; default 1/64 "
                "of the largest extent)"
            )
        self.origin, self.spacing, self.values = signed_distance_grid(V, F, h, margin=4 * h)
        super().__init__(**kw)

    def params(self):
        return [*self.origin.tolist(), self.spacing]

    def grid(self):
        return list(self.values.shape), self.values.ravel()

    def _sdf_local(self, y):
        """As the engine (contact.hpp, tool_sdf): trilinear inside the grid; outside it, the
        value at the nearest point of the grid's box plus the distance to that box."""
        from scipy.interpolate import RegularGridInterpolator

        axes = [self.origin[d] + self.spacing * np.arange(self.values.shape[d]) for d in range(3)]
        f = RegularGridInterpolator(axes, self.values)
        y = np.asarray(y, float)
        lo, hi = np.array([a[0] for a in axes]), np.array([a[-1] for a in axes])
        yc = np.clip(y, lo, hi)
        out = np.linalg.norm(y - yc, axis=1)
        phi = f(yc)
        return np.where(out > 0, out + np.maximum(phi, 0.0), phi)


def deepest_start(tools, X: np.ndarray, nodes: list[np.ndarray], size: np.ndarray, skin: np.ndarray):
    """The node that starts deepest inside a rigid tool beyond half its ``size`` [m] (its
    elements' smallest altitude; (N,)): the first step's contact would push it out across its
    elements and invert them. ``nodes``: per tool, the nodes it may touch; ``skin``: each node's
    offset [m] (a sheet's half thickness, (N,)). A tool that closes at t = 0 holds what it starts
    on and is not checked. Returns (tool index, node, depth [m]) or None."""
    worst = None
    for k, (tool, ids) in enumerate(zip(tools, nodes)):
        if not len(ids) or (tool.grips and tool.grips[0] <= 0.0):
            continue
        depth = skin[ids] - tool.signed_distance(X[ids], 0.0)
        over = depth - 0.5 * size[ids]
        i = int(np.argmax(over))
        if over[i] > 0 and (worst is None or depth[i] > worst[2]):
            worst = (k, int(ids[i]), float(depth[i]))
    return worst
