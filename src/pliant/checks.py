"""Checks of values users pass to the API: each returns the value in its canonical type or raises
:class:`~pliant.errors.InputError` naming the argument and what was expected."""

from __future__ import annotations

import math

import numpy as np

from .errors import InputError, MeshError


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


def whole_number(value, what: str, of: str = "") -> int:
    """``value`` as an int: an integer or a float without a fraction, not a bool; InputError naming
    ``what`` otherwise (``of``: what it counts, for the message: " of steps")."""
    if (
        isinstance(value, (bool, np.bool_))
        or not isinstance(value, (int, np.integer, float, np.floating))
        or (isinstance(value, (float, np.floating)) and not float(value).is_integer())
    ):
        raise InputError(f"{what} = {shown(value)}; expected a whole number{of}")
    return int(value)


def flag(value, what: str) -> bool:
    """``value`` as a bool where it is one (a Python or numpy bool, or the integers 0 and 1);
    InputError naming ``what`` otherwise: bool() made the string "false" True, and an array raised
    numpy's "truth value of an array is ambiguous" naming no argument."""
    if isinstance(value, np.ndarray) and value.ndim == 0:
        value = value[()]
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)) and value in (0, 1):
        return bool(value)
    raise InputError(f"{what} = {shown(value)}; expected True or False")


def mesh_arrays(
    nodes, cells, corners: int, who: str, cell: str = "element", empty: bool = False
) -> tuple[np.ndarray, np.ndarray]:
    """Nodes [m] (N, 3), N >= 1, finite, and cells (M, corners) of node indices 0 <= i < N (integers
    or floats without a fraction; M = 0 only where ``empty``), as float and int64 arrays; MeshError
    naming ``who`` (the file or the call) and the culprit (the shape, the node, the ``cell`` and its
    index) otherwise."""
    try:
        X, C = real_array(nodes), np.asarray(cells)
    except (TypeError, ValueError):  # ragged cells
        X = None
    if X is None:
        raise MeshError(f"{who}: nodes (N, 3) and {cell}s (M, {corners}) must be numeric arrays") from None
    if X.ndim != 2 or X.shape[1] != 3 or X.shape[0] == 0:
        raise MeshError(f"{who}: nodes have shape {X.shape}; expected (N, 3) with N >= 1")
    if not np.all(np.isfinite(X)):
        node = int(np.argwhere(~np.isfinite(X))[0, 0])
        raise MeshError(f"{who}: node {node} has a non-finite coordinate {X[node].tolist()}")
    if C.size == 0 and empty:
        return X, np.zeros((0, corners), np.int64)
    if C.ndim != 2 or C.shape[1] != corners or C.shape[0] == 0:
        raise MeshError(f"{who}: {cell}s have shape {C.shape}; expected (M, {corners}) with M >= 1")
    if C.dtype.kind not in "iuf":
        raise MeshError(f"{who}: {cell} indices of type {C.dtype}; expected integers")
    if C.dtype.kind == "f":
        if not np.all(np.isfinite(C)) or not np.all(np.equal(np.mod(C, 1), 0)):
            raise MeshError(f"{who}: {cell} indices must be integers")
    bad = np.argwhere((C < 0) | (C >= X.shape[0]))
    if bad.size:
        k = int(bad[0, 0])
        raise MeshError(
            f"{who}: {cell} {k} has node index {shown(C[k, bad[0, 1]])}; expected 0 <= index < {X.shape[0]}"
        )
    return X, C.astype(np.int64)


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
