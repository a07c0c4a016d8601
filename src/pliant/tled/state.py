"""State (per step) of a Model: displacements, time and step, in the user's node numbering; saved
to and restored from .npz files."""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..checks import as_real, shown
from ..errors import InputError

if TYPE_CHECKING:
    from .model import Model

__all__ = ["State"]


class State:
    """Per-step state: displacement u [m] and the previous step's u⁻, time t [s], last step Δt [s].

    ``displacements``, ``positions``, ``velocities`` are (N, 3) float64 copies in user order;
    ``velocities`` is the half-step velocity (u − u⁻)/Δt [m/s].
    """

    def __init__(self, model: Model, core_state):
        self.model = model
        self._s = core_state

    @property
    def time(self) -> float:
        """Time t [s]: after a run, t_epoch + (steps − step_epoch) Δt on the state's run clock, so
        that however a run is split its steps meet their loads at the same times."""
        return float(self._s.t)

    @time.setter
    def time(self, t: float):
        """Set the time [s] (a finite number); the run clock restarts here."""
        value = as_real(t)
        if not math.isfinite(value):
            raise InputError(f"State.time = {shown(t)}; expected a finite time [s]")
        self._s.t = value

    @property
    def dt(self) -> float:
        return float(self._s.dt)

    def _clock_times(self, steps):
        """Times [s] of step counts ``steps`` (an int or an array) on the run clock, t_epoch +
        (steps − step_epoch) Δt; a count before the epoch (Δt set since) gives the epoch's time."""
        t_epoch, step_epoch = self._s.epoch
        return t_epoch + np.maximum(np.asarray(steps) - step_epoch, 0) * self.dt

    @property
    def steps(self) -> int:
        return int(self._s.step)

    @property
    def displacements(self) -> np.ndarray:
        return self.model.to_user_nodes(np.asarray(self._s.get_u(), dtype=float))

    @property
    def positions(self) -> np.ndarray:
        return self.model.reference_positions + self.displacements

    @property
    def held(self) -> dict[int, int]:
        """The nodes grasped now: user node → the tool holding it."""
        tool = np.asarray(self._s.get_grip()[0])
        nodes = self.model._contact_engine
        return {int(nodes[i]): int(tool[i]) for i in np.nonzero(tool >= 0)[0]}

    @property
    def velocities(self) -> np.ndarray:
        if self._s.dt <= 0:
            return np.zeros((self.model.n_nodes, 3))
        # The increment the next step uses (State::du: free of the rounding of u).
        return self.model.to_user_nodes(np.asarray(self._s.get_du(), dtype=float)) / self._s.dt

    def _check(self, a, name) -> np.ndarray:
        """A finite (N, 3) array in user order, or InputError saying what is wrong with it."""
        try:
            a = np.asarray(a, dtype=float)
        except (TypeError, ValueError) as e:
            raise InputError(f"{name}: expected numbers of shape ({self.model.n_nodes}, 3); {e}") from None
        if a.shape != (self.model.n_nodes, 3):
            raise InputError(f"{name}: expected shape ({self.model.n_nodes}, 3), got {a.shape}")
        bad = np.argwhere(~np.isfinite(a))
        if bad.size:
            i = int(bad[0, 0])
            raise InputError(
                f"{name}: {len(bad)} non-finite value(s), first at node {i}: "
                f"{a[i].tolist()}; expected finite values"
            )
        return a

    def set_displacements(self, u, velocities=None, dt: float | None = None):
        """Set u [m] (N, 3) and optionally the velocity [m/s] (N, 3) for steps of Δt [s]."""
        u = self._check(u, "displacements")
        self._s.set_u(self.model.to_engine_nodes(u))
        if velocities is None:
            self._s.set_u_prev(self.model.to_engine_nodes(u))
        else:
            if dt is None or not dt > 0:
                raise InputError("set_displacements: a velocity needs the time step dt > 0 [s]")
            v = self._check(velocities, "velocities")
            self._s.set_u_prev(self.model.to_engine_nodes(u - v * dt))
            self._s.dt = float(dt)

    def copy(self) -> "State":
        return State(self.model, self._s.copy())

    def assign(self, other: "State"):
        """Copy another state of the same model into this one."""
        self._s.assign(other._s)

    def save(self, path):
        """Save to a .npz file (u, u⁻ and the last increment in user order, t, Δt, step count, the
        run clock, the model's fingerprint), atomically. ``.npz`` is appended to a name without it."""
        from ..io.files import atomic_write, check_output_file

        path = check_output_file(path, "state file")  # first: "/tmp" was saved as /tmp.npz
        if path.suffix != ".npz":
            path = check_output_file(path.with_name(path.name + ".npz"), "state file")
        u_prev = self.model.to_user_nodes(np.asarray(self._s.get_u_prev(), dtype=float))
        du = self.model.to_user_nodes(np.asarray(self._s.get_du(), dtype=float))
        data = dict(
            u=self.displacements,
            u_prev=u_prev,
            du=du,  # the last increment before rounding: the same bits after a restore
            t=self.time,
            dt=self.dt,
            step=self.steps,
            n_nodes=self.model.n_nodes,
            n_elements=self.model.n_elements,
            fingerprint=self.model.fingerprint,
            visco=np.asarray(self._s.get_q(), dtype=float),
            grip_tool=np.asarray(self._s.get_grip()[0]),
            grip_at=np.asarray(self._s.get_grip()[1]),
            # the run clock (time = t_epoch + (step − step_epoch) dt): a restored run meets its
            # curves at the times of the run it continues, to the bit
            t_epoch=self._s.epoch[0],
            step_epoch=self._s.epoch[1],
        )  # engine layout, same model
        atomic_write(path, lambda tmp: np.savez(tmp, **data), "state file")

    def _set_grip(self, path: Path, tool: np.ndarray, at: np.ndarray) -> None:
        """A saved grasp state: per contact node the tool holding it (−1: none; whole numbers below
        the model's tool count) and where it is held (finite positions [m])."""
        n = len(self.model.tools)
        try:
            held = np.asarray(tool, dtype=np.float64).ravel()
            where = np.asarray(at, dtype=np.float64).ravel()
        except (TypeError, ValueError) as e:
            raise InputError(f"{path}: grip state: {e}") from None
        if not (
            np.all(held == np.round(held)) and np.all((held >= -1) & (held < n)) and np.isfinite(where).all()
        ):
            raise InputError(
                f"{path}: grip state holds tool numbers outside -1..{n - 1} (this model has {n} tools) or "
                "non-finite positions: not a state of this model"
            )
        try:
            self._s.set_grip(held.astype(np.int32).tolist(), where.tolist())
        except (TypeError, ValueError) as e:
            raise InputError(f"{path}: {e}") from None

    @staticmethod
    def _epoch(path: Path, t_epoch, step_epoch, step: int) -> tuple[float, int]:
        """A saved run clock (its epoch's time [s] and step): finite, a whole step from 0 to the
        state's own step count."""
        try:
            t0, k0 = float(t_epoch), float(step_epoch)
        except (TypeError, ValueError) as e:
            raise InputError(f"{path}: run clock: {e}") from None
        if not (math.isfinite(t0) and k0 == round(k0) and 0 <= k0 <= step):
            raise InputError(
                f"{path}: run clock t_epoch = {t0}, step_epoch = {k0}; expected a finite time and a "
                f"whole step from 0 to the state's step {step}"
            )
        return t0, int(k0)

    def load(self, path):
        """Restore from a file written by :meth:`save` of the same model. A missing, corrupt,
        truncated or foreign file, or one saved from another model, raises InputError naming it."""
        from ..io.files import file_problem

        path = Path(path)
        problem = file_problem(path)
        if problem:
            raise InputError(f"{path}: {'no such state file' if problem == 'no such file' else problem}")
        try:
            with np.load(path, allow_pickle=False) as d:
                data = {k: d[k] for k in d.files}
        except Exception as e:  # zip, zlib, format and OS errors alike
            raise InputError(
                f"{path}: not a readable pliant state file ({type(e).__name__}: {str(e)[:200]})"
            ) from None
        missing = [k for k in ("u", "u_prev", "t", "dt", "step", "n_nodes", "n_elements") if k not in data]
        if missing:
            raise InputError(f"{path}: not a pliant state file (no {', '.join(missing)})")
        try:
            nn, ne = int(data["n_nodes"]), int(data["n_elements"])
            t, dt, step = float(data["t"]), float(data["dt"]), int(data["step"])
        except (TypeError, ValueError) as e:
            raise InputError(f"{path}: not a pliant state file ({e})") from None
        if nn != self.model.n_nodes or ne != self.model.n_elements:
            raise InputError(
                f"{path}: state of a model with {nn} nodes / {ne} elements; this model "
                f"has {self.model.n_nodes} / {self.model.n_elements}"
            )
        fp = str(data["fingerprint"]) if "fingerprint" in data else None
        if fp is not None and fp != self.model.fingerprint:
            raise InputError(
                f"{path}: state saved from a different model (same sizes, different "
                f"mesh, materials or constraints: fingerprint {fp}, this model "
                f"{self.model.fingerprint})"
            )
        if not (np.isfinite(t) and np.isfinite(dt) and dt >= 0 and step >= 0):
            raise InputError(
                f"{path}: bad time data t = {t}, dt = {dt}, step = {step}; expected "
                "finite t, dt >= 0 and step >= 0"
            )
        saved_clock = "t_epoch" in data and "step_epoch" in data
        epoch = self._epoch(path, data["t_epoch"], data["step_epoch"], step) if saved_clock else None
        u = self.model.to_engine_nodes(self._check(data["u"], f"{path}: u"))
        u_prev = self.model.to_engine_nodes(self._check(data["u_prev"], f"{path}: u_prev"))
        if "visco" in data:
            try:
                self._s.set_q(data["visco"].ravel().tolist())
            except (TypeError, ValueError) as e:
                raise InputError(f"{path}: {e}") from None
        if "grip_tool" in data and "grip_at" in data:
            self._set_grip(path, data["grip_tool"], data["grip_at"])
        du = self.model.to_engine_nodes(self._check(data["du"], f"{path}: du")) if "du" in data else None
        self._s.set_u(u)
        self._s.set_u_prev(u_prev)  # and the increment u − u⁻ (files saved before it was kept)
        if du is not None:
            self._s.set_du(du)
        self._s.t, self._s.dt, self._s.step = t, dt, step  # the clock restarts here, unless saved:
        if epoch is not None:
            self._s.epoch = epoch
