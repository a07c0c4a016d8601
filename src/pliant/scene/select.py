"""Node and element selections for scene files.

A selection is a table combining any of (intersection):
  all = true | ids = [..] | box = [[x0,y0,z0],[x1,y1,z1]] | sphere = {center=[..], radius=r}
  plane = {point=[..], normal=[..], side="below"|"above"|"on", tol=...}
  surface = true   (only nodes on the boundary surface: with box/sphere/plane, a surface patch)
  set = "name"     (elements: a mesh file's element set; nodes: its node set, e.g. a gmsh
                    physical surface)
Coordinates are in metres, after the mesh transform.
"""

from __future__ import annotations

import numpy as np

from ..mesh.topology import boundary_faces, boundary_nodes
from .schema import Ctx, check_keys, vector

_KEYS = {
    "all": "bool",
    "ids": "list [i, j, ...] (0-based node indices)",
    "box": "list [[x0, y0, z0], [x1, y1, z1]] (opposite corners [m])",
    "sphere": "table { center = [x, y, z], radius = r } [m]",
    "plane": "table { point = [x, y, z], normal = [nx, ny, nz] }",
    "surface": "bool",
    "set": "str",
}


def _mask(ctx: Ctx, spec: dict, path: str, P: np.ndarray, extent: float) -> np.ndarray:
    m = np.ones(len(P), dtype=bool)
    if "ids" in spec:
        ids = spec["ids"]
        if not all(isinstance(i, int) and not isinstance(i, bool) for i in ids):
            raise ctx.error(f"{path}.ids", "expected a list of integer indices")
        ids = np.asarray(ids, dtype=np.int64)
        if ids.size and (ids.min() < 0 or ids.max() >= len(P)):
            raise ctx.error(f"{path}.ids", f"index out of range 0..{len(P) - 1}")
        sel = np.zeros(len(P), bool)
        sel[ids] = True
        m &= sel
    if "box" in spec:
        b = spec["box"]
        if not (isinstance(b, list) and len(b) == 2):
            raise ctx.error(f"{path}.box", "expected [[x0, y0, z0], [x1, y1, z1]] [m]")
        lo, hi = np.array(vector(ctx, b[0], f"{path}.box")), np.array(vector(ctx, b[1], f"{path}.box"))
        m &= np.all((P >= np.minimum(lo, hi)) & (P <= np.maximum(lo, hi)), axis=1)
    if "sphere" in spec:
        s = check_keys(
            ctx,
            spec["sphere"],
            f"{path}.sphere",
            {"center": "list [x, y, z] [m]", "radius": "number"},
            ("center", "radius"),
        )
        m &= (
            np.linalg.norm(P - np.array(vector(ctx, s["center"], f"{path}.sphere.center")), axis=1)
            <= s["radius"]
        )
    if "plane" in spec:
        p = check_keys(
            ctx,
            spec["plane"],
            f"{path}.plane",
            {"point": "list [x, y, z] [m]", "normal": "list [nx, ny, nz]", "side": "str", "tol": "number"},
            ("point", "normal"),
        )
        n = np.array(vector(ctx, p["normal"], f"{path}.plane.normal"))
        if not np.linalg.norm(n) > 0:
            raise ctx.error(f"{path}.plane.normal", "expected a non-zero normal")
        d = (P - np.array(vector(ctx, p["point"], f"{path}.plane.point"))) @ (n / np.linalg.norm(n))
        tol = float(p.get("tol", 1e-6 * extent))
        side = p.get("side", "on")
        if side == "on":
            m &= np.abs(d) <= tol
        elif side == "below":
            m &= d <= tol
        elif side == "above":
            m &= d >= -tol
        else:
            raise ctx.error(f"{path}.plane.side", f"side = {side!r}; expected 'below', 'above' or 'on'")
    return m


def select_nodes(
    ctx: Ctx, spec, path: str, nodes: np.ndarray, tets: np.ndarray, sets: dict[str, np.ndarray] | None = None
) -> np.ndarray:
    """Node indices selected by ``spec`` (with ``set``: within the mesh file's node set of that name,
    ``sets``); an empty selection is an error naming the key."""
    check_keys(ctx, spec, path, _KEYS)
    if not spec:
        raise ctx.error(path, "empty selection; give all, ids, box, sphere, plane, surface and/or set")
    extent = float(np.linalg.norm(nodes.max(axis=0) - nodes.min(axis=0)))
    m = _mask(ctx, spec, path, nodes, extent)
    if "set" in spec:
        sets = sets or {}
        if spec["set"] not in sets:
            raise ctx.error(
                f"{path}.set",
                f"unknown node set {spec['set']!r}; the mesh files have: {', '.join(sets) or 'none'} "
                "(a gmsh physical surface, curve or point by its name or tag; tagged triangles of "
                "other formats by tag)",
            )
        s = np.zeros(len(nodes), bool)
        s[sets[spec["set"]]] = True
        m &= s
    if spec.get("surface"):
        s = np.zeros(len(nodes), bool)
        s[boundary_nodes(tets)] = True
        m &= s
    ids = np.nonzero(m)[0]
    if ids.size == 0:
        raise ctx.error(path, "selects no node; check the coordinates (metres, after scale and transform)")
    return ids


def select_elements(
    ctx: Ctx, spec, path: str, nodes: np.ndarray, tets: np.ndarray, sets: dict[str, np.ndarray]
) -> np.ndarray:
    """Element indices whose centroid is selected by ``spec`` (or the named element set)."""
    check_keys(ctx, spec, path, _KEYS)
    if "set" in spec:
        if spec["set"] not in sets:
            raise ctx.error(
                f"{path}.set",
                f"unknown element set {spec['set']!r}; the mesh has: {', '.join(sets) or 'none'}",
            )
        return sets[spec["set"]]
    if spec.get("surface"):
        raise ctx.error(f"{path}.surface", "surface selects nodes, not elements")
    c = nodes[tets].mean(axis=1)
    ids = np.nonzero(_mask(ctx, spec, path, c, float(np.ptp(nodes, axis=0).max())))[0]
    if ids.size == 0:
        raise ctx.error(path, "selects no element")
    return ids


def select_faces(
    ctx: Ctx,
    spec,
    path: str,
    nodes: np.ndarray,
    tets: np.ndarray,
    sets: dict[str, np.ndarray] | None = None,
    sheets: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """The boundary triangles (F, 3) whose three nodes ``spec`` selects (select_nodes), and of
    ``sheets`` (K, 3), the triangles of the sheets apart from the tets, those it selects (none
    without); no triangle at all is an error naming the key (pressure and traction loads,
    membranes)."""
    ids = select_nodes(ctx, spec, path, nodes, tets, sets)
    B, _ = boundary_faces(tets)
    faces = B[np.all(np.isin(B, ids), axis=1)]
    on_sheets = np.zeros((0, 3), np.int64) if sheets is None else sheets[np.all(np.isin(sheets, ids), axis=1)]
    if len(faces) + len(on_sheets) == 0:
        where = "boundary or sheet triangle" if sheets is not None and len(sheets) else "boundary triangle"
        raise ctx.error(path, f"the {ids.size} selected nodes hold no whole {where}: select a surface patch")
    return faces, on_sheets


def closest_node(X: np.ndarray, point) -> tuple[int, float]:
    """The node of X [m] (N, 3) nearest ``point`` [m] (the first on ties) and its distance [m]."""
    p = np.asarray(point, dtype=float)
    d2 = np.einsum("ij,ij->i", X - p, X - p)
    node = int(np.argmin(d2))
    return node, float(np.sqrt(d2[node]))


def nearest_node(ctx: Ctx, point, path: str, X: np.ndarray) -> int:
    """The node of X [m] (N, 3) nearest ``point`` [m] (the first on ties): an output point's (a
    probe's) node. Warns, naming the key at ``path``, of a point farther than a tenth of the mesh's
    size from every node: its displacement is that node's, so such a point is most likely a typo or
    in other units."""
    import warnings

    from ..errors import PliantWarning

    node, dist = closest_node(X, point)
    size = float(np.linalg.norm(X.max(axis=0) - X.min(axis=0))) if len(X) else 0.0
    if dist > 0.1 * size:
        warnings.warn(
            PliantWarning(
                f"{ctx.where(path)} [{path}]: {np.asarray(point, dtype=float).tolist()} is "
                f"{dist:.3g} m from the nearest node ({node}, at {np.round(X[node], 6).tolist()}) of a mesh "
                f"{size:.3g} m across; its displacement is that node's (SI metres expected)"
            ),
            stacklevel=3,
        )
    return node
