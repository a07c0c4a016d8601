"""Surface → volume mesh, as the study did it: repair, QEM-simplify to the detail the tets can
carry, tetrahedralize (fTetWild), check the tets. Sensible defaults give tens of thousands of tets."""

from __future__ import annotations

import math
import time

import numpy as np

from ..errors import MeshError
from .primitives import tet_volumes
from .repair import repair_surface, require_volume, simplify
from .tetra import MAX_TETS, tetrahedralize

BODIES = ("union", "separate", "largest", "one")


def default_edge_length(V: np.ndarray, F: np.ndarray, target_tets: int = 20000) -> float:
    """Edge [m] of regular tets that would fill the enclosed volume with ``target_tets`` tets
    (a regular tet of edge a has volume a³/(6√2)); the volume is the surface's own if it is closed
    and at least 0.3 × its convex hull's (self-intersecting scans can enclose a misleadingly small
    signed volume), else 0.3 × the convex hull's."""
    import trimesh

    m = trimesh.Trimesh(V, F, process=False)
    hull = float(m.convex_hull.volume)
    vol = float(m.volume) if m.is_watertight else 0.0
    vol = max(vol, 0.3 * hull)
    return (6.0 * math.sqrt(2.0) * vol / target_tets) ** (1.0 / 3.0)


def surface_to_tets(
    V: np.ndarray,
    F: np.ndarray,
    edge_length: float | None = None,
    target_tets: int = 10000,
    target_faces: int | None = None,
    epsilon: float | None = None,
    repair: bool = True,
    keep_largest: bool = False,
    bodies: str = "union",
    log=None,
) -> tuple[np.ndarray, np.ndarray, dict]:
    """Tet mesh [m] of a triangle surface. Steps (each timed in the returned info): repair (holes,
    winding, fragments), QEM simplification to ``target_faces`` (default: what the tet size can
    resolve, area / (√3/4 · edge²), i.e. surface triangles of the tet edge), fTetWild with envelope
    ``epsilon`` (relative to the bounding-box diagonal, default 2e-3), then a check that the tets
    fill the surface's volume (within 10 %); on failure fTetWild runs again with half the envelope
    (a large envelope can swallow thin features), and a second failure is an error.
    ``target_tets`` is the count of regular tets the default edge aims at: fTetWild's tets, less
    regular, come out about 1.5–4 times as many. Returns nodes, tets and an info dict.

    ``bodies``, for a surface of several closed bodies (they may overlap, as a teapot's body, lid,
    handle and spout do): "union" (default) meshes the union of the bodies, overlaps merged, as one
    conforming tet mesh (fTetWild's winding-number filter); "separate" meshes each body on its own
    (the meshes share no nodes, and overlap where the bodies do); "largest" keeps the largest body;
    "one" refuses several bodies. ``info["bodies"]`` says how many there were."""
    if bodies not in BODIES:
        raise MeshError(f"bodies = {bodies!r}; expected one of {', '.join(BODIES)}")
    if keep_largest:
        bodies = "largest"
    if not 1 <= int(target_tets) <= MAX_TETS:
        raise MeshError(f"target_tets = {target_tets}; expected 1 to {MAX_TETS:.0e}")
    info: dict = {
        "input_vertices": int(len(V)),
        "input_faces": int(len(F)),
        "seconds": {},
        "bodies_mode": bodies,
    }
    t = time.perf_counter()
    require_volume(V, F, closed=False)
    if repair:
        V, F, actions = repair_surface(V, F, bodies={"union": "all", "separate": "all"}.get(bodies, bodies))
        info["repair"] = actions
    info["seconds"]["repair"] = time.perf_counter() - t
    require_volume(V, F)
    parts = _bodies(V, F)
    info["bodies"] = len(parts)
    if bodies == "separate" and len(parts) > 1:
        return _separate(parts, edge_length, target_tets, epsilon, info, log)
    el = float(edge_length) if edge_length else default_edge_length(V, F, target_tets)
    if not el > 0:
        raise MeshError(f"edge length {el!r}: expected > 0 [m]")
    info["edge_length"] = el
    t = time.perf_counter()
    if target_faces is None:
        import trimesh

        area = float(trimesh.Trimesh(V, F, process=False).area)
        target_faces = max(2000, int(area / (math.sqrt(3) / 4 * el * el)))
    if target_faces < len(F):
        V, F = simplify(V, F, target_faces=target_faces)
    info["simplified_faces"] = int(len(F))
    info["seconds"]["simplify"] = time.perf_counter() - t
    t = time.perf_counter()
    import trimesh

    surf = trimesh.Trimesh(V, F, process=False)
    ref_vol = abs(float(surf.volume)) if surf.is_watertight else None
    # Overlapping bodies: the union's volume lies between the largest body's and the sum.
    low = max(abs(float(p.volume)) for p in parts) if len(parts) > 1 else ref_vol
    eps = 2e-3 if epsilon is None else float(epsilon)
    for attempt in range(2):
        X, T = tetrahedralize(V, F, edge_length=el, epsilon=eps, keep_all=len(parts) > 1)
        vol = float(tet_volumes(X, T).sum())
        ratio = vol / ref_vol if ref_vol else 1.0
        info["volume_ratio"] = ratio
        if ref_vol is None or low is None or 0.9 * low <= vol <= 1.1 * ref_vol:
            break
        if attempt == 1:
            raise MeshError(
                f"tetrahedralize: the tets fill {100 * ratio:.0f} % of the surface's "
                f"volume (envelope {eps:g}); repair the surface or give a smaller "
                "edge length"
            )
        eps /= 2
    if len(parts) > 1:
        info["union_volume"] = vol
        info["bodies_volume"] = ref_vol
    info["epsilon"] = eps
    info["seconds"]["tetrahedralize"] = time.perf_counter() - t
    info["nodes"], info["tets"] = int(len(X)), int(len(T))
    if log:
        if len(parts) > 1 and ref_vol is not None:
            merged = (ref_vol - vol) / ref_vol
            # Without overlap the tets and the surface differ by about 0.5 % (fTetWild's envelope).
            if merged > 0.01:
                what = f"{ref_vol - vol:.3g} m^3, {100 * merged:.0f} %, of overlap merged"
            elif merged < -0.01:
                what = f"the tets {100 * -merged:.1f} % larger than the bodies"
            else:
                what = f"{100 * abs(merged):.2f} % apart: no overlap beyond the meshing's 1 %"
            log(
                f"{len(parts)} bodies meshed as their union: {vol:.4g} m^3 of tets for "
                f"{ref_vol:.4g} m^3 of bodies ({what})"
            )
        log(
            f"repair {info['seconds']['repair']:.1f} s, simplify to {len(F):,} faces "
            f"{info['seconds']['simplify']:.1f} s, tetrahedralize {info['seconds']['tetrahedralize']:.1f} s:"
            f" {len(X):,} nodes, {len(T):,} tets"
        )
    return X, T, info


def _bodies(V: np.ndarray, F: np.ndarray) -> list:
    """The connected bodies of a surface, as trimesh meshes."""
    import trimesh

    return trimesh.Trimesh(V, F, process=False).split(only_watertight=False)


def _separate(parts, edge_length, target_tets, epsilon, info, log):
    """Each body tetrahedralized on its own (one edge length for all), concatenated."""
    V = np.concatenate([p.vertices for p in parts])
    offs = np.cumsum([0] + [len(p.vertices) for p in parts])
    F = np.concatenate([np.asarray(p.faces) + o for p, o in zip(parts, offs)])
    el = float(edge_length) if edge_length else default_edge_length(V, F, target_tets)
    Xs, Ts, n = [], [], 0
    for p in parts:
        X, T, _ = surface_to_tets(
            np.asarray(p.vertices),
            np.asarray(p.faces),
            edge_length=el,
            epsilon=epsilon,
            repair=False,
            bodies="one",
        )
        Xs.append(X)
        Ts.append(T + n)
        n += len(X)
    X, T = np.concatenate(Xs), np.concatenate(Ts)
    info.update(edge_length=el, nodes=int(len(X)), tets=int(len(T)))
    if log:
        log(f"{len(parts)} bodies meshed separately: {len(X):,} nodes, {len(T):,} tets")
    return X, T, info
