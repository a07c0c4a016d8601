"""Checks of values users pass to the API: each returns the value in its canonical type or raises
:class:`~pliant.errors.InputError` naming the argument and what was expected."""

from __future__ import annotations

import math

import numpy as np

from .errors import InputError


def as_real(value) -> float:
    """``value`` as a float where it is a real number (int, float, a numpy scalar or 0-d array);
    NaN for anything else (a bool, a string, None, a list), so that the caller's finiteness check
    refuses it with its own message (float() made True 1.0 and '5' 5.0 silently, and raised
    TypeError or ValueError naming no argument for None or 'abc')."""
    if isinstance(value, np.ndarray) and value.ndim == 0:
        value = value[()]
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
        return math.nan
    return float(value)


def finite_number(value, what: str, unit: str = "") -> float:
    """``value`` as a finite float ("until = nan; expected a finite number [s]")."""
    try:
        x = float(value)
    except (TypeError, ValueError, OverflowError):
        x = None
    if x is None or not math.isfinite(x):
        raise InputError(f"{what} = {shown(value)}; expected a finite number{f' [{unit}]' if unit else ''}")
    return x


def finite_vector(value, n: int, what: str, unit: str = "") -> np.ndarray:
    """``value`` as a float array of shape (n,) with finite entries."""
    try:
        a = np.asarray(value, dtype=float).ravel()
    except (TypeError, ValueError):
        a = None
    if a is None or a.shape != (n,) or not np.all(np.isfinite(a)):
        raise InputError(
            f"{what} = {shown(value)}; expected {n} finite numbers{f' [{unit}]' if unit else ''}"
        )
    return a


def shown(value, limit: int = 80) -> str:
    """A value as an error message shows it: numpy scalars and arrays as plain Python numbers and
    lists (never 'np.float64(nan)' or 'array([...])'), cut to ``limit`` characters."""
    if isinstance(value, (np.ndarray, np.generic)):
        value = value.tolist()
    r = repr(value)
    return r if len(r) <= limit else r[:limit] + f"... ({len(r)} characters)"
