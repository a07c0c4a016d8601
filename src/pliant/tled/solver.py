"""Explicit TLED solver: central differences with lumped mass and mass-proportional damping,
and dynamic relaxation for quasi-static solutions.

    u⁺ = γ1 M⁻¹ (r − f(u)) + γ2 u + γ3 u⁻,  γ1 = 2Δt²/(αΔt + 2), γ2 = 4/(αΔt + 2), γ3 = 1 − γ2
    (Taylor, Cheng & Ourselin 2008, IEEE TMI 27(5), eq. 9; Miller et al. 2007, CNME 23:121).
"""

from __future__ import annotations

import copy
import math
import weakref
from typing import Any

import numpy as np

from .. import _core
from .._core import RunStatus
from ..checks import as_real, finite_number, flag, shown, whole_number
from ..errors import ConvergenceError, InputError, InstabilityError, TimeStepError
from .anp import anp_stabilization
from .geometry import sudden_displacement
from .model import Model
from .state import State
from .report import ContactReport, PairHistory, RelaxInfo, RunInfo, ToolHistory, tool_force

__all__ = ["Solver", "RunInfo", "RelaxInfo", "Simulation", "MAX_STEPS"]

# Most steps one call may take: a billion steps is days of computing even on a small mesh; above it
# a duration is almost surely a typo (1e20 s), and tool histories would not fit in memory.
MAX_STEPS = 10**9
MAX_INCREMENTS = 10_000  # load steps of one quasi-static solve


def _check_every(steps) -> int:
    """Steps between stability checks: a whole number from 1 to MAX_STEPS."""
    if not 1 <= whole_number(steps, "check_every") <= MAX_STEPS:
        raise InputError(f"check_every = {shown(steps)}; expected 1 to {MAX_STEPS:.0e} steps")
    return int(steps)


def _in_relaxation(e: InstabilityError, increments: int, contact: bool) -> InstabilityError:
    """An instability of a relaxation, its message told what a quasi-static solve can do: each
    increment moves the prescribed displacements and loads (and the tools) by its share at once,
    so a large share inverts elements, or pushes nodes through a body they press on (a node more
    than a quarter of an element inside in one step is lost: docs/contact.md), whatever Δt."""
    lost = " (and a node pushed deeper than a quarter of an element into another body is lost)"
    words = (
        f"; in a quasi-static solve each of the {increments} increment(s) applies its share of the "
        "prescribed displacements, loads and tool motion at once"
        + (lost if contact else "")
        + ": give more increments (relax(increments=N), a scene's solver.increments)"
    )
    return InstabilityError(str(e) + words, e.time, e.quantity, e.value, e.element, e.node)


def _step_count(steps, what: str = "steps") -> int:
    """A step count: an integer (not a bool, not a float with a fraction) from 0 to MAX_STEPS."""
    whole_number(steps, what, " of steps")
    if not 0 <= steps <= MAX_STEPS:
        raise InputError(f"{what} = {int(steps)}; expected 0 to {MAX_STEPS:.0e} steps in one call")
    return int(steps)


# A step above this fraction of the element estimate Model.dt_critical (h_min / c_d, not a bound:
# a regular box's exact limit is 0.94 of it) is checked against the mesh's highest frequency.
EXACT_CHECK_FRACTION = 0.8
# Of the exact limit 2/ω_max (Lanczos to 1e-3; float32 force differences to ~2e-3): the largest
# step accepted.
EXACT_MARGIN = 0.99


def stable_substeps(model, dt: float) -> int:
    """The least k for which dt / k is a step the solver accepts (1 where dt is): for a model
    whose time step was chosen for other elements (a NiftySim H8 model split into tetrahedra). A
    step no count of steps could divide is refused as the solver refuses it (TimeStepError)."""
    if dt <= EXACT_CHECK_FRACTION * model.dt_critical or dt <= _exact_limit(model):
        return 1
    ratio = dt / _exact_limit(model) * (1 + 1e-12)
    if not ratio <= MAX_STEPS:
        _stable_limit(model, dt)  # raises, naming the stable step
    return max(2, math.ceil(ratio))


def _exact_limit(model) -> float:
    """EXACT_MARGIN of the mesh's own stable step 2/ω_max about the reference state
    (Model.stable_step: Lanczos on M⁻¹K, β damping included), computed once per model: every solver
    of it asks the same."""
    return EXACT_MARGIN * model.stable_step()


def _default_limit(model) -> float:
    """The step [s] a solver takes by default, before its safety factor: the element estimate, or
    where a membrane sets that estimate the exact limit (_exact_limit), if larger: a membrane's own
    estimate counts its own mass alone, while its corners carry the solid's too (docs/engine.md,
    "Membranes": a 3 MPa capsule on a 4 kPa box, 6.8e-5 s against 3.4e-4 s)."""
    if model.dt_critical_membrane < 0:
        return model.dt_critical
    return max(model.dt_critical, _exact_limit(model))


def default_step(model, safety: float = 0.8) -> float:
    """The step Δt [s] a Solver takes when none is given: ``safety`` × the element estimate (or the
    exact limit where a membrane sets the estimate: _default_limit)."""
    return safety * _default_limit(model)


def _stable_limit(model, dt: float) -> float:
    """The largest step [s] a solver accepts, given the one asked for (TimeStepError above it): the
    element estimate for a step at most EXACT_CHECK_FRACTION of it (the default is 0.8 of it);
    above that, the exact limit (_exact_limit), which is below the estimate on regular meshes and
    far above it on meshes with slivers (their nodes carry their neighbours' mass)."""
    if dt <= EXACT_CHECK_FRACTION * model.dt_critical:
        return model.dt_critical
    limit = _exact_limit(model)
    if dt > limit:
        raise TimeStepError(
            f"dt = {dt:.4g} s exceeds the stable time step {limit:.4g} s of this mesh (0.99 of 2/ω_max, "
            f"its highest frequency; the element estimate, smallest altitude / dilatational wave speed "
            f"of {model.dt_critical_limiter}, is {model.dt_critical:.4g} s); use a smaller dt, "
            "or force it with allow_unstable=True (pliant run --allow-unstable)"
        )
    return limit


def _check_model(model, who: str) -> None:
    if not isinstance(model, Model):
        hint = "; call builder.finalize() first" if type(model).__name__ == "ModelBuilder" else ""
        raise InputError(f"{who}: got a {type(model).__name__}; expected a pliant Model{hint}")


class Solver:
    """Explicit solver for a :class:`Model`.

    dt: time step [s]; default ``safety × model.dt_critical`` (where a membrane sets that estimate,
    safety × the exact limit 2/ω_max if larger: see _default_limit). A dt above 0.8 of the estimate is
    checked against the mesh's own stable step 2/ω_max and refused above 0.99 of it
    (:class:`TimeStepError`) unless ``allow_unstable=True``. damping: α [1/s], default the model's.
    check_every: steps between stability checks (NaN, J ≤ 0, blow-up). backend: where it runs,
    "cpu", "cuda" (CUDA device ``device``) or "cuda-emulated" (default: the model's, from
    ``finalize``); the solver owns its backend and its own copy of the tools' trajectories.
    history_steps: the tools' force histories keep the last this many steps (default: all; an
    interactive session that runs for hours, such as a viewer or a haptic loop, bounds it).
    """

    def __init__(
        self,
        model: Model,
        dt: float | None = None,
        safety: float = 0.8,
        damping: float | None = None,
        allow_unstable: bool = False,
        check_every: int = 16,
        backend: str | None = None,
        device: int | None = None,
        history_steps: int | None = None,
    ):
        _check_model(model, "Solver(model)")
        if history_steps is not None:
            history_steps = _step_count(history_steps, "history_steps")
            if history_steps < 1:
                raise InputError(f"history_steps = {shown(history_steps)}; expected >= 1 or None")
        self.history_steps = history_steps
        self.model = model
        if not (0 < as_real(safety) <= 1):
            raise InputError(f"safety = {shown(safety)}; expected 0 < safety <= 1")
        given, dt = dt, default_step(model, float(safety)) if dt is None else as_real(dt)
        if not math.isfinite(dt) or dt <= 0:
            raise TimeStepError(f"dt = {shown(given)}; expected a finite time step > 0 [s]")
        unstable = flag(allow_unstable, "allow_unstable")
        self._limit = model.dt_critical if unstable else _stable_limit(model, dt)
        self.dt = dt
        self.damping = model.damping if damping is None else as_real(damping)
        if not math.isfinite(self.damping) or self.damping < 0:
            raise InputError(f"damping = {shown(damping)}; expected a finite value >= 0 [1/s]")
        self.check_every = _check_every(check_every)
        X = model.reference_positions
        # The body's size [m] (its bounding box's diagonal): a displacement beyond blow_up_sizes of
        # it is a blow-up, a node moving more than it in one step a jump (the engine's check).
        self.size = float(np.linalg.norm(X.max(axis=0) - X.min(axis=0)))
        self._histories = [ToolHistory(t.name) for t in model.tools]
        self._pairs = [PairHistory(p) for p in model.contact_pairs]
        self._relaxed: list | None = None
        # The last run's or step's Δt [s], None before one or after a relaxation (Model.reactions:
        # the inertia of the DOFs prescribed displacements move).
        self._stepped_dt: float | None = None
        self.tools = [copy.copy(t) for t in model.tools]  # trajectories: set_tool_pose edits them
        for t in self.tools:
            t.keys = [np.array(k, copy=True) for k in t.keys]
            t.grips = list(t.grips)
        self._backend = model.make_backend(backend, device)
        self._device, self._allow_unstable = device, allow_unstable  # for over()
        self._material_scale = 1.0

    def over(self, model: Model, dt: float | None = None) -> "Solver":
        """A solver of ``model`` (the same model after a topology change: pliant.cutting) with this
        one's settings (Δt unless ``dt`` [s] is given, damping, checks, backend, stiffness scale),
        tool trajectories and force histories, which go on from where this one's stopped."""
        _check_model(model, "Solver.over(model)")
        new = Solver(
            model,
            dt=self.dt if dt is None else dt,
            damping=self.damping,  # as it is now (a viewer's slider may have changed it)
            allow_unstable=self._allow_unstable,
            check_every=self.check_every,
            backend=self.backend,
            device=self._device,
            history_steps=self.history_steps,
        )
        new.tools = self.tools
        new._histories = self._histories
        if [h.bodies for h in self._pairs] == list(model.contact_pairs):
            new._pairs = self._pairs
        if model.tools:
            new.set_tool_keys()
        if self._material_scale != 1.0:
            new.scale_materials(self._material_scale)
        return new

    @property
    def backend(self) -> str:
        """The backend this solver runs on: "cpu", "cuda" or "cuda-emulated"."""
        return str(self._backend.name)

    def _ran(self):
        self.model._solver = weakref.ref(self)

    def set_tool_keys(self):
        """Send the solver's tool trajectories (``solver.tools[k].keys``) and grasp times
        (``solver.tools[k].grips``) to its backend."""
        self._backend.set_tool_keys(
            [t.key_array().tolist() for t in self.tools],
            [list(t.grips) for t in self.tools],
            [float(t.reach) for t in self.tools],
        )

    def scale_materials(self, factor: float):
        """Multiply every material's moduli by ``factor`` relative to the model's (a stiffness
        slider); the critical time step scales by 1/√factor: keep dt below it."""
        factor = finite_number(factor, "factor")
        if not factor > 0:
            raise InputError(f"factor = {shown(factor)}; expected > 0")
        self._backend.scale_materials(factor)
        self._material_scale = factor

    def contact_report(self) -> ContactReport:
        """The tools' force histories, the last step's contact forces per node and, after a
        relaxation, the equilibrium tool forces (:class:`ContactReport`)."""
        nodes, tool, f, soft, soft_f = self._backend.contact_state()
        tool, f = np.asarray(tool), np.array(f)
        f[tool < 0] = 0.0
        order = self.model._node_order
        return ContactReport(
            self._histories,
            order[np.asarray(nodes)],
            tool,
            f,
            self._relaxed,
            self._pairs,
            order[np.asarray(soft)],
            np.array(soft_f),
        )

    @property
    def tool_histories(self) -> dict[int, ToolHistory]:
        """Deprecated: ``contact_report().tools``."""
        import warnings

        warnings.warn(
            "Solver.tool_histories is deprecated; use Solver.contact_report().tools",
            DeprecationWarning,
            stacklevel=2,
        )
        return dict(enumerate(self._histories))

    @property
    def relaxed_tool_forces(self):
        """Deprecated: ``contact_report().relaxed``."""
        import warnings

        warnings.warn(
            "Solver.relaxed_tool_forces is deprecated; use Solver.contact_report().relaxed",
            DeprecationWarning,
            stacklevel=2,
        )
        return self._relaxed

    def _loose_hint(self) -> str:
        """For an instability: a sheet that only bends and nothing holds in its plane, or ""."""
        loose = _loose_sheet_node(self.model)
        if loose is None:
            return ""
        return (
            f"; {_loose_words(loose)}: loaded across, such a sheet shrinks in its plane at second "
            "order in its slope, and folds up under large slopes; give it an in-plane modulus"
        )

    def _jump_hint(self) -> str:
        """For a jump: a sheet that only bends (_loose_hint); where membranes carry compression,
        that a sheet may need to wrinkle (a bending sheet compressed at a scale its cells cannot
        fold snaps element by element: docs/engine.md, "Bending")."""
        loose = self._loose_hint()
        if loose:
            return loose
        compressed = [m for m in self.model.membrane_materials if not m.wrinkling]
        if any(m.bends for m in compressed):
            return (
                "; a bending sheet compressed at a scale its cells cannot fold (a drape) snaps "
                "element by element: let it wrinkle (wrinkling = true) or halve dt"
            )
        if compressed:
            return (
                "; membranes that carry compression stiffen as they crumple: a free sheet should "
                "wrinkle (wrinkling=True, the [[sheet]] default)"
            )
        return ""

    def _sudden_hint(self, t: float) -> str:
        """For an instability within the first check (t ≤ (check_every + 1) Δt): a prescribed
        displacement its curve applies whole in the first step, beyond half its node's elements'
        smallest altitude (geometry.sudden_displacement; looked for only then), or ""."""
        if t > (self.check_every + 1.5) * self.dt:
            return ""
        size = self.model._node_sizes()
        found = sudden_displacement(self.model._builder._cons, size)
        if found is None:
            return ""
        n, d, value, curve = found
        return (
            f"; node {n} is prescribed {value:.3g} m along {'xyz'[d]} from the first step on ({curve!r} is "
            f"{float(curve(0.0)):g} at t = 0), more than half its elements' smallest altitude "
            f"({size[n]:.3g} m): that step moves it across them whatever the step; "
            'give it a ramp (pliant.SmoothRamp; curve = "smooth-ramp" in scenes)'
        )

    def _raise(self, rep: dict):
        m, t, v, status = self.model, rep["t"], rep["value"], rep["status"]
        if status == RunStatus.Inverted and not math.isfinite(v):
            e = m.user_element(rep["where"])
            raise InstabilityError(
                f"unstable at t = {t:.6g} s: non-finite deformation in element {e} (J = {v}); "
                f"reduce dt (now {self.dt:.3g} s) or the loads{self._sudden_hint(t)}",
                t,
                "J",
                v,
                element=e,
            )
        if status == RunStatus.Inverted:
            e = m.user_element(rep["where"])
            # T4ANP without stabilization resists an element's own volume change by shear alone.
            hint = (
                '; with nodal_pressure, try nodal_pressure_stabilization = "shear"'
                if m.nodal_pressure and anp_stabilization(m.nodal_pressure_stabilization) == (0.0, False)
                else ""
            )
            raise InstabilityError(
                f"unstable at t = {t:.6g} s: element {e} inverted (J = {v:.3g} <= 0); reduce dt "
                f"(now {self.dt:.3g} s), the loads, or refine/soften around it{hint}{self._sudden_hint(t)}",
                t,
                "J",
                v,
                element=e,
            )
        node = m.user_node(rep["where"])
        if status == RunStatus.NonFinite:
            raise InstabilityError(
                f"unstable at t = {t:.6g} s: non-finite displacement at node {node}"
                f" (value {v}); dt = {self.dt:.3g} s{self._loose_hint()}",
                t,
                "displacement",
                v,
                node=node,
            )
        if status == RunStatus.Jump:
            raise InstabilityError(
                f"unstable at t = {t:.6g} s: node {node} moved {abs(v):.3g} m in one step, more than "
                f"the body's size ({self.size:.3g} m), the sawtooth of an unstable step; reduce dt "
                f"(now {self.dt:.3g} s){self._jump_hint()}",
                t,
                "step displacement",
                v,
                node=node,
            )
        raise InstabilityError(
            f"unstable at t = {t:.6g} s: displacement {v:.3g} m at node {node} exceeds "
            f"{_core.blow_up_sizes:g} x the body size (energy blow-up); dt = {self.dt:.3g} s"
            f"{self._loose_hint()}",
            t,
            "displacement",
            v,
            node=node,
        )

    def _same_model(self, *states: State):
        for s in states:
            if s.model is not self.model:
                raise InputError("state belongs to another model")

    def step(self, state_in: State, state_out: State, dt: float | None = None) -> None:
        """One step from state_in to state_out (distinct objects); dt [s] defaults to the solver's."""
        self._same_model(state_in, state_out)
        if state_in is state_out:
            raise InputError("step(state_in, state_out): states must be distinct; use run() in place")
        given, dt = dt, self.dt if dt is None else as_real(dt)
        if not (math.isfinite(dt) and dt > 0):
            raise TimeStepError(f"dt = {shown(given)}; expected a finite time step > 0 [s]")
        if dt > self._limit and self.dt <= self._limit:
            raise TimeStepError(f"dt = {dt:.4g} s exceeds the stable time step {self._limit:.4g} s")
        rep = self._backend.step(state_in._s, state_out._s, dt, self.damping)
        self._ran()
        self._forget_relaxed()
        self._stepped_dt = dt
        if rep["status"]:
            self._raise(rep)

    def run(self, state: State, steps: int | None = None, until: float | None = None) -> RunInfo:
        """Advance ``state`` in place by ``steps`` steps or to time ``until`` [s] (a time the state
        has reached takes no step: RunInfo.steps is 0, so that a loop over output times may call
        it for every one)."""
        self._same_model(state)
        steps = self.step_count(state, steps, until)
        if steps == 0:
            return RunInfo(0, state.time)
        rep = self._backend.run(state._s, steps, self.dt, self.damping, self.check_every, self.size)
        self._ran()
        self._forget_relaxed()
        self._stepped_dt = self.dt
        self._record_tools(state, int(rep["steps"]))
        if rep["status"]:
            self._raise(rep)
        return RunInfo(
            int(rep["steps"]),
            float(rep["t"]),
            float(rep["elem_seconds"]),
            float(rep["node_seconds"]),
            float(rep["contact_seconds"]),
        )

    def step_count(self, state: State, steps: int | None = None, until: float | None = None) -> int:
        """The steps of ``run(state, steps=…)`` or ``run(state, until=…)``: exactly one given, a
        whole number from 0 to MAX_STEPS (``until`` [s]: the steps of Δt that reach it)."""
        if (steps is None) == (until is None):
            raise InputError("run: give exactly one of steps= or until=")
        if steps is None:
            until = finite_number(until, "until", "s")
            n = (until - state.time) / self.dt - 1e-9
            if not n <= MAX_STEPS:
                raise InputError(
                    f"until = {until:g} s is {n:.3g} steps of {self.dt:.3g} s away; "
                    f"expected at most {MAX_STEPS:.0e} steps in one call"
                )
            steps = max(0, math.ceil(n))
        return _step_count(steps)

    def _forget_relaxed(self):
        """A step or run leaves the last relaxation's equilibrium: no relaxed forces."""
        self._relaxed = None
        for P in self._pairs:
            P.relaxed = None

    def _record_tools(self, state: State, steps: int):
        """The last run's tool and pair forces into their histories, at the times of its steps
        on the state's run clock (State: t_epoch + (step − step_epoch) Δt)."""
        t = state._clock_times(state.steps - steps + np.arange(1, steps + 1))
        keep = slice(-self.history_steps, None) if self.history_steps else slice(None)
        if self._pairs:
            hp = np.asarray(self._backend.pair_history())[:steps]
            for k, P in enumerate(self._pairs):
                P.time = np.concatenate([P.time, t])[keep]
                P.force = np.concatenate([P.force, hp[:, k, :]])[keep]
        if not self.model.tools:
            return
        h = np.asarray(self._backend.tool_history())[:steps]
        for k, H in enumerate(self._histories):
            H.time = np.concatenate([H.time, t])[keep]
            H.force = np.concatenate([H.force, h[:, k, :3]])[keep]
            H.torque = np.concatenate([H.torque, h[:, k, 3:]])[keep]

    def _tool_index(self, k) -> int:
        n = len(self.model.tools)
        if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or not 0 <= k < n:
            raise InputError(
                f"tool index {shown(k)}; expected an integer from 0 to {n - 1}"
                if n
                else f"tool index {shown(k)}: this model has no tools"
            )
        return int(k)

    def tool_force(self, k: int = 0) -> tuple[np.ndarray, np.ndarray]:
        """Force [N] and torque [N·m] tool k received at the last step, or at the equilibrium after
        a relaxation (zeros before any step): ``contact_report().force(k)``, without fetching the
        per-node contact forces (the viewer asks every frame)."""
        return tool_force(self._histories, self._relaxed, self._tool_index(k))

    def relax(
        self,
        state: State,
        at_time: float | None = None,
        tol: float = 1e-5,
        max_steps: int = 200_000,
        increments: int = 1,
        check_every: int = 10,
        strict: bool = True,
    ) -> RelaxInfo:
        """Quasi-static equilibrium under the loads and prescribed displacements of time ``at_time``
        [s] (default: when every load curve has reached its final value), by dynamic relaxation with
        adaptive damping (Joldes, Wittek & Miller 2009, CMAME 198:3313) over fictitious masses
        that give every element the same critical step (Underwood 1983; docs/engine.md). Rigid
        tools hold their pose at ``at_time``: relaxing at successive keyframe times load-steps them.

        ``increments`` > 1 relaxes in turn at evenly spaced times from the state's time to
        ``at_time`` (load stepping along the load curves: use it for large deformations, where
        applying everything at once can invert elements). Stops each increment when the relative
        out-of-balance force falls below ``tol``; raises :class:`ConvergenceError` if the last one
        does not within ``max_steps`` (unless ``strict=False``)."""
        self._same_model(state)
        strict = flag(strict, "strict")
        t_end = self.model.last_load_time if at_time is None else finite_number(at_time, "at_time", "s")
        if not as_real(tol) > 0:
            raise InputError(f"tol = {shown(tol)}; expected a relative residual > 0")
        if not 1 <= whole_number(increments, "increments") <= MAX_INCREMENTS:
            raise InputError(
                f"increments = {shown(increments)}; expected 1 to {MAX_INCREMENTS} "
                "(each is a whole relaxation)"
            )
        if not 1 <= whole_number(max_steps, "max_steps", " of steps") <= MAX_STEPS:
            raise InputError(f"max_steps = {shown(max_steps)}; expected 1 to {MAX_STEPS:.0e}")
        _check_every(check_every)
        steps = 0
        for t in np.linspace(state.time, t_end, int(increments) + 1)[1:]:
            rep = self._backend.relax(
                state._s, float(t), self.dt, float(tol), int(max_steps), int(check_every), self.size
            )
            self._ran()
            self._stepped_dt = None
            steps += int(rep["steps"])
            if rep["status"]:
                try:
                    self._raise(rep)
                except InstabilityError as e:
                    raise _in_relaxation(e, int(increments), bool(self.model.contact_pairs)) from None
        info = RelaxInfo(steps, float(rep["residual"]), rep["residual"] < tol, float(rep["damping"]))
        if self.model.tools:  # the equilibrium contact forces
            h = np.asarray(self._backend.tool_history())[0]
            self._relaxed = [(h[k, :3].copy(), h[k, 3:].copy()) for k in range(len(self.model.tools))]
        if self._pairs:
            hp = np.asarray(self._backend.pair_history())[0]
            for k, P in enumerate(self._pairs):
                P.relaxed = hp[k].copy()
        if strict and not info.converged:
            raise ConvergenceError(self._unconverged(info, tol))
        return info

    def _unconverged(self, info: RelaxInfo, tol: float) -> str:
        """What a relaxation that stopped short of ``tol`` says: where it stopped and the likely
        reason (a sheet nothing holds in its plane, float32's round-off, or the load or step)."""
        loose = _loose_sheet_node(self.model)
        if loose is not None:
            hint = (
                f"{_loose_words(loose)}, so the sheet has no unique rest shape: run it dynamically "
                "with damping, or give it an in-plane modulus"
            )
        elif self.model.dtype == np.float32 and info.residual < 1e-3:
            hint = "the float32 round-off floor: use float64 for tighter tolerances"
        else:
            hint = (
                "if the residual stays large, the material may stiffen beyond the "
                "small-strain modulus that sets the time step (lower the solver's dt or "
                "safety) or the load may need more increments"
            )
        return (
            f"dynamic relaxation reached residual {info.residual:.3g} after {info.steps} steps; "
            f"tolerance {tol:g}. It stops early when the residual no longer falls ({hint}); "
            "else raise max_steps or tol"
        )


def _loose_words(node: int) -> str:
    """The errors' words for a node _loose_sheet_node found."""
    return (
        f"node {node} lies on a sheet that only bends (in-plane modulus 0) and nothing else holds it "
        "in its plane"
    )


def _loose_sheet_node(model: Model) -> int | None:
    """A node (user id) of a sheet that only bends (membranes of in-plane modulus 0) that nothing
    else holds in its plane: on no tet and no stretching membrane, not held in all three directions;
    None where there is none."""
    sets = model._builder._membranes
    only = [F.ravel() for F, m in sets if m.wave_modulus == 0.0]
    if not only:
        return None
    held = np.zeros(model.n_nodes, bool)
    held |= np.asarray(model.constrained, bool).all(axis=1)
    held[model.tets.ravel()] = True
    for F, m in sets:
        held[F.ravel()] |= m.wave_modulus > 0.0
    loose = np.setdiff1d(np.concatenate(only), np.flatnonzero(held))
    return int(loose[0]) if loose.size else None


class Simulation:
    """Convenience wrapper: a model, a solver and the current state, with the solver's verbs.

    ``sim.step()``, ``sim.run(steps=n)`` or ``sim.run(until=T)``, ``sim.relax()``,
    ``sim.displacements``...
    """

    def __init__(self, model: Model, **solver_options):
        _check_model(model, "Simulation(model)")
        self.model = model
        self.solver = Solver(model, **solver_options)
        self.state = model.state()
        self.cutter: Any = None  # pliant.cutting.Cutter, once a blade was added

    def add_blade(self, blade, every: int = 10):
        """Cut with ``blade`` (pliant.cutting.Blade) while running: every ``every`` steps, the
        elements it swept separate (``self.model``, ``state`` and ``solver`` are then new objects
        over the new topology). Returns the blade."""
        from ..cutting import Cutter

        if self.cutter is None:
            self.cutter = Cutter([], every)
        return self.cutter.add(blade)

    def cut(self, triangles):
        """Cut now along the surface ``triangles`` [m] (K, 3, 3) of the current configuration
        (pliant.cutting.cut); returns the :class:`~pliant.cutting.Cut`."""
        from ..cutting import cut

        res = cut(self.state, triangles, self.solver)
        self.model, self.state, self.solver = res.model, res.state, res.solver
        return res

    @property
    def dt(self) -> float:
        """The time step Δt [s] of the solver."""
        return self.solver.dt

    def step(self, n: int | None = None) -> RunInfo:
        """One step of Δt (``step(n)``, n > 1, is deprecated: use ``run(steps=n)``)."""
        if n is not None and not (isinstance(n, (int, np.integer)) and not isinstance(n, bool) and n == 1):
            import warnings

            warnings.warn(
                "Simulation.step(n) is deprecated; use Simulation.run(steps=n)",
                DeprecationWarning,
                stacklevel=2,
            )
            return self.solver.run(self.state, steps=_step_count(n, "n"))
        return self.solver.run(self.state, steps=1)

    def run(self, steps: int | None = None, until: float | None = None) -> RunInfo:
        """Advance by ``steps`` steps or to time ``until`` [s] (Solver.run on the current state;
        with blades, a cut at each step count that is a multiple of ``cutter.every``: Cutter.run)."""
        if self.cutter is None or not self.cutter.blades:
            return self.solver.run(self.state, steps=steps, until=until)
        steps = self.solver.step_count(self.state, steps, until)
        n0 = self.state.steps
        self.solver, self.state = self.cutter.run(self.solver, self.state, steps)
        self.model = self.solver.model
        return RunInfo(self.state.steps - n0, self.state.time)

    def relax(self, **options) -> RelaxInfo:
        """Quasi-static equilibrium of the current state (Solver.relax; same options)."""
        return self.solver.relax(self.state, **options)

    def run_to(self, t: float) -> RunInfo:
        """Deprecated: ``run(until=t)``."""
        import warnings

        warnings.warn(
            "Simulation.run_to(t) is deprecated; use Simulation.run(until=t)",
            DeprecationWarning,
            stacklevel=2,
        )
        return self.run(until=t)

    def solve_static(self, **options) -> RelaxInfo:
        """Deprecated: ``relax(...)``."""
        import warnings

        warnings.warn(
            "Simulation.solve_static() is deprecated; use Simulation.relax()",
            DeprecationWarning,
            stacklevel=2,
        )
        return self.relax(**options)

    @property
    def time(self) -> float:
        return self.state.time

    @property
    def displacements(self) -> np.ndarray:
        return self.state.displacements

    @property
    def positions(self) -> np.ndarray:
        return self.state.positions

    @property
    def velocities(self) -> np.ndarray:
        return self.state.velocities

    def element_results(self) -> dict:
        return self.model.element_results(self.state)

    def kinetic_energy(self) -> float:
        return self.model.kinetic_energy(self.state)

    def strain_energy(self) -> float:
        return self.model.strain_energy(self.state)

    def set_tool_pose(self, k: int, position, rotation=(1.0, 0.0, 0.0, 0.0)):
        """Drive tool k from Python (a haptic device, a viewer): it moves from its current pose to
        this one, then stays. The move takes at least one step, and longer if needed to keep the
        tool's speed under 0.1 × the smallest element altitude per step (a sudden jump deeper than
        an element would invert it)."""
        tool = self.solver.tools[self.solver._tool_index(k)]
        tool.move_to(self.state.time, position, rotation, 0.1 * self.model.min_altitude, self.solver.dt)
        self.solver.set_tool_keys()

    def grasp(self, k: int = 0, reach: float | None = None):
        """Close tool k now: from the next step it holds the surface nodes within ``reach`` [m] of
        it (default: the tool's own :attr:`reach`) and moves them with it (RigidTool.grasp)."""
        self.solver.tools[self.solver._tool_index(k)].grasp(self.state.time, reach)
        self.solver.set_tool_keys()

    def release(self, k: int = 0):
        """Open tool k now: the nodes it holds are free from the next step."""
        self.solver.tools[self.solver._tool_index(k)].release(self.state.time)
        self.solver.set_tool_keys()

    def tool_force(self, k: int = 0):
        """(force [N], torque [N·m]) tool k received: ``contact_report().force(k)``."""
        return self.solver.tool_force(k)

    def contact_report(self) -> ContactReport:
        """The solver's :class:`ContactReport`."""
        return self.solver.contact_report()

    def save(self, path):
        self.state.save(path)

    def load(self, path):
        self.state.load(path)
