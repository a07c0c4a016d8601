"""Runs of a sweep stepped together as one batch (:class:`pliant.tled.batch.Batch`): every run's
scene is loaded with its parameters, the bodies are merged into one model, run once, and each
run's outputs are taken from its own node and element ranges. For many small runs, above all on a
GPU, where one launch per step for all of them replaces a launch per run.

What a batch shares (a time step, damping, gravity, tools) must be the same in every run; the
time step is the smallest critical step of the batch unless the scene fixes one (so a run's
figures equal its run alone exactly when the scene sets ``solver.dt``). Per run, the tools'
forces are reported at the end (``tool.NAME.fx|fy|fz``); their peaks and histories need the runs
alone. A batch that cannot be formed or fails (an instability) is run again one run at a time, so
that a failure is recorded against its own run and the others complete."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import InputError, PliantError
from ..guard import one_line
from .case import SceneCase

__all__ = ["run_batch"]

# Settings of a run that one model and one solver hold once: equal in every run of a batch.
_RUN_SETTINGS = ("duration", "dt", "safety", "dtype", "backend", "check_every", "static")


def _run_together(case: SceneCase, scenes: list) -> list[dict[str, Any]]:
    """Outputs of each scene, run as one batch. Raises InputError (settings differ) or
    PliantError (the batch failed)."""
    from ..runner import body_measures, scene_step, total_steps
    from ..tled import Solver
    from ..tled.batch import Batch

    first = scenes[0]
    for sc in scenes[1:]:
        for key in _RUN_SETTINGS:
            if getattr(sc, key) != getattr(first, key):
                raise InputError(f"batch: solver setting {key} differs between runs")
    if first.static:
        raise InputError("batch: quasi-static solves run one by one")
    batch = Batch([sc.builder for sc in scenes], first.dtype, threads=case.threads, backend=first.backend)
    model = batch.model
    dt = scene_step(first, model)  # as each run alone would take it
    solver = Solver(model, dt=dt, safety=first.safety, check_every=first.check_every)
    state = model.state()
    solver.run(state, steps=total_steps(first.duration, solver.dt))
    res = model.element_results(state)
    forces = batch.tool_forces(solver.contact_report()) if model.tools else np.zeros((batch.bodies, 0, 3))
    X, u = model.reference_positions, state.displacements
    out = []
    for k in range(batch.bodies):
        nodes = slice(batch.node_offsets[k], batch.node_offsets[k + 1])
        elems = slice(batch.element_offsets[k], batch.element_offsets[k + 1])
        rec = {
            **body_measures(model, state, res, nodes, elems),
            "steps": state.steps,
            "simulated_time": state.time,
            "dt": solver.dt,
        }
        for j, tool in enumerate(model.tools):
            rec.update({f"tool.{tool.name}.f{c}": float(forces[k, j, i]) for i, c in enumerate("xyz")})
        rec.update(case.point_outputs(X[nodes], u[nodes]))
        out.append(rec)
    return out


def run_batch(case: SceneCase, indices: list[int], params: list[dict]) -> list[dict]:
    """A worker's task for a batch: the records of runs ``indices`` (as :func:`run_one` makes
    them), run together when they can be, else one by one."""
    import time
    import warnings

    from ..job import load_job
    from .execute import run_one

    t0 = time.perf_counter()
    scenes, records = [], {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for i, p in zip(indices, params):
            try:
                scenes.append((i, load_job(case.base, case.ignore, {**case.fixed, **p})))
            except PliantError as e:
                records[i] = {"run": i, "status": "failed", "error": one_line(str(e)), "wall_time": 0.0}
        try:
            outputs = _run_together(case, [sc for _, sc in scenes]) if scenes else []
        except PliantError:
            outputs = None  # run alone: each failure is attributed to its own run
    if outputs is None:
        for i, p in zip(indices, params):
            records.setdefault(i, run_one(case, i, p, None))
    else:
        share = (time.perf_counter() - t0) / max(1, len(scenes))
        for (i, _), o in zip(scenes, outputs):
            records[i] = {
                "run": i,
                "status": "ok",
                "error": "",
                **o,
                "wall_time": share,
                "batch": len(scenes),
            }
    return [records[i] for i in indices]
