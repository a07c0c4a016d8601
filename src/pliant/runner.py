"""Running a scene: dynamics (or a quasi-static solve) with periodic output frames, a progress bar,
clean Ctrl-C, summary.json and a PNG picture. Every file is written atomically."""

from __future__ import annotations

import json
import math
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from . import __version__
from .checks import flag
from .errors import ConvergenceError, InputError, InstabilityError, PliantWarning
from .io import ResultWriter, atomic_write_text, check_output_dir
from .io.results import INDEX, SURFACE_INDEX, is_frame_file
from .job import Scene
from .memory import OUTPUT_BYTES_PER_TET, require_memory
from .tled import Solver
from .tled.solver import MAX_STEPS, default_step


def _frame_steps(scene: Scene, dt: float, total_steps: int) -> int:
    if scene.output_every:
        return scene.output_every
    if scene.output_interval:
        return max(1, int(round(min(scene.output_interval / dt, MAX_STEPS))))
    return max(1, math.ceil(total_steps / scene.frames))


# NiftySim's nodal outputs (tledSolutionWriter): <Variable> → what each frame keeps, (N, 3).
NIFTYSIM_OUTPUTS = {
    "U": lambda model, state: state.displacements.copy(),  # displacements [m]
    "F": lambda model, state: model.internal_forces(state),  # internal nodal forces [N]
}


def keep_reactions(kept: dict[str, dict], model, state) -> None:
    """Adds each support's reaction [N] at the state (Model.support_reactions) to ``kept``: per
    support name its DOFs, node count, and the times [s] and forces of the frames so far."""
    if not model.supports or not np.all(np.isfinite(state.displacements)):
        return
    forces = model.support_reactions(state)
    for name, ids, dofs in model.supports:
        row = kept.setdefault(name, {"dofs": dofs, "nodes": 0, "time": [], "force": []})
        row["nodes"] = int(ids.size)  # after a cut, with the copies of its nodes
        row["time"].append(state.time)
        row["force"].append(forces[name].tolist())


def write_niftysim_text(path: Path, frames: list[np.ndarray]) -> None:
    """NiftySim's U.txt or F.txt (tledSolutionWriter): a row per DOF (x, y, z of node 0 first), a
    column per output frame after the first, to 9 digits. pliant's frame k is at k·Freq·Δt,
    NiftySim's one step later (docs/scenes.md)."""
    import io

    text = io.StringIO()
    if frames:
        np.savetxt(text, np.stack([u.reshape(-1) for u in frames], axis=1), fmt="%.9g")
    atomic_write_text(path, text.getvalue())


def scene_step(scene: Scene, model, divide: bool = True) -> float | None:
    """The step [s] a run of the scene takes on ``model``. The automatic step (scene.dt None) is
    the solver's default, safety × critical, shortened to duration / n, n the fewest whole steps
    that reach the duration, so that the run ends at it (it ran on to the next multiple of the step:
    a 0.01 s run ended at 0.01129 s); None for a quasi-static solve (the solver's own). A given
    scene.dt is kept, except for a scene whose step was chosen for other elements
    (scene.meta["dt_divides"], its reason: a NiftySim H8 model split into tetrahedra) when
    ``divide``: dt / k for the least k that is stable, the output every k times as many steps (the
    same frame times), with a warning that says so."""
    from .tled.solver import stable_substeps

    dt = scene.dt
    if dt is None:
        if scene.static:
            return None
        auto = default_step(model, scene.safety)
        return min(auto, scene.duration / total_steps(scene.duration, auto))  # min: round-off
    if not divide or not scene.meta.get("dt_divides"):
        return dt
    if "dt_divided_by" in scene.meta:  # decided once per scene (a viewer's reset asks again)
        return dt / scene.meta["dt_divided_by"]
    k = scene.meta["dt_divided_by"] = stable_substeps(model, dt)
    if k > 1:
        if scene.output_every:
            scene.output_every *= k
        scene.warnings.append(
            f"{scene.source}: TimeStep {dt:.4g} s exceeds the stable step of the {scene.meta['dt_divides']}; "
            f"each step runs as {k} steps of {dt / k:.4g} s (outputs at the same times)"
        )
    return dt / k


def build(scene: Scene, threads: int | None = None, backend: str | None = None, allow_unstable: bool = False):
    """The scene's model and solver. Input errors name the scene file (the builder knows only the
    mesh's source); a duration of more than MAX_STEPS steps is refused here, before any work. The
    step is scene_step's."""
    try:
        model = scene.builder.finalize(
            scene.dtype,
            threads=scene.threads if threads is None else threads,
            backend=backend or scene.backend,
        )
        dt = scene_step(scene, model, divide=not allow_unstable)
        solver = Solver(
            model,
            dt=dt,
            safety=scene.safety,
            allow_unstable=allow_unstable,
            check_every=scene.check_every,
        )
    except InputError as e:
        if scene.source in str(e):
            raise
        raise type(e)(f"{scene.source}: {e}", *_extra_args(e)) from None
    total = scene.duration / solver.dt - 1e-9
    if not total <= MAX_STEPS:
        raise InputError(
            f"{scene.source}: duration {scene.duration:g} s takes {total:.3g} steps of "
            f"{solver.dt:.3g} s; expected at most {MAX_STEPS:.0e} steps (shorten the "
            "duration, or use a quasi-static solve)"
        )
    return model, solver


def total_steps(duration: float, dt: float) -> int:
    """Steps of ``dt`` [s] that reach ``duration`` [s] (at least one)."""
    return max(1, math.ceil(duration / dt - 1e-9))


def body_measures(model, state, res: dict, nodes=slice(None), elements=slice(None)) -> dict:
    """A run's closing figures, of the whole model or of one body of a batch (its node and element
    ranges): max displacement [m], max von Mises [Pa] of the tets (0 without), the membranes'
    largest principal tension [N/m] (0 without), kinetic energy ½ Σ m v² [J] (half-step velocity)
    and strain energy [J], Σ V0 W of the tets and Σ A0 h W of the membranes. ``res``:
    ``model.element_results(state)``."""
    u, v = state.displacements[nodes], state.velocities[nodes]
    tets = float(np.dot(model.element_volumes()[elements], res["energy_density"][elements]))
    membranes = _membrane_results(model, state, nodes)
    return {
        "max_displacement": float(np.linalg.norm(u, axis=1).max()),
        "max_von_mises": float(res["von_mises"][elements].max(initial=0.0)),  # 0: membranes alone
        "max_membrane_tension": float(membranes["max_tension"].max(initial=0.0)),  # 0: no membranes
        "kinetic_energy": float(0.5 * np.sum(model.mass[nodes, None] * v * v)),
        "strain_energy": tets + float(membranes["energy"].sum()),
    }


def _membrane_results(model, state, nodes: slice) -> dict[str, np.ndarray]:
    """Model.membrane_results of the membranes whose nodes lie in the node range ``nodes`` (a
    body's): their ``max_tension`` [N/m] and ``energy`` A0 h W [J] (empty without membranes)."""
    if not model.n_membranes:
        return {"max_tension": np.zeros(0), "energy": np.zeros(0)}
    lo, hi, _ = nodes.indices(model.n_nodes)
    first = model.membrane_faces[:, 0]
    mine = (first >= lo) & (first < hi)
    return {k: v[mine] for k, v in model.membrane_results(state).items() if k in ("max_tension", "energy")}


# What a run writes into its folder (run_scene): an earlier run's are replaced as a whole.
RUN_FILES = (
    INDEX,
    SURFACE_INDEX,
    "summary.json",
    "result.png",
    "tools.json",
    "contact_pairs.json",
    "reactions.json",
    "points.json",
    "U.txt",
    "F.txt",
)


def clear_earlier_run(out: Path) -> int:
    """Remove the files an earlier run left in ``out`` (RUN_FILES and its numbered frames, where
    its result.pvd or summary.json says one ran there; nothing else), so that a new run's folder
    never mixes two runs: a run of 5 frames after one of 20 left frames 6 to 20 beside it. Returns
    how many files were removed."""
    if not any((out / f).exists() for f in (INDEX, "summary.json")):
        return 0
    old = [f for f in out.iterdir() if f.is_file() and (f.name in RUN_FILES or is_frame_file(f.name))]
    for f in old:
        try:
            f.unlink()
        except OSError as e:
            raise InputError(f"{f}: cannot replace an earlier run's file: {e.strerror or e}") from None
    return len(old)


def _pair_results(model, solver, summary: dict, out: Path | None) -> None:
    """Soft contact's pairs of bodies (Model.contact_pairs): per pair its bodies, their names (the
    scene's, else "body N"), the force [N] its first body received from the second at the last step
    (a quasi-static solve's: at the equilibrium) and the largest, in summary.json's
    ``contact_pairs``, and at every step in contact_pairs.json."""
    contact = model._builder.soft_contact
    known = (contact.names if contact is not None else None) or {}
    summary["contact_pairs"], steps = [], []
    for pair in solver.contact_report().pairs:
        names = [known.get(b, f"body {b}") for b in pair.bodies]
        if pair.relaxed is not None:  # after a relaxation: the equilibrium's
            last = pair.relaxed
        else:
            last = pair.force[-1] if len(pair.time) else np.zeros(3)
        peak = float(np.linalg.norm(np.vstack([pair.force, last]), axis=1).max())
        summary["contact_pairs"].append(
            {"bodies": list(pair.bodies), "names": names, "force": last.tolist(), "max_force": peak}
        )
        steps.append(
            {
                "bodies": list(pair.bodies),
                "names": names,
                "time": pair.time.tolist(),
                "force": pair.force.tolist(),
            }
        )
    if out is not None:
        atomic_write_text(out / "contact_pairs.json", json.dumps(steps))
        summary["files"].append("contact_pairs.json")


def _extra_args(e: Exception) -> tuple:
    """The arguments after the message of errors that carry more (an element id)."""
    return (e.element,) if hasattr(e, "element") else ()


class _NoFiles:
    """The writer of a run that keeps no files (a sweep's run without fields): counts frames."""

    def __init__(self):
        self.frames: list[tuple[float, str]] = []

    def write(self, state) -> None:
        self.frames.append((state.time, ""))


def run_scene(
    scene: Scene,
    out_dir,
    progress: bool = True,
    allow_unstable: bool = False,
    threads: int | None = None,
    echo=print,
    backend: str | None = None,
    inspect=None,
) -> dict:
    """Run ``scene`` and write OUTDIR/result.pvd, frame_*.vtu, summary.json and result.png
    (``out_dir=None``: no files, the summary alone). ``inspect(model, solver, state) -> dict``, when
    given, adds its entries to the summary once the run has ended (a sweep's outputs).
    Returns the summary. Raises InstabilityError (after writing what it has) when the run fails,
    ConvergenceError (after writing the results) when a quasi-static solve stops short of its tol;
    on KeyboardInterrupt the summary says ``interrupted`` and the frames so far are kept."""
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

    # checked first, created only once the model is valid
    progress, allow_unstable = flag(progress, "progress"), flag(allow_unstable, "allow_unstable")
    out = None if out_dir is None else check_output_dir(out_dir)
    t_build = time.perf_counter()
    with warnings.catch_warnings(record=True) as held:  # a refused build prints its error alone
        warnings.simplefilter("always")
        model, solver = build(scene, threads, backend, allow_unstable)
    for text in scene.warnings:
        warnings.warn(PliantWarning(text), stacklevel=2)
    for w in held:
        warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    if out is not None:
        require_memory(
            model.n_elements, OUTPUT_BYTES_PER_TET, f"{scene.source}: the frames of {model.n_elements:,} tets"
        )
    total = total_steps(scene.duration, solver.dt)
    state = model.state()
    embedding: Any = None
    if out is not None and scene.meta.get("embed_surface"):
        from .mesh import embed_surface

        Ve, Fe = scene.meta["embed_surface"]
        embedding = embed_surface(model.reference_positions, model.tets, Ve, Fe)
    if out is not None and out.is_dir() and (n := clear_earlier_run(out)):
        warnings.warn(PliantWarning(f"{out}: replaced the {n} files of an earlier run there"), stacklevel=2)
    writer = _NoFiles() if out is None else ResultWriter(out, model, fields=scene.fields, embedding=embedding)
    cutter = None
    if scene.blades:  # blades cut as it runs: model, solver and state change with the topology
        from .cutting import Cutter

        cutter = Cutter(list(scene.blades), embedding=embedding)
    # NiftySim's U.txt, F.txt: each frame's nodal values after the first
    texts: dict[str, list[np.ndarray]] = {
        v: [] for v in scene.meta.get("niftysim_outputs", ()) if out is not None
    }
    reactions: dict[str, dict] = {}  # per support: its force [N] at each frame (reactions.json)
    probes: dict[str, dict] = {  # per output point: its node's displacement [m] at each frame
        name: {
            "node": node,
            "position": model.reference_positions[node].tolist(),
            "time": [],
            "displacement": [],
        }
        for name, node in scene.points.items()
    }

    def keep_frame(first: bool = False) -> None:
        """Writes the frame and keeps its support reactions, its output points' displacements and
        (after the first) its NiftySim text outputs."""
        writer.write(state)
        for v, kept in texts.items() if not first else ():
            kept.append(NIFTYSIM_OUTPUTS[v](model, state))
        keep_reactions(reactions, model, state)
        u = state.displacements
        for row in probes.values():
            row["time"].append(state.time)
            row["displacement"].append(u[row["node"]].tolist())

    build_s = time.perf_counter() - t_build
    summary = {
        "pliant": __version__,
        "scene": scene.source,
        "title": scene.title,
        "mode": "static" if scene.static else "dynamic",
        "steps": 0,
        "dt": solver.dt,
        "dt_critical": model.dt_critical,
        "simulated_time": 0.0,
        "wall_time": 0.0,
        "setup_time": build_s,
        "backend": model.backend,
        "threads": model.threads,
        "dtype": scene.dtype,
        "elements": model.n_elements,
        "nodes": model.n_nodes,
        "interrupted": False,
        "error": None,
        "warnings": list(scene.warnings) + [str(w.message) for w in held],
        "files": [INDEX, "summary.json"],
    }
    pipeline = scene.meta.get("mesh_pipeline")
    if pipeline:  # a surface went through the mesh pipeline: say what it made
        summary["mesh_pipeline"] = pipeline
        if pipeline.get("bodies", 1) > 1:
            echo(
                f"{pipeline['bodies']} bodies in the surface, meshed "
                f"{'as their union' if pipeline['bodies_mode'] == 'union' else pipeline['bodies_mode']}"
                f": {pipeline['tets']:,} tets"
            )
    t0 = time.perf_counter()
    try:
        keep_frame(first=True)  # frame 0, inside: a Ctrl-C while it is written still ends with a summary
        if scene.static:
            info = solver.relax(
                state, at_time=scene.duration, tol=scene.tol, increments=scene.increments, strict=False
            )
            summary.update(relax_steps=info.steps, residual=info.residual, converged=info.converged)
            if not info.converged:  # raised once the results are written (the end of run_scene)
                summary["error"] = f"quasi-static solve: {solver._unconverged(info, scene.tol)}"
            keep_frame()
        else:
            every = _frame_steps(scene, solver.dt, total)
            if scene.meta.get("frames_given") and scene.frames > total:
                text = (
                    f"{scene.source}: frames = {scene.frames:,} but the run has {total:,} steps: "
                    f"a frame every step ({total + 1:,} frames)"
                )
                summary["warnings"].append(text)
                warnings.warn(PliantWarning(text), stacklevel=2)
            cols = (
                TextColumn("t = {task.fields[t]:.4g} s"),
                BarColumn(),
                TextColumn("{task.completed}/{task.total} steps"),
                TextColumn("{task.fields[rate]:,.0f} steps/s"),
                TimeElapsedColumn(),
                TimeRemainingColumn(),
            )
            with Progress(*cols, disable=not progress, transient=False) as bar:
                task = bar.add_task("run", total=total, t=0.0, rate=0.0)
                done = 0
                while done < total:
                    n = min(every - done % every, total - done)
                    if cutter is None:
                        solver.run(state, steps=n)
                    else:
                        solver, state = cutter.run(solver, state, n)
                        model, embedding = solver.model, cutter.embedding
                        if isinstance(writer, ResultWriter):
                            writer.embedding = embedding
                        # A cut may shorten the step (cutting/stability.py): the steps left.
                        left = scene.duration - state.time
                        total = done + n + (total_steps(left, solver.dt) if left > 1e-9 * solver.dt else 0)
                        bar.update(task, total=total)
                    done += n
                    if done % every == 0 or done == total:
                        keep_frame()
                    el = time.perf_counter() - t0
                    bar.update(task, completed=done, t=state.time, rate=done / max(el, 1e-9))
    except KeyboardInterrupt:
        summary["interrupted"] = True
    except InstabilityError as e:
        summary["error"] = str(e)
        raise
    finally:
        summary["wall_time"] = time.perf_counter() - t0
        summary["steps"] = state.steps if not scene.static else summary.get("relax_steps", 0)
        summary["simulated_time"] = state.time
        # Simulated seconds per wall second, output included (None for a quasi-static solve).
        summary["real_time_factor"] = None if scene.static else state.time / max(summary["wall_time"], 1e-12)
        summary["frames"] = len(writer.frames)
        if cutter is not None:  # the topology after the cuts
            summary.update(elements=model.n_elements, nodes=model.n_nodes, cuts=len(cutter.events))
        u = state.displacements
        if np.all(np.isfinite(u)):
            res = model.element_results(state)
            summary.update(body_measures(model, state, res))
            if scene.png and out is not None:
                from .view import render_png

                surface, field, label = None, res["von_mises"], "von Mises stress [Pa]"
                sheets = None  # membranes apart from the tets, drawn grey beside them
                if embedding is not None:  # the fine surface, as the viewer and surface.pvd show
                    Pe = embedding.positions(model.tets, state.positions)
                    surface = (Pe, embedding.faces, embedding.tet[embedding.faces[:, 0]])
                elif not model.n_elements:  # membranes alone: coloured by their tension, as in the viewer
                    F = model.membrane_faces
                    surface = (state.positions, F, np.arange(len(F)))
                    field = model.membrane_results(state)["max_tension"]
                    label = "membrane tension [N/m]"
                elif model.n_membranes:
                    from .mesh.topology import faces_off

                    sheets = model.membrane_faces[faces_off(model.membrane_faces, model.tets)]
                render_png(
                    out / "result.png",
                    state.positions,
                    model.tets,
                    field,
                    label=label,
                    title=f"{scene.title[:200]}: t = {state.time:.4g} s",
                    surface=surface,
                    sheets=sheets,
                )
                summary["files"].append("result.png")
        if model.tools:
            summary["tools"] = []
            hist = {}
            report = solver.contact_report()
            for k, (tool, H) in enumerate(zip(model.tools, report.tools)):
                force, torque = report.force(k)  # the equilibrium's after a relaxation
                peak = float(np.linalg.norm(H.force, axis=1).max()) if len(H.time) else 0.0
                summary["tools"].append(
                    {"name": tool.name, "force": force.tolist(), "max_force": peak, "torque": torque.tolist()}
                )
                if len(H.time):
                    hist[tool.name] = {
                        "time": H.time.tolist(),
                        "force": H.force.tolist(),
                        "torque": H.torque.tolist(),
                    }
            if out is not None:
                atomic_write_text(out / "tools.json", json.dumps(hist))
                summary["files"].append("tools.json")
        if model.contact_pairs:
            _pair_results(model, solver, summary, out)
        for v, kept in texts.items():
            if out is not None:
                write_niftysim_text(out / f"{v}.txt", kept)
                summary["files"].append(f"{v}.txt")
        if reactions:
            summary["reactions"] = [
                {"name": k, "dofs": r["dofs"], "nodes": r["nodes"], "force": r["force"][-1]}
                for k, r in reactions.items()
            ]
            if out is not None:
                atomic_write_text(out / "reactions.json", json.dumps(reactions))
                summary["files"].append("reactions.json")
        if probes:
            summary["points"] = [
                {"name": k, "node": r["node"], "displacement": r["displacement"][-1] if r["time"] else None}
                for k, r in probes.items()
            ]
            if out is not None:
                atomic_write_text(out / "points.json", json.dumps(probes))
                summary["files"].append("points.json")
        if inspect is not None and np.all(np.isfinite(u)):
            summary.update(inspect(model, solver, state))
        if out is None:
            summary["files"] = []
        else:
            if not writer.frames:  # interrupted before frame 0 was on disk: no index either
                summary["files"].remove(INDEX)
            atomic_write_text(out / "summary.json", json.dumps(summary, indent=2))
    if summary.get("converged") is False:
        where = "" if out is None else f" (its results are in {out})"
        raise ConvergenceError(summary["error"] + where)
    return summary
