"""Load curves: dimensionless factors of time that scale loads and prescribed displacements.

The evaluation itself is the engine's ``curve_value`` (``cpp/include/pliant/tled.hpp``); these
classes only validate and describe. Times in seconds.
"""

from __future__ import annotations

import math

import numpy as np

from .. import _core
from ..checks import as_real, real_array, shown
from ..errors import InputError

K = _core.CurveKind

__all__ = ["LoadCurve", "Constant", "Step", "Ramp", "SmoothRamp", "Hilly", "Table"]


class LoadCurve:
    kind: _core.CurveKind = K.Constant
    t0 = 0.0
    t1 = 0.0
    times: tuple = ()
    values: tuple = ()

    @property
    def end_time(self) -> float:
        """Time [s] from which the curve stays at its final value."""
        return 0.0

    def _key(self):
        return (self.kind, self.t0, self.t1, self.times, self.values)

    def __eq__(self, other):
        return isinstance(other, LoadCurve) and self._key() == other._key()

    def __hash__(self):
        return hash(self._key())

    def __call__(self, t):
        """Factor at time(s) t [s] (a NumPy mirror of the engine's curve_value, for plotting)."""
        t = np.asarray(t, dtype=float)
        if self.kind == K.Constant:
            return np.ones_like(t)
        if self.kind == K.Step:
            return (t >= self.t0).astype(float)
        if self.kind in (K.Ramp, K.SmoothRamp, K.Hilly):
            tau = np.clip((t - self.t0) / (self.t1 - self.t0), 0.0, 1.0)
            if self.kind == K.Hilly:
                return tau * np.exp(np.cos(4 * np.pi * tau) - 1)
            return tau if self.kind == K.Ramp else tau**3 * (10 - 15 * tau + 6 * tau**2)
        return np.interp(t, self.times, self.values)


def _time(name, v, cls):
    """``v`` as a finite time [s]; a bool or a string is not one (float() made True 1 s)."""
    t = as_real(v)
    if not math.isfinite(t):
        raise InputError(f"{cls}: {name} = {shown(v)}; expected a finite time [s]")
    return t


class Constant(LoadCurve):
    """Factor 1 at all times."""

    kind = K.Constant

    def __repr__(self):
        return "Constant()"


class Step(LoadCurve):
    """0 before t0 [s], 1 from t0 on."""

    kind = K.Step

    def __init__(self, t0: float = 0.0):
        self.t0 = _time("t0", t0, "Step")

    @property
    def end_time(self):
        return self.t0

    def __repr__(self):
        return f"Step(t0={self.t0:g})"


class Ramp(LoadCurve):
    """Linear from 0 at t0 to 1 at t1 [s], then held (NiftySim's RAMP with t0 = 0)."""

    kind = K.Ramp

    def __init__(self, t1: float, t0: float = 0.0):
        self.t0, self.t1 = _time("t0", t0, type(self).__name__), _time("t1", t1, type(self).__name__)
        if not self.t1 > self.t0:
            raise InputError(f"{type(self).__name__}: t1 = {shown(t1)} must be later than t0 = {shown(t0)}")

    @property
    def end_time(self):
        return self.t1

    def __repr__(self):
        return f"{type(self).__name__}(t1={self.t1:g}, t0={self.t0:g})"


class SmoothRamp(Ramp):
    """10τ³ − 15τ⁴ + 6τ⁵ with τ = (t − t0)/(t1 − t0): zero velocity and acceleration at both ends
    (NiftySim's POLY345)."""

    kind = K.SmoothRamp


class Hilly(Ramp):
    """τ exp(cos(4πτ) − 1) with τ = (t − t0)/(t1 − t0): a peaky curve (NiftySim's HILLY)."""

    kind = K.Hilly


class Table(LoadCurve):
    """Piecewise linear through (times [s], values), held constant outside."""

    kind = K.Table

    def __init__(self, times, values):
        t, v = real_array(times), real_array(values)
        for name, given, a in (("times", times, t), ("values", values, v)):
            if a is None or a.ndim > 1:  # booleans, strings, nested lists were made numbers
                raise InputError(f"Table: {name} = {shown(given)}; expected a list of numbers")
        assert t is not None and v is not None
        t, v = t.ravel(), v.ravel()
        if t.size < 1 or t.size != v.size:
            raise InputError(f"Table: {t.size} times and {v.size} values; expected equal, >= 1")
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(v))):
            raise InputError("Table: times and values must be finite")
        if np.any(np.diff(t) <= 0):
            k = int(np.argmax(np.diff(t) <= 0))
            raise InputError(
                f"Table: times must increase strictly; times[{k + 1}] = {t[k + 1]:g} <= times[{k}] = {t[k]:g}"
            )
        self.times, self.values = tuple(t.tolist()), tuple(v.tolist())

    @property
    def end_time(self):
        return self.times[-1]

    def __repr__(self):
        return f"Table(times={list(self.times)}, values={list(self.values)})"
