"""A haptic-rate force loop: the simulation runs in its own thread, a haptic device reads the tool
force and writes the tool pose at its own rate (1 kHz and more) through a small thread-safe API::

    loop = pl.haptics.HapticLoop(sim, tool=0)
    with loop:                                   # starts the simulation thread
        while device.running():                  # the device's own 1 kHz servo loop
            loop.write_pose(device.position())   # [m], the tool follows (speed-limited)
            device.set_force(loop.read_force())  # [N], continuous, passive

Between simulation updates the force is interpolated: each new simulated force is reached by a
linear ramp from the force being rendered, over one update period, so the rendered force is
continuous whatever the two rates (it lags the simulation by one update). Interpolation and the
simulation's own update delay can make the coupling create energy (a delayed spring is active);
a time-domain passivity observer and controller (Hannaford & Ryu, "Time-domain passivity control
of haptic interfaces", IEEE Trans. Robotics and Automation 18(1), 2002, eqs. 6-9) measures the
energy the virtual environment has absorbed through the device port, W = −Σ f·v Δt, and when W
turns negative adds a damping force −α v with α = −W / (‖v‖² Δt), which returns W to zero (at
most the size of the rendered force per read, so that a tiny motion never asks for a large force).

Units: positions [m], forces [N], times [s]. docs/haptics.md shows how to connect a device
library (Force Dimension SDK, OpenHaptics, CHAI3D); :class:`VirtualDevice` is a scripted device for
tests and demonstrations.
"""

from __future__ import annotations

import math
import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .errors import InputError
from .checks import as_real, finite_number, finite_vector, flag, shown
from .tled import Simulation

__all__ = ["HapticLoop", "VirtualDevice", "DeviceLog"]


class HapticLoop:
    """Runs ``sim`` in a thread of its own and serves tool ``tool`` to a haptic device.

    update_period: simulated time [s] per update (the steps between two force samples, at least
    one step); realtime: pace the simulation to the wall clock (otherwise as fast as it runs);
    max_force: the device's force limit [N] (the rendered force is clipped to it); passivity:
    the passivity controller on (recommended; the observer, ``port_energy``, runs either way).
    The simulation object belongs to the loop's thread while it runs: touch it only through this
    API until :meth:`stop`.
    """

    def __init__(
        self,
        sim: Simulation,
        tool: int = 0,
        update_period: float = 1e-3,
        realtime: bool = True,
        max_force: float = math.inf,
        passivity: bool = True,
    ):
        if not isinstance(sim, Simulation):
            raise InputError(f"HapticLoop(sim): got {type(sim).__name__}; expected a pliant Simulation")
        self.sim, self.tool = sim, sim.solver._tool_index(tool)
        period = finite_number(update_period, "update_period", "s")
        if not period > 0:
            raise InputError(f"update_period = {shown(update_period)}; expected > 0 [s]")
        self.steps_per_update = max(1, round(period / sim.dt))
        self.realtime, self.passivity = flag(realtime, "realtime"), flag(passivity, "passivity")
        self.max_force = as_real(max_force)  # inf (no limit) allowed; NaN for what is no number
        if not self.max_force > 0:
            raise InputError(f"max_force = {shown(max_force)}; expected a force > 0 [N] (inf: no limit)")
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._error: BaseException | None = None
        self._pose: tuple[np.ndarray, tuple] | None = None
        self._pose_new = False
        # The rendered force: a ramp from `_from` at wall time `_t0` to `_to` over `_span` seconds.
        self._from = np.zeros(3)
        self._to = np.zeros(3)
        self._t0, self._span = 0.0, 1.0
        self._last_sample_wall: float | None = None
        self._updates = 0
        self._sim_time = sim.time
        self._wall_start = 0.0
        self._sim_start = sim.time
        # Passivity observer: device positions and the force rendered since the last read.
        self._x_prev: np.ndarray | None = None
        self._last_dx: np.ndarray | None = None
        self._f_prev = np.zeros(3)
        self.port_energy = 0.0  # W [J]: energy the environment absorbed through the port
        # The latest published samples (wall time [s], simulated time [s], force [N] (3,)).
        self.samples: deque[tuple[float, float, np.ndarray]] = deque(maxlen=100_000)

    # --- the simulation thread ---------------------------------------------------------------
    def start(self) -> HapticLoop:
        """Start the simulation thread (once)."""
        if self._thread is not None:
            raise InputError("HapticLoop.start: already started")
        self._wall_start, self._sim_start = time.perf_counter(), self.sim.time
        self._thread = threading.Thread(target=self._run, name="pliant-haptics", daemon=True)
        self._thread.start()
        return self

    def stop(self) -> None:
        """Stop the simulation thread and wait for it; re-raise its error if it failed."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join()
        if self._error is not None:
            raise self._error

    def __enter__(self) -> HapticLoop:
        return self.start()

    def __exit__(self, *exc) -> None:
        self.stop()

    def _run(self) -> None:
        try:
            while not self._stop.is_set():
                self._apply_pose()
                self.sim.run(steps=self.steps_per_update)
                force, _ = self.sim.tool_force(self.tool)
                self._publish(force, self.sim.time)
                self._pace()
        except BaseException as e:  # handed to the caller by stop() and `error`
            self._error = e

    def _apply_pose(self) -> None:
        with self._lock:
            pose, self._pose_new = (self._pose if self._pose_new else None), False
        if pose is not None:
            self.sim.set_tool_pose(self.tool, pose[0], pose[1])

    def _publish(self, force: np.ndarray, sim_time: float) -> None:
        """A new simulated force: ramp to it from the force rendered now, over one update."""
        now = time.perf_counter()
        with self._lock:
            if self._last_sample_wall is not None:
                self._span = max(now - self._last_sample_wall, 1e-6)
            self._from = self._render(now)
            self._to, self._t0 = np.array(force, dtype=float), now
            self._last_sample_wall = now
            self._updates += 1
            self._sim_time = sim_time
            self.samples.append((now, sim_time, self._to))

    def _pace(self) -> None:
        if self.realtime:
            ahead = (self.sim.time - self._sim_start) - (time.perf_counter() - self._wall_start)
            if ahead > 0:
                self._stop.wait(ahead)

    def _render(self, now: float) -> np.ndarray:
        a = min(1.0, max(0.0, (now - self._t0) / self._span))
        return self._from + a * (self._to - self._from)

    # --- the device side ------------------------------------------------------------------------
    def write_pose(self, position, rotation=(1.0, 0.0, 0.0, 0.0)) -> None:
        """The device's pose: position [m] (3,), rotation as a unit quaternion (w, x, y, z). The
        latest one wins; the tool moves to it at a speed the stable step allows."""
        p = finite_vector(position, 3, "write_pose: position", "m")
        q = tuple(finite_vector(rotation, 4, "write_pose: rotation", ""))
        with self._lock:
            self._pose, self._pose_new = (p, q), True
            self._observe(p)

    def _observe(self, x: np.ndarray) -> None:
        """Passivity observer: the energy absorbed since the last pose, with the force rendered."""
        if self._x_prev is not None:
            self._last_dx = x - self._x_prev
            self.port_energy -= float(self._f_prev @ self._last_dx)
        self._x_prev = x

    def read_force(self) -> np.ndarray:
        """The force [N] (3,) to render on the device now: the simulated tool force, interpolated,
        passivity-controlled and clipped to ``max_force``."""
        now = time.perf_counter()
        with self._lock:
            f = self._render(now)
            if self.passivity:
                c = self._passivity_damping()
                # At most the rendered force's size: a tiny motion never asks for a large force
                # (the rest of −W is dissipated over the following reads).
                size, limit = float(np.linalg.norm(c)), float(np.linalg.norm(f))
                f = f + (c * (limit / size) if size > limit else c)
            self._f_prev = f
        norm = float(np.linalg.norm(f))
        return f * (self.max_force / norm) if norm > self.max_force else f

    def _passivity_damping(self) -> np.ndarray:
        """Passivity controller: when the observed energy W is negative, a damping force along the
        device's last displacement that dissipates −W over it (Hannaford & Ryu 2002, eq. 9)."""
        if self.port_energy >= 0 or self._last_dx is None:
            return np.zeros(3)
        dx = self._last_dx
        d2 = float(dx @ dx)
        if d2 == 0.0:
            return np.zeros(3)
        # W < 0: against the motion; the observer books its work at the next pose.
        return self.port_energy / d2 * dx

    # --- status ---------------------------------------------------------------------------------
    @property
    def updates(self) -> int:
        """Simulation updates published so far."""
        return self._updates

    @property
    def sim_time(self) -> float:
        """Simulated time [s] of the latest published force."""
        return self._sim_time

    @property
    def real_time_factor(self) -> float:
        """Simulated seconds per wall second since start (1 when paced and keeping up)."""
        wall = time.perf_counter() - self._wall_start
        return (self._sim_time - self._sim_start) / wall if wall > 0 else 0.0

    @property
    def error(self) -> BaseException | None:
        """The simulation thread's error, if it stopped on one."""
        return self._error


MAX_RATE = 1e6  # [Hz] a VirtualDevice's most reads a second
MAX_READS = 1e8  # a VirtualDevice run's most reads (its log: 5.6 GB)


class VirtualDevice:
    """A scripted haptic device for tests and demonstrations: a thread that, ``rate`` times per
    second [Hz], writes the pose ``path(t)`` [m] and reads the force, as a device's servo loop
    does. Its k-th tick writes ``path(k / rate)`` (the script's own clock, t [s] since start), so
    every step is the script's step; a tick the machine delays runs late, never skipped and never
    a larger step (a loaded machine then shows as late reads, not as a faster hand)."""

    def __init__(self, loop: HapticLoop, path: Callable[[float], object], rate: float = 1000.0):
        self.loop, self.path = loop, path
        self.rate = finite_number(rate, "rate", "Hz")
        # A servo loop's rate: at least one read a second (the run's last read waits a period), at
        # most MAX_RATE (haptic devices serve 1–10 kHz).
        if not 1.0 <= self.rate <= MAX_RATE:
            raise InputError(f"rate = {shown(rate)}; expected 1 to {MAX_RATE:g} reads a second [Hz]")

    def run(self, duration: float) -> DeviceLog:
        """Serve the device for ``duration`` [s] of wall time (reads at k / rate, k = 0, 1, ...)."""
        duration = finite_number(duration, "duration", "s")
        reads = duration * self.rate
        if not 0 <= reads <= MAX_READS:  # the log keeps 7 numbers a read
            raise InputError(
                f"duration = {shown(duration)} s; expected >= 0 and at most {MAX_READS:.0e} reads "
                f"({MAX_READS / self.rate:.3g} s at {self.rate:g} Hz)"
            )
        n = math.ceil(reads)
        times, forces, energy = np.zeros(n), np.zeros((n, 3)), np.zeros(n)
        start = time.perf_counter()
        for k in range(n):
            wait = k / self.rate - (time.perf_counter() - start)
            if wait > 0:
                time.sleep(wait)
            now = time.perf_counter() - start
            self.loop.write_pose(self.path(k / self.rate))
            forces[k] = self.loop.read_force()
            times[k], energy[k] = now, self.loop.port_energy
        rest = n / self.rate - (time.perf_counter() - start)  # the last read's period
        if rest > 0:
            time.sleep(rest)
        return DeviceLog(times, forces, energy, time.perf_counter() - start)


@dataclass
class DeviceLog:
    """What a :class:`VirtualDevice` saw: read times [s] (n,), forces [N] (n, 3), the passivity
    observer's port energy after each read [J] (n,), and the wall time the run took [s]."""

    times: np.ndarray
    forces: np.ndarray
    port_energy: np.ndarray
    elapsed: float

    @property
    def reads_per_second(self) -> float:
        return len(self.times) / self.elapsed
