"""Tetrahedralization of closed surfaces.

Default engine: fTetWild (Hu et al. 2020, "Fast Tetrahedral Meshing in the Wild", ACM TOG 39(4)),
through the ``pytetwild`` wheel (MPL-2.0: file-level copyleft that does not bind users' code).
fTetWild is Delaunay-based and robust to dirty input (small holes, self-intersections) thanks to its
envelope and winding-number filtering. TetGen (AGPL) is deliberately not a dependency.
Output tets are positively oriented; degenerate slivers are removed.
"""

from __future__ import annotations

import hashlib
import math
import os
from pathlib import Path

import numpy as np

from ..checks import as_real, flag, mesh_arrays, shown, whole_number
from ..errors import MeshError
from .topology import drop_unused, unique_rows
from . import ftetwild
from .primitives import orient_positive, tet_volumes, triangle_measures, unit_scale


MAX_TETS = 2e7  # beyond this fTetWild runs for hours and exhausts a workstation's memory
# fTetWild's target edge is at most this fraction of the bounding-box diagonal. Beyond it the mesh is
# no coarser (fTetWild keeps the surface's detail within its envelope: a 642-vertex sphere gave
# 2,700-3,300 tets for any edge from 0.09 to 1.4 diagonals) while fTetWild's run grows without bound
# (that sphere: 1.5 s at 0.3 diagonals, 8 s at 0.9, 25 s at 1.4, over 2 minutes at 6).
EDGE_CAP = 0.25
# fTetWild's envelope (relative to the diagonal) from MIN_ENVELOPE to MAX_ENVELOPE. Its run grows
# steeply as the envelope shrinks (a 642-vertex sphere at the default edge: 6.7 s at 1e-4, 24 s at
# 5e-5, 67 s at 3e-5, over 100 s at 1e-5), and it aborted (SIGABRT) at 0.1 and 0.2. The pipeline's
# smallest own envelope is 2e-3 / 32 (surface_to_tets: wall_envelope, then the volume check's retry).
MIN_ENVELOPE, MAX_ENVELOPE = 5e-5, 0.05


def largest_component(tets: np.ndarray, keep_all: bool = False, island: float = 0.01) -> np.ndarray:
    """The tets of the largest face-connected component (fTetWild can leave small islands of tets
    inside thin or self-intersecting regions of a scan); with ``keep_all``, every component of at
    least ``island`` × the tet count (separate bodies meshed together)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    M = len(tets)
    faces = np.sort(
        np.concatenate([tets[:, [1, 2, 3]], tets[:, [0, 2, 3]], tets[:, [0, 1, 3]], tets[:, [0, 1, 2]]]),
        axis=1,
    )
    owner = np.tile(np.arange(M), 4)
    _, inv = unique_rows(faces, return_inverse=True)
    order = np.argsort(inv, kind="stable")
    same = inv[order][1:] == inv[order][:-1]
    a, b = owner[order][:-1][same], owner[order][1:][same]
    n, label = connected_components(coo_matrix((np.ones(a.size), (a, b)), shape=(M, M)), directed=False)
    if n == 1:
        return tets
    sizes = np.bincount(label)
    if keep_all:
        return tets[sizes[label] >= island * M]
    return tets[label == np.argmax(sizes)]


def edge(value, diag: float, who: str) -> float:
    """A tet edge length [m] given by the user: a finite number > 0, at most the surface's
    bounding-box diagonal ``diag`` [m]; MeshError naming ``who`` otherwise (none where "": a scene
    names its key)."""
    el, who = as_real(value), f"{who}: " if who else ""
    if not (math.isfinite(el) and el > 0):
        raise MeshError(f"{who}edge length {shown(value)}; expected a finite length > 0 [m]")
    if el > diag:
        raise MeshError(
            f"{who}edge length {el:.3g} m is longer than the surface's bounding-box diagonal "
            f"({diag:.3g} m): no tet of that edge fits in it; expected at most {diag:.3g} m "
            "(a length in other units than the surface's?)"
        )
    return el


def envelope(value, who: str) -> float:
    """fTetWild's envelope, relative to the bounding-box diagonal: MIN_ENVELOPE to MAX_ENVELOPE."""
    eps = as_real(value)
    if not MIN_ENVELOPE <= eps <= MAX_ENVELOPE:
        raise MeshError(
            f"{who}: epsilon = {shown(value)}; expected an envelope relative to the bounding-box "
            f"diagonal from {MIN_ENVELOPE:g} to {MAX_ENVELOPE:g} (a smaller one runs fTetWild for "
            "minutes, a larger one makes it abort)"
        )
    return eps


def cache_dir() -> Path:
    d = Path(os.environ.get("PLIANT_CACHE", Path.home() / ".cache" / "pliant"))
    d.mkdir(parents=True, exist_ok=True)
    return d


def tetrahedralize(
    V: np.ndarray,
    F: np.ndarray,
    edge_length: float | None = None,
    edge_length_fac: float = 0.05,
    epsilon: float = 1e-3,
    optimize: bool = True,
    threads: int = 0,
    cache: bool = True,
    keep_all: bool = False,
) -> tuple[np.ndarray, np.ndarray]:
    """Tet mesh of the volume bounded by a triangle surface V [m] (n, 3), F (f, 3).

    edge_length: target tet edge [m] (default: ``edge_length_fac`` × bounding-box diagonal).
    epsilon: allowed surface deviation, relative to the bounding-box diagonal.
    Returns nodes [m] (N, 3) and positively oriented tets (M, 4). Results are cached on disk
    (``$PLIANT_CACHE`` or ~/.cache/pliant) keyed by the input and the parameters. Only the largest
    connected piece of the result is kept, or with ``keep_all`` every piece of at least 1 % of the
    tets (several bodies). A surface that encloses no volume is refused before fTetWild sees it
    (fTetWild crashes on flat input), and so is an edge longer than the surface's bounding-box
    diagonal (no such tet fits in it; fTetWild ran for minutes on one: a length in other units?).
    fTetWild is given at most ``EDGE_CAP`` × the diagonal (no coarser a mesh, and a bounded run)."""
    from .repair import require_volume, surface_volume

    V, F = mesh_arrays(V, F, 3, "tetrahedralize", cell="face")
    optimize = flag(optimize, "tetrahedralize: optimize")
    cache = flag(cache, "tetrahedralize: cache")
    keep_all = flag(keep_all, "tetrahedralize: keep_all")
    epsilon = envelope(epsilon, "tetrahedralize")
    threads = whole_number(threads, "tetrahedralize: threads")
    if threads < 0:
        raise MeshError(f"tetrahedralize: threads = {threads}; expected 0 (all cores) or more")
    V, F = np.ascontiguousarray(V), np.ascontiguousarray(F, dtype=np.uint32)
    if len(V) < 4 or len(F) < 4:
        raise MeshError(
            f"tetrahedralize: need a closed triangle surface, got {V.shape} vertices, {F.shape} faces"
        )
    require_volume(V, F, who="tetrahedralize")
    diag = float(np.linalg.norm(V.max(axis=0) - V.min(axis=0)))
    el = edge(edge_length, diag, "tetrahedralize") if edge_length is not None else None
    if el is None:
        fac = as_real(edge_length_fac)
        if not 0 < fac <= 1:
            raise MeshError(
                f"tetrahedralize: edge_length_fac = {shown(edge_length_fac)}; expected a fraction of "
                "the bounding-box diagonal, 0 < edge_length_fac <= 1"
            )
        el = fac * diag
    volume = abs(surface_volume(V, F))
    area = float(triangle_measures(V, F.astype(np.int64))[0].sum())
    with np.errstate(over="ignore", divide="ignore"):  # el = 1e-300: el³ is 0, the counts inf
        expected = float(np.float64(volume) / (np.float64(el) ** 3 / (6 * math.sqrt(2))))  # regular tets
        faces = float(np.float64(area) / (math.sqrt(3) / 4 * np.float64(el) ** 2))  # triangles of edge el
    if expected > MAX_TETS:
        raise MeshError(
            f"tetrahedralize: edge length {el:.3g} m would make about {expected:.3g} "
            f"tets in the surface's {volume:.3g} m^3; expected at most {MAX_TETS:.0e} "
            "(give a larger edge length)"
        )
    if faces > MAX_TETS:
        raise MeshError(
            f"tetrahedralize: edge length {el:.3g} m would make about {faces:.3g} triangles on the "
            f"surface's {area:.3g} m^2 (it encloses {volume:.3g} m^3: walls "
            f"{2 * volume / area:.2g} m thick); expected at most {MAX_TETS:.0e} (give a larger edge length)"
        )
    key = hashlib.sha256(
        V.tobytes() + F.tobytes() + repr((el, epsilon, optimize, keep_all, 3)).encode()
    ).hexdigest()[:24]
    path = cache_dir() / f"tet-{key}.npz"
    if cache and path.exists():
        with np.load(path) as d:
            return d["nodes"], d["tets"]
    # fTetWild's tolerances are absolute in places: it returned no tets for a surface 1e30 across and
    # crashed on one 1e-9 across. It meshes the surface scaled by a power of two (exact both ways) to
    # a diagonal of about 1; its edge length and envelope are relative to the diagonal. In a child
    # process (ftetwild.py): a crash there is a MeshError, not the end of the caller's.
    scale = unit_scale(V)
    el = min(el, EDGE_CAP * diag)  # (after the cache key: the same request, the same entry)
    nodes, tets = ftetwild.run(V * scale, F, el / diag, epsilon, optimize, threads)
    nodes = np.asarray(nodes, float) / scale
    tets = np.asarray(tets, np.int64)
    if len(tets) == 0:
        raise MeshError(
            "tetrahedralize: fTetWild produced no tetrahedra (is the surface closed and of non-zero volume?)"
        )
    tets = orient_positive(nodes, tets)
    # Drop unused nodes and (near-)zero-volume slivers.
    tets = tets[tet_volumes(nodes, tets) > 1e-9 * el**3]
    tets = largest_component(tets, keep_all)
    nodes, tets, _ = drop_unused(nodes, tets)
    if cache:
        tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp.npz")
        np.savez(tmp, nodes=nodes, tets=tets)
        os.replace(tmp, path)
    return nodes, tets
