"""Model (static, built once), in the user's node and element numbering (its State: state.py).

Internally the engine stores nodes and elements in its own cache-friendly order (elements grouped
by material and sorted along a Morton curve, nodes numbered by first use); the Model maps every
array back, so users never see that order.
"""

from __future__ import annotations

import hashlib
import math
import warnings
from typing import TYPE_CHECKING

import numpy as np

from .. import _core
from ..checks import shown
from ..contact.soft import engine_surface, no_surface, sheets_apart
from ..errors import InputError, MaterialError, MeshError, PliantWarning
from .curves import Constant, LoadCurve
from .anp import anp_stabilization
from ..mesh.primitives import triangle_measures
from .smoothing import strain_smoothing
from .geometry import node_sizes

if TYPE_CHECKING:
    from .state import State

__all__ = ["Model"]


def _held_sum(held: np.ndarray, ids: np.ndarray, dofs: str) -> np.ndarray:
    """Σ over the nodes ``ids`` of f − r [N] (N, 3), the components outside ``dofs`` zeroed."""
    return held[ids].sum(axis=0) * np.array([d in dofs for d in "xyz"], dtype=float)


def _lumped_mass(n_nodes: int, T: np.ndarray, volume: np.ndarray, density: np.ndarray) -> np.ndarray:
    """Lumped nodal masses [kg] (n_nodes,): a quarter of each element's ρ V0 to each of its nodes
    (T (M, 4), V0 (M,) [m³] as the engine computed them (tet_geometry), density (M,) [kg/m³])."""
    return np.bincount(T.ravel(), np.repeat(density * volume / 4.0, 4), minlength=n_nodes)


def _membrane_mass(n_nodes: int, X: np.ndarray, F: np.ndarray, materials: list) -> np.ndarray:
    """Lumped nodal masses [kg] (n_nodes,) of membrane triangles F (K, 3) over positions X [m]: a
    third of each one's ρ h A0 to each corner, as the engine's (materials: one per triangle)."""
    if not len(F):
        return np.zeros(n_nodes)
    area = triangle_measures(X, F)[0]
    rho_h = np.array([m.density * m.thickness for m in materials])
    return np.bincount(F.ravel(), np.repeat(rho_h * area / 3.0, 3), minlength=n_nodes)


def _bending_input(
    builder, mem_F: np.ndarray, mem_mat: list, held: np.ndarray, node_rank: np.ndarray
) -> dict:
    """The engine's bending input (ModelInput::mem_nbrs, mem_bend) where any membrane bends: the
    nodes across each membrane's edges (engine numbering; a boundary edge is clamped whose nodes
    add_membrane's ``clamped`` lists, or by default are held in all three directions) and each
    membrane's E_b, ν_b."""
    if not any(m.bends for m in mem_mat):
        return {}
    from .patches import across_edges, clamp_edges, patch_nodes

    nbrs = across_edges(mem_F)
    start = 0
    for (F, _), clamped in zip(builder._membranes, builder._membrane_clamps):
        mask: np.ndarray = np.asarray(held.all(axis=1))
        if clamped is not None:
            mask = np.zeros(held.shape[0], bool)
            mask[clamped] = True
        clamp_edges(nbrs[start : start + len(F)], F, mask)
        start += len(F)
    nbrs = patch_nodes(mem_F, nbrs)
    ranked = np.where(nbrs >= 0, node_rank[np.maximum(nbrs, 0)], nbrs)
    return {
        "mem_nbrs": [int(v) for v in ranked.ravel()],
        "mem_bend": [v for m in mem_mat for v in (m.bending_E, m.bending_nu)],
    }


def _membrane_altitudes(X: np.ndarray, F: np.ndarray) -> np.ndarray:
    """Smallest altitude [m] of each membrane triangle F (K, 3) over positions X: 2 A / longest edge."""
    area, longest = triangle_measures(X, F)
    return 2 * area / longest


def _morton_order(points: np.ndarray) -> np.ndarray:
    """Permutation sorting points (n, 3) along a 3-D Morton (Z-order) curve, 10 bits per axis."""
    if not len(points):
        return np.zeros(0, np.int64)
    lo, hi = points.min(axis=0), points.max(axis=0)
    q = ((points - lo) / np.maximum(hi - lo, 1e-300) * 1023).astype(np.uint64)
    code = np.zeros(len(points), dtype=np.uint64)
    for bit in range(10):
        for d in range(3):
            code |= ((q[:, d] >> np.uint64(bit)) & np.uint64(1)) << np.uint64(3 * bit + d)
    return np.argsort(code, kind="stable")


def _check_threads(threads) -> None:
    """None (automatic) or an integer from 1 to the engine's limit (4 per processor, at least 64;
    far more threads than processors make OpenMP fail)."""
    if threads is None:
        return
    limit = int(_core.thread_limit())
    if isinstance(threads, bool) or not isinstance(threads, (int, np.integer)) or not 1 <= threads <= limit:
        raise InputError(
            f"threads = {shown(threads)}; expected an integer from 1 to {limit} on this "
            "machine, or None for automatic"
        )


def _fingerprint(X, T, sets, dtype, constraints) -> str:
    """A short hash of what makes a state meaningful for a model: mesh, materials, densities,
    element sets, constrained DOFs and precision (saved states carry it)."""
    h = hashlib.sha256()
    h.update(np.ascontiguousarray(X, float).tobytes())
    h.update(np.ascontiguousarray(T, np.int64).tobytes())
    for s in sets:
        h.update(repr((type(s.material).__name__, s.material.params, s.density)).encode())
        h.update(np.ascontiguousarray(s.elements, np.int64).tobytes())
    h.update(repr((str(np.dtype(dtype)), sorted(map(tuple, constraints)))).encode())
    return h.hexdigest()[:16]


SLOW_ELEMENT_FACTOR = 20.0  # warn when one element makes a run this many times longer


def _warn_slow_element(source: str, dt: np.ndarray, altitude: np.ndarray) -> None:
    """Warn when the worst element's stable step (the engine's h_min / c_d per element, ``dt`` [s],
    user order) is SLOW_ELEMENT_FACTOR or more times below the median element's: that one element
    multiplies the steps of every run (a sliver from a mesher, a node jittered almost onto a face).
    ``altitude``: smallest altitude per element [m], for the message."""
    if not dt.size:  # membranes alone
        return
    worst = int(np.argmin(dt))
    if not dt[worst] > 0:  # degenerate elements are refused before (finalize)
        return
    factor = float(np.median(dt) / dt[worst])
    if factor >= SLOW_ELEMENT_FACTOR:
        warnings.warn(
            PliantWarning(
                f"{source}: element {worst} limits the stable time step estimate to {dt[worst]:.3g} s, "
                f"{factor:.0f}x below the median element's {np.median(dt):.3g} s (smallest altitude "
                f"{altitude[worst]:.3g} m): a run at the default step takes {factor:.0f}x the steps a "
                "uniform mesh would. The mesh's own stable step 2/ω_max counts the mass its nodes share "
                "with their neighbours and can be far larger: a dt given up to it runs (it is checked; "
                "Model.stable_step() computes it); or check the mesh (pliant mesh quality)"
            ),
            stacklevel=4,
        )


def _check_wave_speeds(source: str, dt: np.ndarray, sets: list, owner: np.ndarray) -> None:
    """Refuse a model whose element stable steps (smallest altitude / dilatational wave speed
    √((λ + 2μ)/ρ), ``dt`` [s] per element, user order) are not finite and positive: moduli and a
    density that each pass as positive numbers can still make the wave speed overflow (a density of
    5e-324 kg/m³) or vanish, and the run would then divide by the zero step. Names the first such
    element, its set and density."""
    bad = np.flatnonzero(~(np.isfinite(dt) & (dt > 0)))
    if bad.size == 0:
        return
    e = int(bad[0])
    s = sets[int(owner[e])]
    speed = "infinite" if dt[e] == 0 else "zero" if np.isinf(dt[e]) else "not a number"
    raise MaterialError(
        f"{source}: element {e} of set {s.name!r} ({type(s.material).__name__}, density {s.density:.3g} "
        f"kg/m^3): its dilatational wave speed, sqrt((lambda + 2 mu) / density), is {speed}, so no time "
        "step is stable; expected moduli [Pa] and a density [kg/m^3] of physical size"
    )


def _check_tool_starts(source: str, tools, X, size, reach: list, skin) -> None:
    """A rigid tool must not start deep in what it touches: a node inside it by more than half its
    elements' smallest altitude ``size`` [m] (N,) would be pushed out across them in the first step
    and invert them (an InputError naming the tool and node)."""
    from ..contact.tools import deepest_start

    worst = deepest_start(tools, X, reach, size, skin)
    if worst is not None:
        k, node, depth = worst
        raise InputError(
            f"{source}: tool {k} ({tools[k].name!r}) starts with node {node} {depth:.3g} m inside it, more "
            f"than half its elements' smallest altitude ({size[node]:.3g} m): the first step would push it "
            "out across them; expected the tool outside the body at t = 0 (keyframes can bring it in)"
        )


def _check_initial_overlap(
    source: str,
    X: np.ndarray,
    T: np.ndarray,
    labels: np.ndarray,
    pairs,
    contact,
    sheets=(None, None),
    sheet_faces=None,
) -> None:
    """Soft contact needs the bodies it pairs to start apart or touching: a node that starts inside
    another body deeper than the contact band is never pushed out (an InputError), a shallower
    one is pushed out in the first step, a jolt (a PliantWarning); a node on a sheet's mid-surface
    is on neither side of it (an InputError). ``sheets``: the nodes of sheets of membranes and
    their bodies; ``sheet_faces``: their triangles and each one's body."""
    from ..contact.soft import initial_overlap, on_a_sheet

    o = initial_overlap(X, T, labels, pairs, *sheets)
    where = o and (
        f"{source}: soft contact: node {o['node']} of {contact.name(o['body'])} starts {o['depth']:.3g} m "
        f"inside {contact.name(o['other'])}"
    )
    if o and o["depth"] > o["band"]:
        raise InputError(
            f"{where}, deeper than the contact band there ({o['band']:.3g} m: {_core.soft_band:g} x the "
            "nearest triangle's mean edge), so contact would never push it out; expected the bodies apart or "
            "touching at the start (move them apart)"
        )
    s = on_a_sheet(X, T, labels, pairs, sheets[0], sheets[1], sheet_faces)
    if s is not None:
        raise InputError(
            f"{source}: soft contact: node {s['node']} of {contact.name(s['body'])} starts on the "
            f"mid-surface of {contact.name(s['sheet'])} ({s['distance']:.3g} m from it), on neither of "
            "its sides, and contact keeps a node on the side it starts on; expected the bodies apart "
            "(move one to the side of the sheet it should be on)"
        )
    if o is None:
        return
    warnings.warn(
        PliantWarning(f"{where}: contact pushes it out in the first step, a jolt; start the bodies apart"),
        stacklevel=4,
    )


def _prony_row(prony) -> list[float]:
    """One group's Prony terms in the engine's layout (materials.hpp, Prony): n_iso, n_vol, then
    (α, τ) pairs, isochoric at 0.., volumetric at prony_max/2.."""
    iso, vol = prony or ((), ())
    half = _core.prony_max // 2
    row = [float(len(iso)), float(len(vol))] + [0.0] * (2 * _core.prony_max)
    for start, terms in ((0, iso), (half, vol)):
        for i, (a, tau) in enumerate(terms):
            row[2 + 2 * (start + i)], row[3 + 2 * (start + i)] = a, tau
    return row


def _damped_critical_step(dt0: float, beta: float) -> float:
    """The critical step of central differences with stiffness-proportional damping β [s]:
    Δt = (2/ω_max)(√(1 + ξ²) − ξ), ξ = β ω_max / 2 (Belytschko, Liu & Moran 2000, eq. 6.3.18),
    with ω_max = 2/Δt0 from the undamped critical step Δt0 = min h/c [s]."""
    xi = beta / dt0
    return dt0 * (math.sqrt(1.0 + xi * xi) - xi)


def _auto_threads(n_elements: int) -> int:
    """Threads for a model: all cores, but one per ~1,000 elements at most: every step has
    barriers (two to four) that cost a few microseconds each, more than a tiny model's work."""
    return max(1, min(_core.max_threads(), n_elements // 1000))


#: The backends a model can run on (bound from the engine).
BACKENDS: tuple[str, ...] = tuple(_core.backends)


def check_backend(backend) -> str:
    """``backend`` if it names a backend, else InputError saying which exist."""
    if not isinstance(backend, str) or backend not in BACKENDS:
        raise InputError(f"backend = {shown(backend)}; expected one of {', '.join(BACKENDS)}")
    return backend


class Model:
    """Static part of a simulation: mesh, materials, masses, constraints, loads (build it with
    :class:`~pliant.tled.builder.ModelBuilder`).

    Attributes: ``n_nodes``, ``n_elements``, ``dtype``, ``damping`` α [1/s],
    ``stiffness_damping`` β [s], ``dt_critical`` [s] (smallest h_min/c_d over elements and
    membranes, reduced for β by the factor √(1 + ξ²) − ξ, ξ = β/(h_min/c_d)), ``dt_critical_element``
    (user element index; −1 without tets), ``dt_critical_membrane`` (the membrane that sets it, or
    −1), ``n_membranes`` and ``membrane_faces`` (K, 3),
    ``reference_positions`` [m] (N, 3), ``tets`` (M, 4), ``mass`` [kg] (N,), ``nodal_pressure``
    (T4ANP on) and ``nodal_pressure_stabilization`` (as the builder had it); with soft contact,
    ``bodies`` (body of each element, (M,); else None) and ``contact_pairs`` (the pairs of bodies
    (a, b), a <= b, in the order of ``ContactReport.pairs``).
    """

    def __init__(
        self,
        builder,
        owner: np.ndarray,
        dtype: np.dtype,
        threads: int | None,
        geometry: tuple[np.ndarray, np.ndarray],
    ):
        X, T = builder.nodes, builder.tets
        _check_threads(threads)
        self.reference_positions = X.copy()
        self.tets = T.copy()
        self.dtype = dtype
        self.damping = float(builder.damping)
        self.stiffness_damping = float(builder.stiffness_damping)
        self.nodal_pressure = bool(builder.nodal_pressure)
        self.nodal_pressure_stabilization = builder.nodal_pressure_stabilization
        self.sets = list(builder.sets)
        self._builder = builder.snapshot()  # what rebuilds the model (rebuilt; pliant.cutting)
        N, M = X.shape[0], T.shape[0]

        # Element order: by element set, then along a Morton curve of the centroids.
        centroids = X[T].mean(axis=1)
        morton = _morton_order(centroids)
        rank = np.empty(M, dtype=np.int64)
        rank[morton] = np.arange(M)
        elem_order = np.lexsort((rank, owner))  # engine element i is user element elem_order[i]
        group_end = np.cumsum(np.bincount(owner[elem_order], minlength=len(self.sets)))
        keep = np.diff(np.concatenate([[0], group_end])) > 0
        # Node order: first use in element order, then in membrane order; orphan nodes last.
        mem_F = builder.membrane_faces()
        mem_mat = [m for F, m in builder._membranes for _ in range(len(F))]
        flat = np.concatenate([T[elem_order].ravel(), mem_F.ravel()])
        _, first = np.unique(flat, return_index=True)
        used = flat[np.sort(first)]
        orphans = np.setdiff1d(np.arange(N), used)
        if orphans.size:
            warnings.warn(
                PliantWarning(
                    f"{builder.source}: {orphans.size} node(s) belong to no element (first: "
                    f"{int(orphans[0])}); they carry no mass and never move unless prescribed"
                ),
                stacklevel=3,
            )
        node_order = np.concatenate([used, orphans])  # engine node i is user node node_order[i]
        node_rank = np.empty(N, dtype=np.int64)
        node_rank[node_order] = np.arange(N)
        self._node_order, self._node_rank, self._elem_order = node_order, node_rank, elem_order

        # Curves (deduplicated), load patterns per curve, constraints.
        curves: list[LoadCurve] = [Constant()]

        def cid(c: LoadCurve) -> int:
            if c not in curves:
                curves.append(c)
            return curves.index(c)

        pattern_of: dict[int, np.ndarray] = {}
        for ids, f, c in builder._forces:
            k = cid(c)
            R = pattern_of.setdefault(k, np.zeros((N, 3)))
            np.add.at(R, node_rank[ids], f)
        if builder._node_gravity:  # add_gravity: m_a g on its nodes, m_a = Σ ρ V0 / 4 as the engine's
            m_a = _lumped_mass(
                N, T, np.asarray(geometry[0], float), np.array([s.density for s in self.sets])[owner]
            ) + _membrane_mass(N, X, mem_F, mem_mat)
            for ids, g, c in builder._node_gravity:
                R = pattern_of.setdefault(cid(c), np.zeros((N, 3)))
                np.add.at(R, node_rank[ids], m_a[ids, None] * g)
        pattern_curve = sorted(pattern_of)
        # Loaded faces: follower pressures (p, no traction), then tractions (t, no pressure).
        loaded = [(F, p, np.zeros((len(F), 3)), c) for F, p, c in builder._pressures] + [
            (F, np.zeros(len(F)), t, c) for F, t, c in builder._tractions
        ]
        press_F = np.concatenate([F for F, *_ in loaded]) if loaded else np.zeros((0, 3), np.int64)
        press_p = np.concatenate([p for _, p, _, _ in loaded]) if loaded else np.zeros(0)
        press_t = np.concatenate([t for _, _, t, _ in loaded]) if loaded else np.zeros((0, 3))
        press_c = [cid(c) for F, _, _, c in loaded for _ in range(len(F))]
        patterns = np.stack([pattern_of[k] for k in pattern_curve]) if pattern_curve else np.zeros((0, N, 3))
        cons = sorted(builder._cons.items())
        self._cons_user = [(n, d) for (n, d), _ in cons]
        self._altitudes = np.asarray(geometry[1], float)  # smallest altitude [m] per element, user order
        mem_alt = _membrane_altitudes(X, mem_F)
        held = np.zeros((X.shape[0], 3), dtype=bool)  # DOFs a constraint holds (user numbering)
        if cons:
            held[tuple(np.array(self._cons_user).T)] = True
        g, gcurve = (builder._gravity[0], cid(builder._gravity[1])) if builder._gravity else (np.zeros(3), -1)
        cons_curve = [cid(c) for _, (v, c) in cons]  # register every curve before the tables
        self.curves = curves
        tb: list[int] = []
        tc: list[int] = []
        tt: list[float] = []
        tv: list[float] = []
        for c in curves:
            tb.append(len(tt))
            tc.append(len(c.times))
            tt.extend(c.times)
            tv.extend(c.values)

        density = np.array([s.density for s in self.sets])[owner[elem_order]]
        # Contact: boundary nodes with at least one free DOF, if there are tools (the kernel moves
        # only the free DOFs: symmetry planes and rollers keep their constraint).
        self.tools = list(builder.tools)
        if self.tools:
            from ..mesh.topology import boundary_nodes

            n_cons = np.bincount(np.array([n for n, _ in self._cons_user], np.int64), minlength=X.shape[0])
            surface = np.union1d(boundary_nodes(T), mem_F.ravel())  # membranes' nodes meet tools too
            restricted = [s for s in builder.tool_nodes if s is not None]
            cand = np.unique(np.concatenate([surface, *restricted])).astype(np.int64)
            cn = cand[n_cons[cand] < 3]
            # Tool mask per contact node: bit k if tool k may touch it (surface nodes for tools
            # without a node set, the node set otherwise).
            on_surface = np.isin(cn, surface)
            masks = np.zeros(cn.size, np.int64)
            for bit, s in enumerate(builder.tool_nodes[: _core.masked_tools]):
                masks |= (on_surface if s is None else np.isin(cn, s)).astype(np.int64) << bit
        else:
            cn, masks = np.zeros(0, np.int64), np.zeros(0, np.int64)
        self.contact_nodes = cn
        cn_order = np.argsort(node_rank[cn], kind="stable")
        # The sheets apart from the tets (bodies of their own in soft contact) and their thicknesses;
        # such a sheet meets a tool with its face, half its thickness from its nodes.
        apart = sheets_apart(mem_F, T, X.shape[0])[0] if len(mem_F) else np.zeros(0, np.int64)
        apart_h = np.array([mem_mat[k].thickness for k in apart])
        skin = np.zeros(X.shape[0])
        np.maximum.at(skin, mem_F[apart].ravel(), np.repeat(apart_h / 2, 3))
        if self.tools:
            reach = [cn[np.isin(cn, surface if s is None else s)] for s in builder.tool_nodes]
            size = node_sizes(N, T, self._altitudes, mem_F, mem_alt)
            _check_tool_starts(builder.source, self.tools, X, size, reach, skin)
        self._contact_engine = cn[cn_order]  # user node of each engine contact node (grasp state)
        tool_grids = [t.grid() for t in self.tools]
        soft = dict(no_surface(), pairs=[], labels=None)
        if builder.soft_contact is not None:
            soft = engine_surface(builder.soft_contact, X, T, node_rank, held, (mem_F[apart], apart_h))
        self.contact_pairs = soft.pop("pairs")  # soft-contact pairs of bodies (a <= b), index order
        self.bodies = soft.pop("labels")  # body of each element (user order), or None
        sheets = soft.pop("sheet_nodes", None), soft.pop("sheet_labels", None)  # bodies after the tets'
        sheet_faces = soft.pop("sheet_faces", None)
        if self.contact_pairs:
            _check_initial_overlap(
                builder.source,
                X,
                T,
                self.bodies,
                self.contact_pairs,
                builder.soft_contact,
                sheets,
                sheet_faces,
            )
        visco = []  # per group: n_iso, n_vol, (α, τ) × prony_max (isochoric first half)
        if any(getattr(self.sets[k].material, "prony", None) for k in np.nonzero(keep)[0]):
            for grp in np.nonzero(keep)[0]:
                visco.extend(_prony_row(getattr(self.sets[grp].material, "prony", None)))
        n_par = _core.material_params
        params = [
            p for k in np.nonzero(keep)[0] for p in (*self.sets[k].material.params, *([0.0] * n_par))[:n_par]
        ]
        Engine = _core.EngineF32 if dtype == np.float32 else _core.EngineF64
        gamma, shear = anp_stabilization(builder.nodal_pressure_stabilization)
        try:
            self._engine = Engine(
                X=np.ascontiguousarray(X[node_order]),
                tets=np.ascontiguousarray(node_rank[T[elem_order]].astype(np.int32)),
                density=np.ascontiguousarray(density),
                group_end=[int(e) for e in group_end[keep]],
                group_kind=[int(self.sets[k].material.kind) for k in np.nonzero(keep)[0]],
                group_params=params,
                patterns=np.ascontiguousarray(patterns, dtype=float),
                pattern_curve=pattern_curve,
                cons_node=[int(node_rank[n]) for (n, d), _ in cons],
                cons_dim=[d for (n, d), _ in cons],
                cons_value=[v for _, (v, c) in cons],
                cons_curve=cons_curve,
                curve_kind=[int(c.kind) for c in curves],
                curve_t0=[c.t0 for c in curves],
                curve_t1=[c.t1 for c in curves],
                curve_table_begin=tb,
                curve_table_count=tc,
                table_t=tt,
                table_v=tv,
                gravity=[float(x) for x in g],
                gravity_curve=gcurve,
                # engine order: sequential access
                contact_nodes=[int(node_rank[n]) for n in cn[cn_order]],
                contact_skin=skin[cn[cn_order]].tolist(),
                contact_masks=[int(m) for m in masks[cn_order]],
                tool_kind=[int(t.kind) for t in self.tools],
                tool_params=[p for t in self.tools for p in t.params()],
                tool_mu=[m for t in self.tools for m in (t.mu_s, t.mu_k)],
                tool_keys=[t.key_array().tolist() for t in self.tools],
                tool_grid_dims=[d for dims, _ in tool_grids for d in dims],
                tool_grids=[v.tolist() for _, v in tool_grids],
                press_nodes=[int(v) for v in node_rank[press_F].ravel()],
                press_value=press_p.tolist(),
                press_curve=press_c,
                press_traction=press_t.ravel().tolist(),
                anp=bool(builder.nodal_pressure),
                group_visco=visco,
                stiffness_damping=self.stiffness_damping,
                anp_stabilization=gamma,
                anp_shear_stabilization=shear,
                tool_grips=[list(t.grips) for t in self.tools],
                tool_reach=[float(t.reach) for t in self.tools],
                **soft,
                smoothing=strain_smoothing(builder.strain_smoothing),
                mem_nodes=[int(v) for v in node_rank[mem_F].ravel()],
                mem_kind=[int(m.kind) for m in mem_mat],
                mem_params=[
                    v for m in mem_mat for v in (m.thickness, m.density, *m.params, float(m.wrinkling))
                ],
                **_bending_input(builder, mem_F, mem_mat, held, node_rank),
                threads=int(threads if threads else _auto_threads(M)),
            )
        except ValueError as e:  # the engine's own checks, in words a user can act on
            raise MeshError(f"{builder.source}: {e}") from None
        self.n_nodes, self.n_elements = N, M
        self.fingerprint = _fingerprint(X, T, self.sets, dtype, self._cons_user)
        self._results_backend = None  # made on first use (element_results, internal_forces)
        self._backend, self._device = "cpu", 0  # the default backend of its solvers
        self._solver = None  # weak reference: the last solver that ran
        steps = self.to_user_elements(np.asarray(self._engine.critical_steps()))
        _check_wave_speeds(builder.source, steps, self.sets, owner)
        self.dt_critical = _damped_critical_step(float(self._engine.dt_critical), self.stiffness_damping)
        self._stable_step: float | None = None  # 2/ω_max with β, when a solver first needs it
        self._volumes = np.asarray(geometry[0], float)  # V0 [m³] per element, user order
        # smallest element (or membrane) altitude [m]
        self.min_altitude = float(np.min(np.concatenate([self._altitudes, mem_alt])))
        limit = int(self._engine.dt_critical_element)  # −1: no tets (membranes alone)
        self.dt_critical_element = int(elem_order[limit]) if limit >= 0 else -1
        # The membrane (add order) whose own step is dt_critical's, or −1 where an element's is.
        self.dt_critical_membrane = int(self._engine.dt_critical_membrane)
        self.n_membranes = len(mem_mat)
        self.membrane_faces = mem_F.copy()  # (K, 3) user node ids, in add_membrane's order
        _warn_slow_element(builder.source, steps, np.asarray(geometry[1], float))
        self.mass = self.to_user_nodes(self._engine.mass().astype(float))
        self.last_load_time = max(c.end_time for c in curves)
        self.constrained = held

    @property
    def dt_critical_limiter(self) -> str:
        """What sets dt_critical: "element E" or "membrane K" (user numbering, membranes in the order
        add_membrane took them)."""
        if self.dt_critical_membrane >= 0:
            return f"membrane {self.dt_critical_membrane}"
        return f"element {self.dt_critical_element}"

    def stable_step(self) -> float:
        """The mesh's own stable step 2/ω_max [s] about the reference state, β included (Lanczos on
        M⁻¹K; a float32 model's forces are too noisy for it, so on a float64 copy; computed once).
        Membranes that wrinkle count as taut: about the flat reference state a compressive
        perturbation meets no stiffness, so differences there would halve the stiffness that a
        stretched sheet has."""
        if self._stable_step is None:
            from ..cutting.stability import stable_step, taut

            exact = taut(self, "float64")  # (stable_step's own taut() is then the model itself)
            self._stable_step = stable_step(exact, exact.state())
        return self._stable_step

    def rebuilt(self, dtype: str, taut: bool = False) -> "Model":
        """This model built again from its builder at ``dtype`` ("float32" or "float64"), on as many
        threads (its warnings were given when it was first built); ``taut``: its membranes carry
        compression (none wrinkles)."""
        b = self._builder
        if taut:
            b = b.snapshot()
            b._membranes = [(F, m.taut()) for F, m in b._membranes]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return b.finalize(dtype, threads=self.threads)

    # --- numbering ----------------------------------------------------------------------------
    def to_user_nodes(self, a: np.ndarray) -> np.ndarray:
        out = np.empty_like(a)
        out[self._node_order] = a
        return out

    def to_engine_nodes(self, a: np.ndarray) -> np.ndarray:
        return np.ascontiguousarray(a[self._node_order])

    def to_user_elements(self, a: np.ndarray) -> np.ndarray:
        out = np.empty_like(a)
        out[self._elem_order] = a
        return out

    def user_node(self, engine_node: int) -> int:
        return int(self._node_order[engine_node])

    def user_element(self, engine_element: int) -> int:
        return int(self._elem_order[engine_element])

    @property
    def threads(self) -> int:
        return int(self._engine.threads)

    @property
    def memory_bytes(self) -> int:
        """Engine memory for the model's arrays [bytes] (states and scratch not included)."""
        return int(self._engine.bytes)

    # --- backends, states and results -----------------------------------------------------------
    @property
    def backend(self) -> str:
        """The backend a Solver of this model uses unless told otherwise: "cpu", "cuda" or
        "cuda-emulated" (``finalize(backend=...)``)."""
        return self._backend

    @property
    def device(self) -> int:
        """The CUDA device a Solver of this model uses unless told otherwise."""
        return self._device

    def make_backend(self, backend: str | None = None, device: int | None = None):
        """A new engine backend stepping this model (what a Solver owns): ``backend`` one of
        :data:`BACKENDS` (default :attr:`backend`). Raises BackendError if this build has no CUDA
        backend or the machine no such GPU."""
        from ..errors import BackendError

        name = check_backend(self._backend if backend is None else backend)
        dev = self._device if device is None else int(device)
        try:
            return self._engine.make_backend(name, dev, self.threads)
        except ValueError as e:
            raise BackendError(f"backend {name!r}: {e}") from None

    def use_backend(self, backend: str, device: int = 0):
        """Deprecated: the Solver owns its backend (``Solver(model, backend=...)``, or
        ``finalize(backend=...)`` for every solver of the model). Sets the default."""
        warnings.warn(
            "Model.use_backend() is deprecated; pass backend= to Solver or finalize()",
            DeprecationWarning,
            stacklevel=2,
        )
        self._set_default_backend(backend, device)

    def _set_default_backend(self, backend: str, device: int = 0):
        if check_backend(backend) != "cpu":
            self.make_backend(backend, device)  # refuses an unusable one now, by name
        self._backend, self._device = backend, int(device)

    def use_cuda(self, device: int = 0):
        """Deprecated: ``Solver(model, backend="cuda", device=d)``."""
        warnings.warn(
            "Model.use_cuda(d) is deprecated; use Solver(model, backend='cuda', device=d)",
            DeprecationWarning,
            stacklevel=2,
        )
        self._set_default_backend("cuda", device)

    def _results(self):
        """The host (CPU) backend that computes results of any state, made on first use: a model
        that is only stepped on a GPU, or never asked for stresses, allocates none."""
        if self._results_backend is None:
            self._results_backend = self._engine.make_backend("cpu", 0, 0)
        return self._results_backend

    def _last_solver(self, what: str):
        warnings.warn(
            f"Model.{what} is deprecated; use Solver.contact_report() (one report of tool "
            "forces and contact)",
            DeprecationWarning,
            stacklevel=3,
        )
        solver = self._solver() if self._solver else None
        if solver is None:
            raise InputError(f"Model.{what}: no solver has run this model")
        return solver

    def set_tool_keys(self):
        """Deprecated: ``Solver.set_tool_keys()`` (tool trajectories belong to the solver)."""
        solver = self._last_solver("set_tool_keys()")
        for mine, theirs in zip(self.tools, solver.tools):
            theirs.keys, theirs._fixed = list(mine.keys), mine._fixed
        solver.set_tool_keys()

    def tool_history(self) -> np.ndarray:
        """Deprecated: ``Solver.contact_report().tools``."""
        return np.asarray(self._last_solver("tool_history()")._backend.tool_history())

    def contact_forces(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Deprecated: ``Solver.contact_report()`` (nodes, node_tool, node_force)."""
        r = self._last_solver("contact_forces()").contact_report()
        return r.nodes, r.node_tool, r.node_force

    def state(self) -> State:
        """A new state at rest, t = 0, zero displacement."""
        from .state import State

        return State(self, self._engine.new_state())

    def element_results(self, state: "State") -> dict[str, np.ndarray]:
        """Per element (user order): ``J``; ``energy_density`` W [Pa]; ``pk2`` S, ``cauchy`` σ [Pa] and
        ``green_strain`` E, each (M, 6) as xx, yy, zz, xy, yz, xz; ``von_mises`` [Pa] (M,)."""
        J, W, S, sig, E = self._results().measures(state._s)
        out = {
            k: self.to_user_elements(np.asarray(v, dtype=float))
            for k, v in dict(J=J, energy_density=W, pk2=S, cauchy=sig, green_strain=E).items()
        }
        s = out["cauchy"]
        out["von_mises"] = np.sqrt(
            0.5 * ((s[:, 0] - s[:, 1]) ** 2 + (s[:, 1] - s[:, 2]) ** 2 + (s[:, 2] - s[:, 0]) ** 2)
            + 3.0 * (s[:, 3] ** 2 + s[:, 4] ** 2 + s[:, 5] ** 2)
        )
        return out

    def membrane_results(self, state: "State") -> dict[str, np.ndarray]:
        """Per membrane (add_membrane's order): ``area_ratio`` A/A0 (K,); ``tension``, the Cauchy
        stress resultant [N/m] (K, 6) as xx, yy, zz, xy, yz, xz (the force per current length of a
        cut through the membrane, in its plane); ``max_tension`` [N/m] (K,), its larger in-plane
        principal value (negative: compressed both ways); ``energy``, its strain energy A0 h W [J]
        (K,) (cpp/include/pliant/membrane.hpp, membrane_measures)."""
        r = np.asarray(self._results().membrane_measures(state._s), dtype=float)
        t = r[:, 1:7]
        # t has the membrane's normal as a null vector: its in-plane principal values are the roots of
        # λ² − tr λ + I2 (I2 the sum of its principal 2 × 2 minors).
        tr = t[:, 0] + t[:, 1] + t[:, 2]
        i2 = t[:, 0] * t[:, 1] + t[:, 1] * t[:, 2] + t[:, 2] * t[:, 0] - (t[:, 3:] ** 2).sum(axis=1)
        top = 0.5 * tr + np.sqrt(np.maximum(0.25 * tr**2 - i2, 0.0))
        return {"area_ratio": r[:, 0], "tension": t, "max_tension": top, "energy": r[:, 7]}

    def element_volumes(self) -> np.ndarray:
        """Reference volume V0 [m³] per element (M,)."""
        return self._volumes.copy()

    def internal_forces(self, state: "State") -> np.ndarray:
        """Internal nodal forces f(u) [N], (N, 3), the forces the elements need at the nodes: at the
        constrained DOFs of an equilibrium state, less the loads applied there, the forces the
        supports exert on the body (a bar hanging under gravity: its weight, upward, at the top)."""
        return self._internal_forces(state, damped=False)

    def _internal_forces(self, state: "State", damped: bool) -> np.ndarray:
        """internal_forces, with ``damped`` plus β damping's viscous forces from the state's own
        increment and step (the engine's internal_forces(state, damped))."""
        return self.to_user_nodes(np.asarray(self._results().internal_forces(state._s, damped), dtype=float))

    def external_forces(self, state: "State", t: float | None = None) -> np.ndarray:
        """External loads [N], (N, 3), at the state's displacements and the load curves at ``t`` [s]
        (default: the state's time): load patterns (point forces, gravity m g), follower pressure
        and surface traction on the current faces; contact forces are not loads here. The engine's
        own per-node loads (applied_loads, tled.hpp), those the step drives the nodes with."""
        when = state.time if t is None else float(t)
        return self.to_user_nodes(np.asarray(self._results().external_forces(state._s, when), dtype=float))

    def reactions(self, state: "State", nodes, dofs: str = "xyz", t: float | None = None) -> np.ndarray:
        """Total force [N], (3,), the supports exert on the body at ``nodes`` (user node ids) along
        ``dofs`` (the others 0): Σ (f − r) over them, internal forces less the external loads (a
        bar hanging under gravity: its weight, upward, at its fixed top), plus, on the DOFs a
        prescribed displacement moves, their own inertia and mass damping (``_moved_inertia``:
        after a dynamic run), plus the stiffness-proportional damping's viscous forces at the
        state's last increment (docs/scenes.md, "Reactions")."""
        return _held_sum(self._held_forces(state, t), np.asarray(nodes, dtype=np.int64).reshape(-1), dofs)

    def _held_forces(self, state: "State", t: float | None) -> np.ndarray:
        """What the step drives each node with, less its loads [N], (N, 3): f(u) + f_β(u, du/Δt)
        − r(t) + the moved DOFs' m (a + α v) (M a + α M v + f + f_β − r = the support's force).
        f_β: β damping's viscous forces from the state's own increment and step (zero after a
        relaxation, whose increment is zero)."""
        f = self._internal_forces(state, damped=self.stiffness_damping > 0.0)
        return f - self.external_forces(state, t) + self._moved_inertia(state, t)

    def _moved_inertia(self, state: "State", t: float | None = None) -> np.ndarray:
        """m (a + α v) [N] (N, 3) on each DOF a prescribed displacement d c(t) moves, as the last
        solver's central differences drive it at the state's time t: a = d (c(t + Δt) − 2 c(t) +
        c(t − Δt)) / Δt², v = d (c(t + Δt) − c(t − Δt)) / (2 Δt), α its mass damping (the step's
        M a + α M v + f − r = the support's force); zeros where that solver last relaxed (an
        equilibrium: the DOFs hold still) or none has run."""
        out = np.zeros((self.n_nodes, 3))
        solver = self._solver() if self._solver else None
        if solver is None or solver._stepped_dt is None:
            return out
        when = state.time if t is None else float(t)
        dt, alpha = float(solver._stepped_dt), float(solver.damping)
        factor: dict = {}  # each curve's a + α v per unit of displacement, computed once
        for (n, d), (value, curve) in self._builder._cons.items():
            if value == 0.0 or not curve.end_time > when - dt:  # held still since t − Δt
                continue
            if curve not in factor:
                c = curve(np.array([when - dt, when, when + dt]))
                factor[curve] = (c[2] - 2.0 * c[1] + c[0]) / dt**2 + alpha * (c[2] - c[0]) / (2.0 * dt)
            out[n, d] = self.mass[n] * value * factor[curve]
        return out

    def _node_sizes(self) -> np.ndarray:
        """Each node's smallest altitude [m] over its tets and membranes, (N,) (geometry.node_sizes)."""
        X, F = self.reference_positions, self.membrane_faces
        return node_sizes(self.n_nodes, self.tets, self._altitudes, F, _membrane_altitudes(X, F))

    @property
    def membrane_materials(self) -> list:
        """Each membrane set's material, in the order ModelBuilder.add_membrane took them."""
        return [m for _, m in self._builder._membranes]

    @property
    def supports(self) -> list[tuple[str, np.ndarray, str]]:
        """The supports (name, user node ids, DOFs), one per ModelBuilder.fix / prescribe call."""
        return list(self._builder.supports)

    def support_reactions(self, state: "State", t: float | None = None) -> dict[str, np.ndarray]:
        """Each support's reaction [N], (3,), by its name (``reactions`` over its nodes and DOFs):
        internal (with β damping's) less external forces on its held DOFs (plus the inertia of those
        a prescribed displacement moves, after a dynamic run), less the soft-contact force on them at the
        last step of the solver that last ran this model (a body resting on a held surface: the
        support carries it through the contact)."""
        held = self._held_forces(state, t)
        solver = self._solver() if self._solver and self.contact_pairs else None
        if solver is not None:
            report = solver.contact_report()
            np.subtract.at(held, report.soft_nodes, report.soft_force)
        return {name: _held_sum(held, ids, dofs) for name, ids, dofs in self._builder.supports}

    def strain_energy(self, state: "State") -> float:
        """Total strain energy [J]: Σ V0 W of the tets and Σ A0 h W of the membranes."""
        tets = float(np.dot(self.element_volumes(), self.element_results(state)["energy_density"]))
        return tets + (float(self.membrane_results(state)["energy"].sum()) if self.n_membranes else 0.0)

    def kinetic_energy(self, state: "State") -> float:
        """½ Σ m v² [J] with the half-step velocity of the state."""
        v = state.velocities
        return float(0.5 * np.sum(self.mass[:, None] * v * v))
