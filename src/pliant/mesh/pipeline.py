"""Surface → volume mesh, as the study did it: repair, QEM-simplify to the detail the tets can
carry, tetrahedralize (fTetWild), check the tets. Sensible defaults give tens of thousands of tets."""

from __future__ import annotations

import math
import time

import numpy as np

from ..checks import flag, mesh_arrays, whole_number
from ..errors import MeshError
from .primitives import tet_volumes, unit_scale
from .repair import repair_surface, require_volume, simplify
from .tetra import MAX_TETS, MIN_ENVELOPE, edge, envelope, tetrahedralize

BODIES = ("union", "separate", "largest", "one")
MIN_FACES = 2000  # the simplified surface keeps at least this many faces, to hold its shape


def default_edge_length(V: np.ndarray, F: np.ndarray, target_tets: int = 20000) -> float:
    """Edge [m] of regular tets that would fill the enclosed volume with ``target_tets`` tets
    (a regular tet of edge a has volume a³/(6√2)); the volume is the surface's own if it is closed
    and at least 0.3 × its convex hull's (self-intersecting scans can enclose a misleadingly small
    signed volume), else 0.3 × the convex hull's. At least the edge of ``target_tets`` equilateral
    triangles covering the surface (area / (√3/4 a²)): a body thinner than its edge (a sheet, a
    capsule's wall) would otherwise get an edge from its small volume and millions of surface
    triangles (a disc 5 nm thick and 10 cm across: fTetWild ran for hours at 0.1 mm)."""
    import trimesh

    V, F = mesh_arrays(V, F, 3, "default_edge_length", cell="face")
    if not 1 <= whole_number(target_tets, "target_tets") <= MAX_TETS:
        raise MeshError(f"target_tets = {target_tets}; expected 1 to {MAX_TETS:.0e}")
    # On the surface scaled by a power of two to a diagonal of about 1 (trimesh's tolerances are
    # absolute: its hull of a surface 1e30 across overflowed), the edge scaled back.
    scale = unit_scale(V)
    return _unit_edge(trimesh.Trimesh(V * scale, F, process=False), target_tets) / scale


def _unit_edge(m, target_tets: int) -> float:
    """default_edge_length of trimesh mesh m."""
    hull = float(m.convex_hull.volume)
    vol = float(m.volume) if m.is_watertight else 0.0
    vol = max(vol, 0.3 * hull)
    by_volume = (6.0 * math.sqrt(2.0) * vol / target_tets) ** (1.0 / 3.0)
    by_area = math.sqrt(float(m.area) / (math.sqrt(3.0) / 4.0 * target_tets))
    return max(by_volume, by_area)


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
    fill_shell: bool = False,
    log=None,
) -> tuple[np.ndarray, np.ndarray, dict]:
    """Tet mesh [m] of a triangle surface. Steps (each timed in the returned info): repair (holes,
    winding, fragments), QEM simplification to ``target_faces`` (default: what the tet size can
    resolve, area / (√3/4 · edge²), i.e. surface triangles of the tet edge), fTetWild with envelope
    ``epsilon`` (relative to the bounding-box diagonal, default 2e-3, halved until it spans at
    most half the walls of a thin-walled body: ``wall_envelope``), then a check that the tets fill
    the surface's volume (within 10 %); on failure fTetWild runs again with half the envelope (a
    large envelope can swallow thin features), and a second failure is an error.
    ``target_tets`` is the count of regular tets the default edge aims at: fTetWild's tets, less
    regular, come out about 1.5–4 times as many. Returns nodes, tets and an info dict
    (``info["epsilon"]``: the envelope of the tets returned; ``info["tries"]``: (envelope, volume
    ratio) of each fTetWild run); ``info["warnings"]`` lists what the caller should show (far
    more tets than the edge asks for, and why: ``count_note``).

    A body inside another is a cavity (its faces pointing in, as a hollow sphere's inner surface)
    or an inclusion (pointing out: meshed with its container); it belongs to that body below.
    ``bodies``, for a surface of several closed bodies (they may overlap, as a teapot's body, lid,
    handle and spout do): "union" (default) meshes the union of the bodies, overlaps merged, as one
    conforming tet mesh (fTetWild's winding-number filter); "separate" meshes each body on its own
    (the meshes share no nodes, and overlap where the bodies do); "largest" keeps the largest body;
    "one" refuses several bodies. ``info["bodies"]`` says how many there were.

    ``fill_shell``: the surface is a thin-walled shell, an organ's capsule (two sheets a wall apart,
    joined at the rims of its openings): mesh the solid its outer sheet encloses, the openings
    closed (``shell.outer_sheet``; ``info["shell"]`` says what was kept), instead of the wall. It
    repairs the surface whatever ``repair`` says."""
    if not isinstance(bodies, str) or bodies not in BODIES:
        raise MeshError(f"bodies = {bodies!r}; expected one of {', '.join(BODIES)}")
    repair = flag(repair, "surface_to_tets: repair")
    fill_shell = flag(fill_shell, "surface_to_tets: fill_shell")
    if flag(keep_largest, "surface_to_tets: keep_largest"):
        bodies = "largest"
    if not 1 <= whole_number(target_tets, "target_tets") <= MAX_TETS:
        raise MeshError(f"target_tets = {target_tets}; expected 1 to {MAX_TETS:.0e}")
    if target_faces is not None and whole_number(target_faces, "surface_to_tets: target_faces") < 4:
        raise MeshError(f"surface_to_tets: target_faces = {target_faces}; expected >= 4")
    epsilon = None if epsilon is None else envelope(epsilon, "surface_to_tets")
    V, F = mesh_arrays(V, F, 3, "surface_to_tets", cell="face")
    if edge_length is not None:  # against the whole surface's size (bodies="separate" meshes parts)
        edge_length = edge(edge_length, _diagonal(V), "surface_to_tets")
    info: dict = {
        "input_vertices": int(len(V)),
        "input_faces": int(len(F)),
        "seconds": {},
        "bodies_mode": bodies,
        "warnings": [],
    }
    t = time.perf_counter()
    require_volume(V, F, closed=False)
    keep = {"union": "all", "separate": "all"}.get(bodies, bodies)  # the pieces repair keeps
    if repair or fill_shell:  # the shell's sheets are told apart on a closed, outward surface
        V, F, actions = repair_surface(V, F, bodies=keep)
        info["repair"] = actions
    if fill_shell:
        from .shell import outer_sheet

        V, F, info["shell"] = outer_sheet(V, F)
        V, F, actions = repair_surface(V, F, bodies=keep)
        info["repair"] = info.get("repair", []) + actions
    info["seconds"]["repair"] = time.perf_counter() - t
    require_volume(V, F)
    parts, _, pieces = _bodies(V, F)
    info["bodies"] = len(parts)
    if bodies == "separate" and len(parts) > 1:
        return _separate(parts, edge_length, target_tets, epsilon, info, log)
    # A default edge can exceed the diagonal (target_tets = 1 on a cube: 1.2 diagonals), and a given
    # one the repaired or simplified surface's: tetrahedralize would refuse what it is given.
    el = edge_length if edge_length is not None else default_edge_length(V, F, target_tets)
    el = min(el, _diagonal(V))
    info["edge_length"] = el
    t = time.perf_counter()
    if target_faces is None:
        import trimesh

        area = float(trimesh.Trimesh(V, F, process=False).area)
        with np.errstate(over="ignore", divide="ignore"):  # el = 1e-300: el² is 0, the count inf
            faces = np.float64(area) / (math.sqrt(3) / 4 * np.float64(el) ** 2)
        target_faces = max(MIN_FACES, int(min(faces, 1e18)))  # tetrahedralize refuses what is too many
    if target_faces < len(F):
        V, F = simplify(V, F, target_faces=target_faces)
    info["simplified_faces"] = int(len(F))
    info["seconds"]["simplify"] = time.perf_counter() - t
    t = time.perf_counter()
    import trimesh

    surf = trimesh.Trimesh(V, F, process=False)
    area = float(surf.area)
    filled = _bodies(V, F)[1] if surf.is_watertight else []  # of the simplified surface
    ref_vol = sum(filled) if filled else None
    # Overlapping bodies: the union's volume lies between the largest body's and the sum.
    low = max(filled) if ref_vol else None
    eps = 2e-3 if epsilon is None else float(epsilon)
    if epsilon is None and ref_vol:
        eps = wall_envelope(eps, 2.0 * ref_vol / area, _diagonal(V))
    tries = []  # (envelope, volume ratio) of each fTetWild run
    for attempt in range(2):
        X, T = tetrahedralize(V, F, edge_length=min(el, _diagonal(V)), epsilon=eps, keep_all=pieces > 1)
        vol = float(tet_volumes(X, T).sum())
        ratio = vol / ref_vol if ref_vol else 1.0
        info["volume_ratio"] = ratio
        tries.append((eps, ratio))
        if ref_vol is None or low is None or 0.9 * low <= vol <= 1.1 * ref_vol:
            break
        if attempt == 1 or eps / 2 < MIN_ENVELOPE:
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
    info["tries"] = tries
    info["seconds"]["tetrahedralize"] = time.perf_counter() - t
    info["nodes"], info["tets"] = int(len(X)), int(len(T))
    note = count_note(len(T), vol, area, len(F), el, tries)
    if note:
        info["warnings"].append(note)
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
            f"{info['seconds']['simplify']:.1f} s, tetrahedralize {info['seconds']['tetrahedralize']:.1f} s"
            f" (envelope {eps:g}): {len(X):,} nodes, {len(T):,} tets"
        )
    return X, T, info


# The most times wall_envelope halves the default envelope (2e-3 / 16 = 1.25e-4 of the diagonal):
# below that fTetWild's run grows long; the volume check's retry may halve it once more.
WALL_HALVINGS = 4


def wall_envelope(eps: float, wall: float, diag: float) -> float:
    """The envelope (a fraction of the diagonal ``diag`` [m]) for a body whose walls are ``wall`` [m]
    thick (a closed surface's 2 × volume / area): ``eps`` halved until it spans at most half a wall
    (at most WALL_HALVINGS times). Within a wider envelope fTetWild may move a wall's two sheets
    onto each other: on the open kidney scan of ../shared/meshes (walls 0.34 mm, diagonal 15 cm)
    the envelope 2e-3 kept 28 % of the volume, and the volume check's retry at 1e-3 ran fTetWild
    again; hollow spheres of 2 cm with a 0.2 mm wall came out with 7–8 % too much volume at 2e-3,
    2.5–3 % at 1e-3. A solid body's walls are far thicker than any envelope (a sphere's 2V/A is 0.19
    of its diagonal): unchanged. So is a body whose walls are thinner than WALL_HALVINGS halvings
    reach (a sheet crushed flat, a surface of no volume): no envelope follows them, and a smaller one
    only makes fTetWild work longer on what it swallows anyway (a 10 cm disc 5 nm thick: refused in
    22 s at 1/16 of the envelope, in 0.5 s at the default)."""
    if eps * diag / 2**WALL_HALVINGS > 0.5 * wall:
        return eps
    while eps * diag > 0.5 * wall:
        eps /= 2
    return eps


# fTetWild's tets of edge el usually number 1.5–4 times the regular tets of that edge that fill the
# volume; beyond this many times, say why.
MANY_TETS = 10.0


def count_note(tets: int, volume: float, area: float, faces: int, el: float, tries: list) -> str | None:
    """Why ``tets`` tets are far more than the regular tets of edge ``el`` [m] that fill ``volume``
    [m³] (a regular tet of edge a: a³/(6√2)), or None when they are not (under ``MANY_TETS`` times).
    ``area`` [m²] and ``faces``: the meshed surface's; ``tries``: (envelope, volume ratio) of each
    fTetWild run. Triangles of edge el resolve area / (√3/4 el²) faces; fTetWild keeps the others.
    A closed surface's 2 × volume / area is the thickness of a thin-walled body (a wall of area A/2
    each side); walls thinner than the edge must be filled by tets as thin as they are."""
    regular = volume / (el**3 / (6.0 * math.sqrt(2.0)))
    if not (regular > 0 and tets > MANY_TETS * regular):
        return None
    thick = 2.0 * volume / area if area > 0 else math.inf
    why = []
    if len(tries) > 1:
        eps, ratio = tries[0]
        why.append(
            f"the envelope {eps:g} filled {100 * ratio:.0f} % of the volume, and the retry at "
            f"{tries[-1][0]:g} follows the surface closer"
        )
    resolved = area / (math.sqrt(3.0) / 4.0 * el * el)
    if faces > 4 * resolved:
        why.append(
            f"the surface keeps {faces:,} faces (at least {MIN_FACES:,}, to hold its shape) where "
            f"the edge resolves about {resolved:,.0f}; a surface of fewer faces (pliant mesh simplify) "
            "makes fewer tets"
        )
    if thick < el:
        why.append(
            f"the walls are about {thick:.2g} m thick (2 × volume / area) under the {el:.2g} m edge, "
            "and tets that fill them are no thicker than they are (an organ's capsule, a hollow "
            "organ? fill_shell, --fill-shell, meshes the solid inside it)"
        )
    if not why:
        why.append("fTetWild refined the surface to follow it within the envelope (a larger one makes fewer)")
    few = f"{regular:,.0f}" if regular >= 10 else f"{regular:.2g}"  # an edge near the body's size: 0.4
    return (
        f"{tets:,} tets, {tets / regular:,.0f} times the {few} regular tets of edge {el:.3g} m "
        "that fill the volume (usually 1.5–4 times): " + "; ".join(why)
    )


def _bodies(V: np.ndarray, F: np.ndarray) -> tuple[list, list[float], int]:
    """The bodies of a surface, as trimesh meshes: each outer body with the cavities and inclusions
    inside it (bodies.groups); the volume [m³] each fills (bodies.filled_volumes); and how many
    closed pieces the surface has (a body on an island in a cavity is two tet pieces)."""
    import trimesh

    from .bodies import filled_volumes, groups, parents

    pieces = trimesh.Trimesh(V, F, process=False).split(only_watertight=False)
    parent = parents(pieces) if len(pieces) > 1 else [-1] * len(pieces)
    grouped = groups(pieces, parent) if len(pieces) > 1 else [[0]] * len(pieces)
    bodies = [
        trimesh.util.concatenate([pieces[k] for k in g]) if len(g) > 1 else pieces[g[0]] for g in grouped
    ]
    return bodies, filled_volumes(pieces, parent), len(pieces)


def _diagonal(V: np.ndarray) -> float:
    """The bounding-box diagonal [m] of points V (n, 3)."""
    return float(np.linalg.norm(np.ptp(V, axis=0)))


def _separate(parts, edge_length, target_tets, epsilon, info, log):
    """Each body tetrahedralized on its own (one edge length for all), concatenated."""
    V = np.concatenate([p.vertices for p in parts])
    offs = np.cumsum([0] + [len(p.vertices) for p in parts])
    F = np.concatenate([np.asarray(p.faces) + o for p, o in zip(parts, offs)])
    el = edge_length if edge_length is not None else default_edge_length(V, F, target_tets)
    Xs, Ts, n = [], [], 0
    for p in parts:
        X, T, one = surface_to_tets(
            np.asarray(p.vertices),
            np.asarray(p.faces),
            edge_length=min(el, _diagonal(np.asarray(p.vertices))),  # a small body: its own size
            epsilon=epsilon,
            repair=False,
            bodies="one",
        )
        info["warnings"] += one["warnings"]
        Xs.append(X)
        Ts.append(T + n)
        n += len(X)
    X, T = np.concatenate(Xs), np.concatenate(Ts)
    info.update(edge_length=el, nodes=int(len(X)), tets=int(len(T)))
    if log:
        log(f"{len(parts)} bodies meshed separately: {len(X):,} nodes, {len(T):,} tets")
    return X, T, info
