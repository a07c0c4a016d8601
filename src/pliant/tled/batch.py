"""Batches: many independent bodies stepped together. A :class:`Batch` merges the builders of N
bodies (copies of one body with other parameters, or different bodies) into one model whose nodes
and elements are laid out body after body, so that every launch of the engine steps all of them:
one OpenMP region (or one CUDA graph) per step instead of N, and element kernels that read each
block's material parameters from memory, so that bodies of one material kind with different values
share a single launch (the leading batch dimension of the material parameters).

The bodies do not interact (no contact between them). What a model holds once is shared and must
be the same in every body: damping (α and β), the element formulation (T4ANP or not), gravity and
the rigid tools (each body meets the same tools; a tool's force history is the sum over the
bodies: per-body forces come from :meth:`Batch.tool_forces`). One time step serves all: the
smallest critical step of any body, unless a step is given.

    batch = Batch.replicate(builder, materials=[NeoHookean(E=E, nu=0.45) for E in (2e3, 4e3, 8e3)])
    sim = Simulation(batch.model)
    sim.run(until=0.5)
    u = batch.stack(sim.displacements)      # [m], shape (3, N, 3)
"""

from __future__ import annotations

import copy
import dataclasses

import numpy as np

from ..checks import flag, shown
from ..errors import InputError
from .builder import ModelBuilder
from .anp import anp_stabilization
from .smoothing import strain_smoothing

__all__ = ["Batch", "merge_builders"]


def _same(a, b) -> bool:
    """Equality of builder settings that may hold arrays."""
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return np.array_equal(np.asarray(a), np.asarray(b))
    if isinstance(a, tuple) and isinstance(b, tuple):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    return a == b


def _tool_signature(tool) -> tuple:
    return (
        type(tool).__name__,
        tool.name,
        tool.mu_s,
        tool.mu_k,
        tuple(tool.params()),
        tool.key_array().tobytes(),
    )


def _check_shared(builders: list[ModelBuilder]) -> None:
    """The settings a model holds once are the same in every body; InputError names the first
    body that differs and the setting."""
    first = builders[0]
    shared = {
        "damping": lambda b: float(b.damping),
        "stiffness_damping": lambda b: float(b.stiffness_damping),
        "nodal_pressure (T4ANP)": lambda b: (
            flag(b.nodal_pressure, "nodal_pressure"),
            anp_stabilization(b.nodal_pressure_stabilization),
        ),
        "strain smoothing": lambda b: strain_smoothing(b.strain_smoothing),
        "gravity": lambda b: b._gravity,
        "tools": lambda b: [_tool_signature(t) for t in b.tools],
        "tool node restrictions": lambda b: [s is None for s in b.tool_nodes],
    }
    for k, b in enumerate(builders[1:], start=1):
        for what, get in shared.items():
            if not _same(get(b), get(first)):
                raise InputError(
                    f"batch: body {k} ({b.source}) has another {what} than body 0 "
                    f"({first.source}); a batch shares its {what}: expected the same "
                    "in every body"
                )


def _listed(items, what: str) -> list:
    """``items`` (a list, tuple or other iterable; not a string or a mapping) as a list; InputError
    naming ``what`` otherwise."""
    if isinstance(items, (str, bytes, dict)) or not hasattr(items, "__iter__"):
        raise InputError(f"batch: {what} = {shown(items)}; expected a list, one entry per body")
    return list(items)


def _check_material(m, k: int) -> None:
    """replicate's materials[k]: a Material, or a dict of element-set names to Materials."""
    from ..materials import Material

    if isinstance(m, Material):
        return
    if isinstance(m, dict) and all(isinstance(v, Material) for v in m.values()):
        return
    raise InputError(
        f"batch: materials[{k}] = {shown(m)}; expected a pliant Material (every element set) "
        "or a dict of element-set names to Materials"
    )


def merge_builders(builders: list[ModelBuilder]) -> tuple[ModelBuilder, np.ndarray, np.ndarray]:
    """One builder with every body of ``builders``, body after body. Returns it with the node and
    element offsets of each body, shape (B + 1,) each (body k: nodes off[k]:off[k+1])."""
    if not builders:
        raise InputError("batch: expected at least one body")
    for k, b in enumerate(builders):
        if not isinstance(b, ModelBuilder) or b.n_elements == 0:
            raise InputError(f"batch: body {k} is not a ModelBuilder with a mesh")
    _check_shared(builders)
    out = ModelBuilder()
    first = builders[0]
    out.damping, out.stiffness_damping = first.damping, first.stiffness_damping
    out.nodal_pressure, out._gravity = first.nodal_pressure, first._gravity
    out.nodal_pressure_stabilization = first.nodal_pressure_stabilization
    out.strain_smoothing = first.strain_smoothing
    out.tools = list(first.tools)
    node_off = np.concatenate([[0], np.cumsum([b.n_nodes for b in builders])]).astype(np.int64)
    elem_off = np.concatenate([[0], np.cumsum([b.n_elements for b in builders])]).astype(np.int64)
    out.nodes = np.vstack([b.nodes for b in builders])
    out.tets = np.vstack([b.tets + n0 for b, n0 in zip(builders, node_off)])
    for k, (b, n0, e0) in enumerate(zip(builders, node_off, elem_off)):
        for s in b.sets:
            out.sets.append(dataclasses.replace(s, name=f"{s.name}#{k}", elements=s.elements + e0))
        out._cons.update({(n + int(n0), d): v for (n, d), v in b._cons.items()})
        out._forces += [(ids + n0, f, c) for ids, f, c in b._forces]
        out._pressures += [(F + n0, p, c) for F, p, c in b._pressures]
        out._tractions += [(F + n0, t, c) for F, t, c in b._tractions]
        out._membranes += [(F + n0, m) for F, m in b._membranes]
        out._membrane_clamps += [None if c is None else c + n0 for c in b._membrane_clamps]
        out._node_gravity += [(ids + n0, g, c) for ids, g, c in b._node_gravity]
    out.tool_nodes = [
        None if s is None else np.concatenate([b.tool_nodes[t] + n0 for b, n0 in zip(builders, node_off)])
        for t, s in enumerate(first.tool_nodes)
    ]
    out.source = f"batch of {len(builders)} ({first.source})"
    return out, node_off, elem_off


class Batch:
    """N independent bodies in one :class:`~pliant.tled.model.Model` (``model``): node ranges
    ``node_offsets`` and element ranges ``element_offsets`` (shape (N + 1,) each, user numbering),
    ``bodies`` = N. ``finalize`` options (dtype, threads, backend, device) pass through."""

    def __init__(self, builders: list[ModelBuilder], dtype="float32", **finalize_options):
        merged, self.node_offsets, self.element_offsets = merge_builders(_listed(builders, "builders"))
        self.bodies = len(self.node_offsets) - 1
        self.model = merged.finalize(dtype, **finalize_options)

    @classmethod
    def replicate(
        cls, builder: ModelBuilder, materials: list, dtype="float32", **finalize_options
    ) -> "Batch":
        """len(materials) copies of ``builder``, copy k with ``materials[k]``: a Material (every
        element set) or a dict set name → Material (the sets it names)."""
        builders = []
        for k, m in enumerate(_listed(materials, "materials")):
            b = copy.copy(builder)
            names = {s.name for s in builder.sets}
            _check_material(m, k)
            if isinstance(m, dict) and set(m) - names:
                raise InputError(
                    f"batch: materials[{k}] names element set(s) "
                    f"{sorted(set(m) - names)}; the sets are {sorted(names)}"
                )
            b.sets = [
                dataclasses.replace(s, material=(m.get(s.name, s.material) if isinstance(m, dict) else m))
                for s in builder.sets
            ]
            builders.append(b)
        return cls(builders, dtype, **finalize_options)

    def nodes(self, a: np.ndarray, k: int) -> np.ndarray:
        """Body k's rows of a per-node array (N_total, ...) such as displacements [m]."""
        return a[self.node_offsets[k] : self.node_offsets[k + 1]]

    def elements(self, a: np.ndarray, k: int) -> np.ndarray:
        """Body k's rows of a per-element array (M_total, ...) such as von Mises stress [Pa]."""
        return a[self.element_offsets[k] : self.element_offsets[k + 1]]

    def stack(self, a: np.ndarray) -> np.ndarray:
        """A per-node array with the batch as its leading dimension, shape (B, N, ...), when
        every body has N nodes (copies of one body); InputError otherwise."""
        n = np.diff(self.node_offsets)
        if np.any(n != n[0]):
            raise InputError(
                "batch: the bodies have different node counts "
                f"({sorted(set(n.tolist()))}); take them one by one with nodes(a, k)"
            )
        return a.reshape(self.bodies, int(n[0]), *a.shape[1:])

    def tool_forces(self, report) -> np.ndarray:
        """The force each tool receives from each body at the report's step [N], shape (B, tools, 3),
        from a :class:`~pliant.tled.report.ContactReport` (the per-node forces summed by body, in
        node order: the same bits for any thread count)."""
        n_tools = len(report.tools)
        out = np.zeros((self.bodies, n_tools, 3))
        body = np.searchsorted(self.node_offsets, report.nodes, side="right") - 1
        for i in np.argsort(report.nodes, kind="stable"):
            if report.node_tool[i] >= 0:
                out[body[i], report.node_tool[i]] -= report.node_force[i]  # the tool receives −f
        return out
