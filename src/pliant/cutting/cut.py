"""Applying a cut: the model rebuilt over the split mesh (masses, the node → element gather map,
contact surfaces, the critical time step: everything a Model derives from its mesh), the state
carried over node by node, the solver over the new model with the old one's settings, tool
trajectories and force histories, and an embedded visual surface opened along the cut."""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import InputError, PliantWarning
from .split import Split, crossed_faces, interior_faces, split_nodes

__all__ = ["Cut", "cut", "cut_embedding", "STEP_SAFETY"]

# Fraction of the cut body's linearized stable step a solver may use after a cut: the stiffness
# grows with strain in hyperelastic tissue, and the eigenvalue is found to 1e-3.
STEP_SAFETY = 0.9


@dataclass
class Cut:
    """What a cut made. ``model``, ``state``, ``solver``: the new ones (the same objects when
    nothing was cut); ``parent`` (K,) the node each new node (numbered from the old node count)
    copies; ``faces`` (F, 3) the triangles the cut opened (both sides) and ``face_elements`` (F,)
    the element of each; ``crossed``: interior faces the surface crossed."""

    model: Any
    state: Any
    solver: Any
    parent: np.ndarray
    faces: np.ndarray
    face_elements: np.ndarray
    crossed: int

    @property
    def changed(self) -> bool:
        """Whether the topology changed (some node was split)."""
        return len(self.parent) > 0


def _rebuild_model(model, split: Split):
    """The model over the split mesh, with the old one's precision, threads and backend. The
    warnings its build would repeat (slow elements) were given for the original."""
    builder = model._builder.split(split.tets, split.parent)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PliantWarning)
        new = builder.finalize(model.dtype, threads=model.threads, backend=model.backend, device=model.device)
    if not np.array_equal(new._elem_order, model._elem_order):  # same elements, same centroids
        raise RuntimeError("cut: the element order changed; the viscoelastic state cannot be carried")
    return new


def _carry_state(state, model, parent: np.ndarray):
    """The state over the new model: every node copy takes its parent's u and u⁻ (so its
    velocity); time, step, Δt and the per-element viscoelastic state are kept (elements and their
    engine order are unchanged)."""
    old = state.model
    s = model.state()
    u = state.displacements
    u_prev = old.to_user_nodes(np.asarray(state._s.get_u_prev(), dtype=float))
    s._s.set_u(model.to_engine_nodes(np.vstack([u, u[parent]])))
    s._s.set_u_prev(model.to_engine_nodes(np.vstack([u_prev, u_prev[parent]])))
    q = np.asarray(state._s.get_q())
    if q.size:
        s._s.set_q(q.tolist())
    tool, at = (np.asarray(a) for a in state._s.get_grip())
    if tool.size:  # grasped nodes stay grasped, and so do their copies
        held = {int(n): i for i, n in enumerate(old._contact_engine) if tool[i] >= 0}
        source = np.concatenate([np.arange(old.n_nodes), parent])[model._contact_engine]
        row = np.array([held.get(int(n), -1) for n in source], dtype=np.int64)
        new_tool = np.where(row >= 0, tool[row], -1)
        new_at = np.where(row[:, None] >= 0, at[row], 0.0)
        s._s.set_grip(new_tool.astype(np.int32).tolist(), new_at.ravel().tolist())
    s._s.t, s._s.dt, s._s.step = state._s.t, state._s.dt, state._s.step
    s._s.epoch = state._s.epoch  # the same run clock (a new Δt restarts it: Engine::run)
    return s


def check_cuttable(builder) -> None:
    """InputError if a cut could not carry the model's state: a viscoelastic material with
    edge-smoothed strain keeps its Prony state per edge, and a cut changes the edges."""
    from ..tled.smoothing import StrainSmoothing, strain_smoothing

    if strain_smoothing(builder.strain_smoothing) != StrainSmoothing.Edge:
        return
    for s in builder.sets:
        if getattr(s.material, "prony", None):
            raise InputError(
                f"element set {s.name!r}: a viscoelastic material with edge-smoothed strain cannot be "
                "cut yet (its state lives on the edges a cut changes); expected strain_smoothing = "
                "'element' in a model that is cut"
            )


def cut(state, triangles, solver=None, faces=None) -> Cut:
    """Cut ``state.model`` along the surface ``triangles`` [m] (K, 3, 3), in the state's current
    (deformed) configuration: elements separate at the faces whose centroid-to-centroid segment
    crosses it, and nodes split where their elements fall apart (pliant.cutting.split). Returns a
    :class:`Cut` with the new model and state (and ``solver`` rebuilt over it, if given); the
    inputs are left as they were. ``faces``: the model's :func:`interior_faces`, if known."""
    model = state.model
    check_cuttable(model._builder)
    try:
        tri = np.asarray(triangles, float).reshape(-1, 3, 3)
    except (TypeError, ValueError) as e:
        raise InputError(
            f"cut: triangles {np.shape(triangles)}; expected (K, 3, 3) coordinates [m]: {e}"
        ) from None
    if not np.all(np.isfinite(tri)):
        raise InputError("cut: triangles have non-finite coordinates; expected finite values [m]")
    faces = interior_faces(model.tets) if faces is None else faces
    crossed = crossed_faces(state.positions, model.tets, tri, faces)
    split = split_nodes(model.tets, model.n_nodes, crossed, faces)
    if len(split.parent) == 0:
        return Cut(model, state, solver, split.parent, split.faces, split.face_elements, len(crossed))
    new_model = _rebuild_model(model, split)
    new_state = _carry_state(state, new_model, split.parent)
    new_solver = None
    if solver is not None:  # the step stays below the cut body's own stable step (stability.py)
        from .stability import stable_step

        # Moduli scaled by the solver (a stiffness slider) scale ω² as well.
        dt_stable = stable_step(new_model, new_state) / math.sqrt(solver._material_scale)
        new_solver = solver.over(new_model, dt=min(solver.dt, STEP_SAFETY * dt_stable))
    return Cut(new_model, new_state, new_solver, split.parent, split.faces, split.face_elements, len(crossed))


def cut_embedding(embedding, old_tets: np.ndarray, result: Cut):
    """The embedded visual surface after a cut (pliant.mesh.Embedding; its elements keep their
    numbers): its triangles torn by the cut (two of their vertices lie in elements that shared a
    node before and share none now) are removed, and the faces the cut opened are added, each
    vertex embedded at its node (weights one-hot), so that the surface stays closed."""
    from ..mesh.embed import Embedding

    if not result.changed:
        return embedding
    new_tets = result.model.tets
    e = embedding.tet[embedding.faces]  # (F, 3) element of each corner
    torn = np.zeros(len(e), dtype=bool)
    for i, j in ((0, 1), (1, 2), (2, 0)):
        a, b = e[:, i], e[:, j]
        before = (old_tets[a][:, :, None] == old_tets[b][:, None, :]).any(axis=(1, 2))
        after = (new_tets[a][:, :, None] == new_tets[b][:, None, :]).any(axis=(1, 2))
        torn |= before & ~after
    nv = len(embedding.tet)
    fe = np.repeat(result.face_elements, 3)
    local = np.argmax(new_tets[fe] == result.faces.reshape(-1, 1), axis=1)
    weights = np.zeros((len(fe), 4))
    weights[np.arange(len(fe)), local] = 1.0
    return Embedding(
        np.concatenate([embedding.tet, fe]),
        np.vstack([embedding.weights, weights]),
        np.vstack([embedding.faces[~torn], nv + np.arange(len(fe)).reshape(-1, 3)]),
        np.concatenate([embedding.distance, np.zeros(len(fe))]),
    )
