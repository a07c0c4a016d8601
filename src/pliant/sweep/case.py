"""One run of a sweep: the base scene with the run's parameters set, run as ``pliant run`` runs it
(same steps, same bits), and the outputs to collect. A :class:`SceneCase` is what a Dask worker
calls; any other callable ``case(params, run_dir) -> dict`` can stand in its place (a closed-form
model run through the same machinery)."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..scene.select import closest_node
from .spec import Outputs, SweepSpec

__all__ = ["SceneCase", "SUMMARY_OUTPUTS"]

# Scalars of a run's summary that every sweep collects: max displacement [m], max von Mises [Pa],
# max membrane tension [N/m], kinetic and strain energy [J] at the end, steps, simulated time [s],
# time step [s].
SUMMARY_OUTPUTS = (
    "max_displacement",
    "max_von_mises",
    "max_membrane_tension",
    "kinetic_energy",
    "strain_energy",
    "steps",
    "simulated_time",
    "dt",
)


@dataclass(frozen=True)
class SceneCase:
    """Runs ``base`` (scene or NiftySim model) with ``fixed`` and then a run's parameters set (key
    path → value), with ``threads`` CPU threads, collecting ``outputs``."""

    base: str
    fixed: dict = field(default_factory=dict)
    outputs: Outputs = field(default_factory=Outputs)
    threads: int = 1
    ignore: tuple[str, ...] = ()

    @classmethod
    def from_spec(cls, spec: SweepSpec) -> "SceneCase":
        return cls(str(spec.base), dict(spec.fixed), spec.outputs, spec.threads, spec.ignore)

    def __call__(self, params: dict[str, Any], run_dir: Path | None = None) -> dict[str, Any]:
        """The run's outputs (flat: name → number or list). Raises what ``pliant run`` raises
        (InputError for a bad value, InstabilityError when the run fails)."""
        from ..job import load_job
        from ..runner import run_scene

        scene = load_job(self.base, self.ignore, {**self.fixed, **params})
        summary = run_scene(
            scene,
            run_dir if self.outputs.fields else None,
            progress=False,
            threads=self.threads,
            echo=lambda *a, **k: None,
            inspect=lambda m, s, st: self._inspect(m, s, st, run_dir),
        )
        return _flatten(summary)

    def point_outputs(self, X: np.ndarray, u: np.ndarray) -> dict[str, Any]:
        """Displacement [m] at the node nearest each named point (first on ties) of a body with
        reference positions X [m] and displacements u [m], shapes (N, 3)."""
        out: dict[str, Any] = {}
        for name, p in self.outputs.points.items():
            node = closest_node(X, p)[0]
            out.update({f"point.{name}.u{c}": float(u[node, j]) for j, c in enumerate("xyz")})
            out[f"point.{name}.node"] = node
        return out

    def _inspect(self, model, solver, state, run_dir: Path | None) -> dict[str, Any]:
        """Outputs that need the final state: displacement at named points, force histories, and
        (with fields) the final fields saved for the dataset."""
        X, u = model.reference_positions, state.displacements
        out = self.point_outputs(X, u)
        if self.outputs.tool_history and model.tools:
            for tool, H in zip(model.tools, solver.contact_report().tools):
                out[f"tool.{tool.name}.time"] = H.time.tolist()
                out[f"tool.{tool.name}.force_history"] = H.force.tolist()
        if self.outputs.fields and run_dir is not None:
            res = model.element_results(state)
            np.savez(
                Path(run_dir) / "fields.npz",
                points=X,
                tets=model.tets,
                displacement=u,
                von_mises=res["von_mises"],
                J=res["J"],
            )
        return out


def _flatten(summary: dict) -> dict[str, Any]:
    """The summary's scalars, per-tool figures and support reactions as flat columns; inspect's
    entries as they are."""
    out = {k: summary.get(k) for k in SUMMARY_OUTPUTS}
    for t in summary.get("tools", []):
        out[f"tool.{t['name']}.max_force"] = t["max_force"]
        out.update({f"tool.{t['name']}.f{c}": t["force"][j] for j, c in enumerate("xyz")})
    for r in summary.get("reactions", []):
        out.update({f"reaction.{r['name']}.f{c}": r["force"][j] for j, c in enumerate("xyz")})
    out.update({k: v for k, v in summary.items() if k.startswith(("point.", "tool."))})
    return out
