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


def as_index(value) -> int:
    """``value`` as an int where it is an integer (int or a numpy integer; not a bool); raises
    ValueError otherwise (int() made 1.7 one and True one)."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        raise ValueError(f"{value!r} is not an integer")
    return int(value)


def real_array(value) -> np.ndarray | None:
    """``value`` as a float array where every entry is a real number; None for anything else (bools,
    strings, ragged or nested objects): np.asarray(value, float) made True 1.0 and '1' 1.0."""
    try:
        a = np.asarray(value)
    except (TypeError, ValueError):
        return None
    if a.dtype.kind not in "iuf":
        return None
    if not isinstance(value, np.ndarray) and _has_bool(value):
        return None  # numpy made (True, 0, 0) integers and (True, 0.5) floats
    return a.astype(float)


def _has_bool(value) -> bool:
    """Whether a (nested) sequence holds a bool anywhere."""
    entries = np.asarray(value, dtype=object).ravel()
    return any(isinstance(x, (bool, np.bool_)) for x in entries)


def finite_number(value, what: str, unit: str = "") -> float:
    """``value`` as a finite float ("until = nan; expected a finite number [s]"); a bool or a string
    is not a number (as_real)."""
    x = as_real(value)
    if not math.isfinite(x):
        raise InputError(f"{what} = {shown(value)}; expected a finite number{f' [{unit}]' if unit else ''}")
    return x


def finite_vector(value, n: int, what: str, unit: str = "") -> np.ndarray:
    """``value`` as a float array of shape (n,) with finite entries (numbers: no bools or strings)."""
    a = real_array(value)
    a = None if a is None else a.ravel()
    if a is None or a.shape != (n,) or not np.all(np.isfinite(a)):
        raise InputError(
            f"{what} = {shown(value)}; expected {n} finite numbers{f' [{unit}]' if unit else ''}"
        )
    return a


def described(value) -> str:
    """``value`` for a message about its shape: shown, with its shape where it is numeric
    ("[1.0, 2.0] (shape (2,))", "'up'")."""
    a = real_array(value)
    return shown(value) if a is None else f"{shown(value)} (shape {a.shape})"


def shown(value, limit: int = 80) -> str:
    """A value as an error message shows it: numpy scalars and arrays as plain Python numbers and
    lists (never 'np.float64(nan)' or 'array([...])'), cut to ``limit`` characters."""
    if isinstance(value, (np.ndarray, np.generic)):
        value = value.tolist()
    r = repr(value)
    return r if len(r) <= limit else r[:limit] + f"... ({len(r)} characters)"
