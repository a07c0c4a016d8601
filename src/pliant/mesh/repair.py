"""Surface checks and repair, QEM simplification and Loop subdivision.

Libraries: trimesh (MIT) for connectivity and winding; fast-simplification (MIT,
Fast-Quadric-Mesh-Simplification, Garland–Heckbert quadric error metrics) for QEM. Loop
subdivision is ours (trimesh's weights its boundary vertices with all their neighbours). Hole filling
is ours: each boundary loop is closed by a minimum-area triangulation (fill_loop). Bodies
inside bodies (cavities, inclusions): bodies.py.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any

import math

import numpy as np

from ..checks import as_real, flag, mesh_arrays, whole_number
from ..errors import MeshError
from .topology import unique_rows


@dataclass
class SurfaceReport:
    """What `check_surface` found. ``ok`` means: a closed, manifold, consistently oriented,
    single-body surface without degenerate faces."""

    vertices: int
    faces: int
    bodies: int
    boundary_edges: int
    holes: int
    non_manifold_edges: int
    degenerate_faces: int
    duplicate_faces: int
    winding_consistent: bool
    outward: bool
    watertight: bool
    volume: float
    self_intersections: int | None = None
    cavities: int = 0  # bodies inside a body with faces pointing in (bodies.py); not in ``bodies``
    problems: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)  # worth knowing, not problems (``ok`` ignores them)

    @property
    def ok(self) -> bool:
        return not self.problems

    def as_dict(self) -> dict:
        d = asdict(self)
        d["ok"] = self.ok
        return d


def edge_counts(F: np.ndarray):
    """The edges (E, 2) of triangles F (K, 3), each once (ascending node ids), and how many
    triangles share each (E,): 1 on an open edge, 2 inside a manifold surface."""
    e = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
    return unique_rows(e, return_counts=True)


def boundary_loops(F: np.ndarray) -> list[np.ndarray]:
    """Closed loops of boundary edges (edges used by one face), as ordered vertex lists. A boundary
    that passes a vertex twice (two holes meeting at a vertex, a hole pinched to a figure eight) is
    cut there into simple loops, each of which fill_loop can close: the walk follows unused edges and
    cuts off a loop whenever it comes back to a vertex already on it."""
    directed = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    key = np.sort(directed, axis=1)
    uniq, inv, count = unique_rows(key, return_inverse=True, return_counts=True)
    b = directed[count[inv] == 1].tolist()
    out: dict[int, list[int]] = {}  # vertex → its outgoing boundary edges
    for k, (a, _) in enumerate(b):
        out.setdefault(int(a), []).append(k)
    used = [False] * len(b)
    loops = []
    for e0 in range(len(b)):
        if used[e0]:
            continue
        walk = [int(b[e0][0])]
        where = {walk[0]: 0}  # vertex → its place on the walk
        e: int | None = e0
        while e is not None:
            used[e] = True
            v = int(b[e][1])
            if v in where:  # back at a vertex of the walk: cut the loop off, go on from v
                i = where[v]
                loop = walk[i:]
                for u in loop[1:]:
                    del where[u]
                del walk[i + 1 :]
                if len(loop) >= 3:
                    loops.append(np.array(loop))
            else:
                where[v] = len(walk)
                walk.append(v)
            e = next((k for k in out.get(v, ()) if not used[k]), None)
    return loops


# A vertex out at 1e300 m (a scan's stray point) overflows areas and volumes to inf: reported as such.
@np.errstate(over="ignore", invalid="ignore", divide="ignore")
def check_surface(V: np.ndarray, F: np.ndarray, self_intersections: bool = True) -> SurfaceReport:
    """Watertightness, holes, non-manifold edges, degenerate and duplicate faces, winding
    consistency and orientation, number of bodies, self-intersections (sampled exactly)."""
    import trimesh

    V, F = mesh_arrays(V, F, 3, "check_surface", cell="face")
    self_intersections = flag(self_intersections, "check_surface: self_intersections")
    m = trimesh.Trimesh(V, F, process=False, validate=False)
    uniq, count = edge_counts(F)
    boundary = int((count == 1).sum())
    nonman = int((count > 2).sum())
    area = np.linalg.norm(np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]), axis=1) / 2
    # Degenerate: no area for its size (collinear or coincident corners), each face measured by its
    # own longest edge (by the surface's size, a stray vertex far out made every face so).
    longest = np.linalg.norm(V[F] - V[F[:, [1, 2, 0]]], axis=2).max(axis=1)
    degenerate = int((~(area / longest / longest > 1e-12)).sum())
    dup = len(F) - len(unique_rows(np.sort(F, axis=1)))
    # connected pieces (by shared edges); split into meshes only when there are several
    bodies = (
        trimesh.graph.connected_components(m.face_adjacency, nodes=np.arange(len(F)), min_len=1)
        if len(F)
        else []
    )
    pieces = m.split(only_watertight=False) if len(bodies) > 1 else [m] * len(bodies)
    bodies, cavities = len(pieces), 0
    if bodies > 1 and boundary == 0 and nonman == 0:  # nesting: of closed pieces only
        from .bodies import groups

        grouped = groups(pieces)
        bodies = len(grouped)
        cavities = sum(int(pieces[k].volume < 0) for g in grouped for k in g[1:])
    holes = len(boundary_loops(F)) if boundary else 0
    winding = bool(m.is_winding_consistent)
    watertight = boundary == 0 and nonman == 0
    volume = float(m.volume) if watertight else float("nan")
    rep = SurfaceReport(
        len(V),
        len(F),
        bodies,
        boundary,
        holes,
        nonman,
        degenerate,
        dup,
        winding,
        bool(watertight and volume > 0),
        watertight,
        volume,
        cavities=int(cavities),
    )
    if self_intersections and nonman == 0:
        rep.self_intersections = count_self_intersections(V, F)
    if boundary:
        rep.problems.append(f"{holes} hole(s) ({boundary} boundary edges)")
    if nonman:
        rep.problems.append(f"{nonman} non-manifold edge(s)")
    if degenerate:
        rep.problems.append(f"{degenerate} degenerate face(s)")
    if dup:
        rep.problems.append(f"{dup} duplicate face(s)")
    if not winding:
        rep.problems.append("inconsistent winding")
    elif watertight and volume <= 0:
        rep.problems.append("faces oriented inward")
    if bodies > 1:
        rep.problems.append(f"{bodies} separate bodies")
    if rep.self_intersections:
        rep.problems.append(f"{rep.self_intersections} self-intersecting face pair(s)")
    if nonman and _repairs_touching(V, F):
        rep.notes.append(
            f"the {nonman} non-manifold edge(s) are where bodies touch: repair (and tetrahedralize) "
            "splits the surface there"
        )
    stray = stray_vertex(V, F)
    if stray:
        rep.problems.append(stray)
    wall = 2.0 * volume / float(area.sum()) if watertight and volume > 0 else math.inf
    across = float(np.linalg.norm(np.ptp(V, axis=0))) if len(V) else 0.0
    if wall < THIN_WALL * across and not stray:  # a closed surface of area A around V: walls 2V/A thick
        rep.notes.append(
            f"thin-walled: walls about {wall:.2g} m thick (2 × volume / area) on a body {across:.2g} m "
            "across; an organ's capsule (two sheets around a hollow)? `pliant mesh tetrahedralize "
            "--fill-shell` meshes the solid inside it"
        )
    return rep


# A closed surface whose walls (2 × volume / area) are under this share of its diagonal is noted as
# thin-walled: a sphere's are 0.19 of it, HuBMAP's liver capsule's 0.003.
THIN_WALL = 0.02


@np.errstate(over="ignore", invalid="ignore", divide="ignore")  # faces out at 1e300 m
def count_self_intersections(V: np.ndarray, F: np.ndarray, max_pairs: int = 2_000_000) -> int:
    """Number of pairs of faces that share no vertex and intersect (Möller 1997 interval test on
    candidate pairs from a uniform grid over face bounding boxes)."""
    tri = V[F]
    lo, hi = tri.min(axis=1), tri.max(axis=1)
    h = float(np.median(hi - lo)) * 2
    h = h if 0 < h < math.inf else 1.0
    # A face over more cells than there are faces (a stray vertex far out: a scan's spike; a box's
    # face beside a fine sphere) is tested against every face its box meets, the cheaper way, instead
    # of being put in each cell (a spike to 1e12 m put one face in 1e14 cells).
    large = ~(np.prod(np.floor(hi / h) - np.floor(lo / h) + 1, axis=1) <= max(LARGE_FACE_CELLS, len(F)))
    small = np.nonzero(~large)[0]
    origin = lo[small].min(axis=0) if len(small) else np.zeros(3)
    cl = np.floor((lo[small] - origin) / h).astype(np.int64)
    ch = np.floor((hi[small] - origin) / h).astype(np.int64)
    cell_list, owner_list = [], []
    for k, i in enumerate(small):
        r = [np.arange(cl[k, d], ch[k, d] + 1) for d in range(3)]
        g = np.stack(np.meshgrid(*r, indexing="ij"), -1).reshape(-1, 3)
        cell_list.append(g)
        owner_list.append(np.full(len(g), i))
    pairs = [_large_face_pairs(np.nonzero(large)[0], lo, hi, max_pairs)]
    if cell_list:
        pairs += _shared_cell_pairs(np.concatenate(cell_list), np.concatenate(owner_list))
    pairs = [p for p in pairs if len(p)]
    if not pairs:
        return 0
    P = unique_rows(np.sort(np.concatenate(pairs), axis=1))
    P = P[P[:, 0] != P[:, 1]][:max_pairs]
    share = (F[P[:, 0]][:, :, None] == F[P[:, 1]][:, None, :]).any(axis=(1, 2))
    P = P[~share]
    overlap = np.all((lo[P[:, 0]] <= hi[P[:, 1]]) & (lo[P[:, 1]] <= hi[P[:, 0]]), axis=1)
    P = P[overlap]
    return int(_tri_tri_intersect(tri[P[:, 0]], tri[P[:, 1]]).sum())


# A face whose bounding box covers more cells of count_self_intersections' grid than this (and than
# there are faces) is a large face, paired by its box with every face instead (_large_face_pairs).
LARGE_FACE_CELLS = 512


def _shared_cell_pairs(cells: np.ndarray, owners: np.ndarray) -> list[np.ndarray]:
    """Pairs (k, 2) of the faces (``owners``) that have a grid cell (``cells``, (n, 3)) in common,
    one array per shared cell."""
    key = (cells[:, 0] * 73856093) ^ (cells[:, 1] * 19349663) ^ (cells[:, 2] * 83492791)
    order = np.argsort(key, kind="stable")
    key, owners = key[order], owners[order]
    starts = np.nonzero(np.r_[True, key[1:] != key[:-1]])[0]
    ends = np.r_[starts[1:], len(key)]
    pairs = []
    for s, e in zip(starts, ends):
        if e - s > 1:
            o = owners[s:e]
            a, b = np.triu_indices(len(o), 1)
            pairs.append(np.stack([o[a], o[b]], 1))
    return pairs


def _large_face_pairs(large: np.ndarray, lo: np.ndarray, hi: np.ndarray, max_pairs: int) -> np.ndarray:
    """Pairs (k, 2) of each large face (indices ``large``) with every other face whose bounding box
    (``lo``, ``hi``, (F, 3)) meets its own, at most ``max_pairs`` of them."""
    out, count = [], 0
    for i in large:
        meets = np.nonzero(np.all((lo <= hi[i]) & (lo[i] <= hi), axis=1))[0]
        meets = meets[meets != i]
        out.append(np.stack([np.full(len(meets), i), meets], 1))
        count += len(meets)
        if count >= max_pairs:
            break
    return np.concatenate(out) if out else np.zeros((0, 2), np.int64)


def _tri_tri_intersect(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """Vectorized triangle–triangle intersection test for non-coplanar pairs (Möller 1997)."""

    def plane(T):
        n = np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0])
        return n, -np.einsum("ij,ij->i", n, T[:, 0])

    nA, dA = plane(A)
    nB, dB = plane(B)
    sB = np.einsum("ikj,ij->ik", B, nA) + dA[:, None]
    sA = np.einsum("ikj,ij->ik", A, nB) + dB[:, None]
    eps = 1e-12 * (np.abs(sA).max(axis=1) + np.abs(sB).max(axis=1) + 1e-300)
    sB = np.where(np.abs(sB) < eps[:, None], 0, sB)
    sA = np.where(np.abs(sA) < eps[:, None], 0, sA)
    sep = np.all(sB > 0, 1) | np.all(sB < 0, 1) | np.all(sA > 0, 1) | np.all(sA < 0, 1)
    coplanar = np.all(sB == 0, 1)
    D = np.cross(nA, nB)

    def interval(T, s, Dc):
        p = np.einsum("ikj,ij->ik", T, Dc)
        out = np.empty((len(T), 2))
        for i in range(len(T)):
            si, pi = s[i], p[i]
            ts = []
            for a, b in ((0, 1), (1, 2), (2, 0)):
                if si[a] == 0:
                    ts.append(pi[a])
                if si[a] * si[b] < 0:
                    ts.append(pi[a] + (pi[b] - pi[a]) * si[a] / (si[a] - si[b]))
            out[i] = (min(ts), max(ts)) if ts else (np.inf, -np.inf)
        return out

    res = np.zeros(len(A), bool)
    cand = np.nonzero(~sep & ~coplanar)[0]
    if cand.size:
        ia = interval(A[cand], sA[cand], D[cand])
        ib = interval(B[cand], sB[cand], D[cand])
        tol = 1e-12 * (np.abs(ia).max(axis=1) + np.abs(ib).max(axis=1))
        res[cand] = (ia[:, 0] < ib[:, 1] - tol) & (ib[:, 0] < ia[:, 1] - tol)
    return res


def fill_loop(V: np.ndarray, loop: np.ndarray, existing_edges: set | None = None) -> np.ndarray:
    """Minimum-area triangulation of a boundary loop (vertex indices in boundary-edge order):
    W(i, j) = min_m W(i, m) + W(m, j) + area(i, m, j), never using as a diagonal an edge that the
    surface already has (that would make it non-manifold). Faces are oriented to continue the
    surface (each boundary edge a → b is used as b → a). Returns faces (len(loop) − 2, 3)."""
    P = V[loop]
    n = len(loop)
    W = np.zeros((n, n))
    best = np.zeros((n, n), dtype=np.int64)
    existing = existing_edges or set()
    for L in range(2, n):
        for i in range(0, n - L):
            j = i + L
            if L < n - 1 and (min(loop[i], loop[j]), max(loop[i], loop[j])) in existing:
                W[i, j] = np.inf
                continue
            m = np.arange(i + 1, j)
            area = 0.5 * np.linalg.norm(np.cross(P[m] - P[i], P[j] - P[i]), axis=1)
            cost = W[i, m] + W[m, j] + area
            k = int(np.argmin(cost))
            W[i, j], best[i, j] = cost[k], m[k]
    faces, stack = [], [(0, n - 1)]
    while stack:
        i, j = stack.pop()
        if j - i < 2:
            continue
        m = best[i, j]
        faces.append((loop[j], loop[m], loop[i]))
        stack += [(i, m), (m, j)]
    return np.array(faces, dtype=np.int64)


BODIES = ("one", "all", "largest")
MAX_FACES = 2e7  # surfaces beyond this exhaust a workstation's memory in the mesh pipeline


def repair_surface(
    V: np.ndarray, F: np.ndarray, fill_holes: bool = True, keep_largest: bool = False, bodies: str = "one"
) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Merge duplicate vertices, drop degenerate and duplicate faces and fragments (bodies with
    under 1 % of the faces), fill holes (minimum-area triangulation), make winding consistent and
    each body's faces point outward. Returns (V, F, actions).

    ``bodies``: what to do with a surface of several closed bodies (a teapot's body, lid, handle
    and spout; two organs): "one" refuses it, "all" keeps every body (each closed and outward;
    they may overlap: tetrahedralization then meshes their union), "largest" keeps the largest
    (``keep_largest=True`` is the same). Raises MeshError naming the reason when the result is
    still not closed (e.g. non-manifold edges) or encloses no volume."""
    import trimesh

    fill_holes = flag(fill_holes, "repair_surface: fill_holes")
    if flag(keep_largest, "repair_surface: keep_largest"):
        bodies = "largest"
    if not isinstance(bodies, str) or bodies not in BODIES:
        raise MeshError(f"repair: bodies = {bodies!r}; expected one of {', '.join(BODIES)}")
    actions = []
    # process: merge duplicate vertices; not validate, whose fix_normals would re-wind faces
    # silently (trimesh 5): the winding is fixed, and reported, body by body (_close_body).
    # trimesh merges vertices and finds degenerate faces with absolute tolerances (1e-8): work on the
    # surface scaled by a power of two (exact) to a diagonal of about 1, so that a surface 1e-9 or
    # 1e30 across is repaired as one of 1 m (its vertices all merged, or rounded past int64, were).
    from .primitives import unit_scale

    V, F = mesh_arrays(V, F, 3, "repair", cell="face")
    scale = unit_scale(V)
    m = trimesh.Trimesh(V * scale, F, process=True, validate=False)
    m.update_faces(m.unique_faces() & m.nondegenerate_faces())
    m.remove_unreferenced_vertices()
    if len(m.vertices) < len(V):
        actions.append(f"merged {len(V) - len(m.vertices)} duplicate/unused vertices")
    if len(m.faces) < len(F):
        actions.append(f"removed {len(F) - len(m.faces)} degenerate/duplicate faces")
    if len(m.faces) == 0:
        raise MeshError(
            f"repair: no valid faces left (every face is degenerate or a duplicate){_also(stray_vertex(V))}"
        )
    groups = trimesh.graph.connected_components(m.face_adjacency, nodes=np.arange(len(m.faces)), min_len=1)
    big = [g for g in groups if len(g) >= 0.01 * len(m.faces)]
    if len(big) < len(groups):
        actions.append(
            f"dropped {len(groups) - len(big)} fragment(s) of {len(m.faces) - sum(len(g) for g in big)} faces"
        )
    shared = _split_touching(np.asarray(m.faces), big, actions)
    parts: list = [m.submesh([g], append=True) for g in big]
    done = _solid([_close_body(p, fill_holes, actions) for p in parts], shared, actions)
    closed, grouped = _orient_bodies([c for c, _ in done], [r for _, r in done], actions)
    if len(grouped) > 1 and bodies == "one":
        raise MeshError(
            f"repair: {len(grouped)} separate bodies; keep them all (bodies='all', "
            "--bodies all: their union is meshed), or the largest (--bodies largest)"
        )
    if len(grouped) > 1 and bodies == "largest":
        n = len(grouped)
        grouped = [max(grouped, key=lambda g: len(closed[g[0]].faces))]
        actions.append(f"kept the largest of {n} bodies")
    if len(grouped) > 1:
        actions.append(f"kept {len(grouped)} bodies")
    keep = [closed[k] for g in grouped for k in g]
    out: Any = trimesh.util.concatenate(keep) if len(keep) > 1 else keep[0]
    rep = check_surface(out.vertices, out.faces, self_intersections=False)
    if not rep.watertight or not rep.winding_consistent:
        raise MeshError(
            f"repair: still not a closed, consistently oriented surface after "
            f"repair ({'; '.join(rep.problems)})"
        )
    return np.asarray(out.vertices, float) / scale, np.asarray(out.faces, np.int64), _once(actions)


def _split_touching(F: np.ndarray, pieces: list, actions: list[str]) -> int:
    """Non-manifold edges (of more than two faces) where bodies touch: two cubes sharing an edge
    (four faces on it), or two regions sharing an interface (three faces on each of its edges). The
    pieces (face indices, joined across edges of two faces only: trimesh's face_adjacency) come
    apart there, each with its own copy of the edge, and hole filling closes the open ones (each
    region over the interface); a piece that still holds such an edge more than twice raises
    MeshError. Returns how many edges were split."""
    uniq, count = edge_counts(F[np.concatenate(pieces)])
    shared = {tuple(e) for e in uniq[count > 2].tolist()}
    if not shared:
        return 0
    for g in pieces:
        e, c = edge_counts(F[g])
        held = np.array([tuple(x) in shared for x in e.tolist()], bool)
        if (c[held] > 2).any():
            raise MeshError(
                f"repair: {len(shared)} non-manifold edge(s) (shared by more than two faces) "
                "within one piece; cannot repair automatically"
            )
    actions.append(f"split the surface at {len(shared)} non-manifold edge(s) (bodies touching there)")
    return len(shared)


def _once(actions: list[str]) -> list[str]:
    """Each action once, in order, an action done to several pieces alike saying how many."""
    count: dict[str, int] = {}
    for a in actions:
        count[a] = count.get(a, 0) + 1
    return [a if n == 1 else f"{a}, in each of {n} pieces" for a, n in count.items()]


def _repairs_touching(V: np.ndarray, F: np.ndarray) -> bool:
    """Whether repair_surface (keeping every body) splits the surface's non-manifold edges where
    bodies touch and closes what it splits (_split_touching, _solid)."""
    try:
        _, _, actions = repair_surface(V, F, bodies="all")
    except MeshError:
        return False
    return any(a.startswith("split the surface at") for a in actions)


def _solid(done: list, shared: int, actions: list[str]) -> list:
    """The closed pieces (_close_body's) less the flat ones, enclosing less than 1e-9 of their own
    diagonal cubed: a sheet and the triangulation that closed its hole, such as an interface that
    _split_touching left on its own. If every piece is flat, MeshError where non-manifold edges
    were split (the pieces between them enclose nothing), else all of them (what checks them next
    names the reason: no volume, a vertex far from the others)."""

    def flat(m) -> bool:
        V, F = np.asarray(m.vertices), np.asarray(m.faces)
        return abs(surface_volume(V, F)) <= 1e-9 * float(np.linalg.norm(np.ptp(V, axis=0))) ** 3

    kept = [d for d in done if not flat(d[0])]
    if not kept and shared:
        raise MeshError(
            f"repair: no piece of the surface encloses a volume (the pieces between its {shared} "
            "non-manifold edge(s)); cannot repair automatically"
        )
    if not kept:
        return done
    if len(kept) < len(done):
        actions.append(f"dropped {len(done) - len(kept)} flat piece(s) enclosing no volume")
    return kept


def _close_body(m, fill_holes: bool, actions: list[str]):
    """One connected body: holes filled, winding consistent. Returns it and whether its winding was
    changed (its orientation then says nothing of the file's intent)."""
    import trimesh

    Vr, Fr = np.asarray(m.vertices, float), np.asarray(m.faces, np.int64)
    if fill_holes:
        loops = boundary_loops(Fr)
        if loops:
            uniq, _ = edge_counts(Fr)
            existing = set(map(tuple, uniq.tolist()))
            Fr = np.concatenate([Fr] + [fill_loop(Vr, loop, existing) for loop in loops])
            actions.append(
                f"filled {len(loops)} hole(s) ({sum(len(l) for l in loops)} boundary "
                "edges) by minimum-area triangulation"
            )
    m = trimesh.Trimesh(Vr, Fr, process=False)
    rewound = not m.is_winding_consistent
    if rewound:
        trimesh.repair.fix_winding(m)
        actions.append("made winding consistent")
    return m, rewound


def _orient_bodies(closed: list, rewound: list, actions: list[str]) -> tuple[list, list[list[int]]]:
    """Outer bodies' faces outward; a body inside another keeps its orientation relative to the
    outer one (faces in: a cavity; out: an inclusion, meshed with its container), unless its winding
    had to be made consistent, when it points outward. Returns the bodies and their groups
    (bodies.groups: each outer body with the bodies inside it)."""
    from .bodies import groups

    grouped = groups(closed) if len(closed) > 1 else [[0]]
    for g in grouped:
        flip = closed[g[0]].is_watertight and closed[g[0]].volume < 0
        for k in g:
            b = closed[k]
            if k != g[0] and rewound[k]:
                if b.is_watertight and b.volume < 0:
                    b.invert()
            elif flip:
                b.invert()
        if flip:
            actions.append("flipped faces outward")
        cavities = sum(closed[k].volume < 0 for k in g[1:])
        if cavities:
            actions.append(f"kept {cavities} inner surface(s) facing inward (cavities)")
    return closed, grouped


def surface_volume(V: np.ndarray, F: np.ndarray) -> float:
    """Signed volume [m³] a closed triangle surface encloses (divergence theorem: Σ x0·(x1 × x2)/6
    over faces); positive for outward faces."""
    P = np.asarray(V, float)[np.asarray(F, np.int64)]
    return float(np.einsum("ij,ij->i", P[:, 0], np.cross(P[:, 1], P[:, 2])).sum() / 6)


def require_volume(V: np.ndarray, F: np.ndarray, closed: bool = True, who: str = "") -> None:
    """Refuse a surface that encloses no volume (flat: all vertices on a plane or a line; or, for a
    closed surface, a signed volume ~0, as in a sheet folded onto itself): tetrahedralizers crash
    or loop on such input. Raises MeshError ("``who``: the surface encloses no volume: why")."""
    V = np.asarray(V, float)
    why = _no_volume(V, F, closed)
    if why:
        stray = stray_vertex(V)
        if stray:  # what the stray point's size makes of the rest: flat, or no volume
            why = f"{stray}, beside which the rest is as good as flat ({why})"
        raise MeshError(
            f"{who}{': ' if who else ''}the surface encloses no volume: {why}; expected a closed "
            "surface around a solid"
        )


def _also(words: str) -> str:
    """ "; words" where there are any."""
    return f"; {words}" if words else ""


@np.errstate(over="ignore", invalid="ignore")
def stray_vertex(V: np.ndarray, F: np.ndarray | None = None) -> str:
    """Words for a vertex of V [m] (n, 3) (of those faces F use, where given) far from the others (a
    scan's stray point: over 100 times farther from their median than 99 % of them, of 100 or
    more) for an error ("vertex k lies ..."), or "". Such a vertex makes the surface's size, and
    every tolerance relative to it, that of the stray point."""
    used = np.arange(len(V)) if F is None else np.unique(F)
    if len(used) < 100:
        return ""
    d = np.linalg.norm(V[used] - np.median(V[used], axis=0), axis=1)
    bulk, far = float(np.percentile(d, 99)), int(np.argmax(d))
    if not (bulk > 0 and d[far] > 100 * bulk):
        return ""
    return (
        f"vertex {int(used[far])} lies {d[far]:.3g} m from the others' median, 99 % of them within "
        f"{bulk:.3g} m of it (a stray vertex? remove it and its faces)"
    )


def _no_volume(V: np.ndarray, F: np.ndarray, closed: bool) -> str | None:
    if len(V) < 4 or (closed and len(F) < 4):
        return f"{len(V)} vertices and {len(F)} faces cannot enclose a volume"
    sv = np.linalg.svd(V - V.mean(axis=0), compute_uv=False)
    if not sv[0] > 0:
        return "all vertices coincide"
    if sv[2] <= 1e-9 * sv[0]:
        return "all vertices lie on one plane (a flat sheet)"
    if not closed:
        return None
    vol = surface_volume(V, F)
    diag = float(np.linalg.norm(V.max(axis=0) - V.min(axis=0)))
    if abs(vol) <= 1e-9 * diag**3:
        return (
            f"its faces enclose a signed volume of {vol:.3g} m^3, under 1e-9 of the cube of its "
            f"{diag:.3g} m diagonal (a zero-thickness shell, or a vertex far from the others)"
        )
    return None


def simplify(
    V: np.ndarray,
    F: np.ndarray,
    target_faces: int | None = None,
    ratio: float | None = None,
    preserve_boundary: bool = True,
) -> tuple[np.ndarray, np.ndarray]:
    """QEM simplification (Garland & Heckbert 1997) to ``target_faces`` faces or a ``ratio`` of
    them, through fast-simplification. Open boundaries are kept (their vertices are not collapsed)
    unless ``preserve_boundary=False``; the result is checked for manifoldness, and a collapse
    order that made an edge non-manifold is retried less aggressively before giving up.
    (A closed surface of genus 0 with F faces has F/2 + 2 vertices.)"""
    import fast_simplification

    if (target_faces is None) == (ratio is None):
        raise MeshError("simplify: give exactly one of target_faces or ratio")
    V, F = mesh_arrays(V, F, 3, "simplify", cell="face")
    preserve_boundary = flag(preserve_boundary, "simplify: preserve_boundary")
    if ratio is not None:
        if not 0 < as_real(ratio) <= 1:
            raise MeshError(f"simplify: ratio = {ratio!r}; expected 0 < ratio <= 1")
        target_faces = int(round(float(ratio) * len(F)))
    assert target_faces is not None  # one of the two was given
    target_faces = whole_number(target_faces, "simplify: target_faces", " of faces")
    if target_faces < 4:
        raise MeshError(f"simplify: target of {target_faces} faces; expected >= 4")
    if target_faces >= len(F):
        return np.asarray(V, float), np.asarray(F, np.int64)
    _, count = edge_counts(np.asarray(F))
    open_mesh = bool((count == 1).any())
    for agg in (7.0, 3.0, 1.0):
        Vs, Fs = fast_simplification.simplify(
            np.asarray(V, np.float32),
            np.asarray(F, np.int32),
            target_count=int(target_faces),
            agg=agg,
            preserve_border=bool(preserve_boundary and open_mesh),
        )
        Fs = np.asarray(Fs, np.int64)
        if not (edge_counts(Fs)[1] > 2).any():
            used = np.unique(Fs)  # drop vertices no face uses any more
            remap = np.full(len(Vs), -1, dtype=np.int64)
            remap[used] = np.arange(used.size)
            return np.asarray(Vs, float)[used], remap[Fs]
    raise MeshError(
        "simplify: every collapse order tried made an edge non-manifold; repair the "
        "surface first (pliant mesh repair) or simplify less"
    )


def subdivide_loop(V: np.ndarray, F: np.ndarray, levels: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """Loop subdivision (Loop 1987, "Smooth subdivision surfaces based on triangles", §3), with
    Loop's boundary rules, ``levels`` times. Each edge gets a new (odd) vertex: 3/8 (a + b) +
    1/8 (c + d) inside, the midpoint on a boundary; each old (even) vertex moves to
    (1 − nβ) v + β Σ neighbours, β = (5/8 − (3/8 + cos(2π/n)/4)²)/n, inside, and to
    3/4 v + 1/8 (b1 + b2) on a boundary (b1, b2 its boundary neighbours: the cubic B-spline rule, so
    boundary curves subdivide as curves). Vertices: V + E per level; faces: 4 F."""
    if whole_number(levels, "subdivide: levels") < 0:
        raise MeshError(f"subdivide: levels = {levels}; expected >= 0")
    V, F = mesh_arrays(V, F, 3, "subdivide", cell="face")
    faces = len(F) * 4.0 ** min(int(levels), 500)  # 4^500 ≈ 1e301: no float overflow
    if faces > MAX_FACES:
        raise MeshError(
            f"subdivide: {levels} levels turn {len(F):,} faces into "
            f"{faces:.3g}{' or more' if levels > 500 else ''}; expected at most "
            f"{MAX_FACES:.0e} (fewer levels, or simplify first)"
        )
    for _ in range(int(levels)):
        V, F = _loop_once(V, F)
    return V, F


def _loop_once(V: np.ndarray, F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    nv = len(V)
    half = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])  # (3F, 2), face k*F + f
    opp = np.concatenate([F[:, 2], F[:, 0], F[:, 1]])  # vertex opposite each
    key = np.sort(half, axis=1)
    edges, inv, count = unique_rows(key, return_inverse=True, return_counts=True)
    if (count > 2).any():
        raise MeshError(f"subdivide: {(count > 2).sum()} non-manifold edge(s); repair first")
    ne = len(edges)
    # Odd vertices.
    opp_sum = np.zeros((ne, 3))
    np.add.at(opp_sum, inv, V[opp])
    boundary = count == 1
    odd = np.where(
        boundary[:, None],
        0.5 * (V[edges[:, 0]] + V[edges[:, 1]]),
        0.375 * (V[edges[:, 0]] + V[edges[:, 1]]) + 0.125 * opp_sum,
    )
    # Even vertices: interior rule from all neighbours, boundary rule from boundary neighbours.
    nb_sum = np.zeros((nv, 3))
    n = np.zeros(nv)
    for i, j in ((0, 1), (1, 0)):
        np.add.at(nb_sum, edges[:, i], V[edges[:, j]])
        np.add.at(n, edges[:, i], 1)
    bnd_sum = np.zeros((nv, 3))
    bnd_n = np.zeros(nv)
    be = edges[boundary]
    for i, j in ((0, 1), (1, 0)):
        np.add.at(bnd_sum, be[:, i], V[be[:, j]])
        np.add.at(bnd_n, be[:, i], 1)
    with np.errstate(divide="ignore", invalid="ignore"):
        beta = (0.625 - (0.375 + 0.25 * np.cos(2 * np.pi / n)) ** 2) / n
    even = np.where((n > 0)[:, None], (1 - n * beta)[:, None] * V + beta[:, None] * nb_sum, V)
    on_b = bnd_n == 2
    even[on_b] = 0.75 * V[on_b] + 0.125 * bnd_sum[on_b]
    # Faces: 4 per face.
    m = nv + inv.reshape(3, -1)  # odd vertex of edges (0,1), (1,2), (2,0) of each face
    e01, e12, e20 = m[0], m[1], m[2]
    a, b, c = F[:, 0], F[:, 1], F[:, 2]
    F2 = np.concatenate(
        [
            np.stack([a, e01, e20], 1),
            np.stack([e01, b, e12], 1),
            np.stack([e20, e12, c], 1),
            np.stack([e01, e12, e20], 1),
        ]
    )
    return np.concatenate([even, odd]), F2
