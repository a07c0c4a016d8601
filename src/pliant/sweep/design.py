"""Designs of experiments: which parameter values each run of a sweep gets.

- ``grid``: every combination of the parameters' values (the first parameter varies slowest).
- ``list``: the i-th values of all parameters together.
- ``lhs``: Latin hypercube sampling (McKay, Beckman & Conover 1979; scipy.stats.qmc).
- ``sobol``: scrambled Sobol' sequence (Sobol' 1967; Owen scrambling; scipy.stats.qmc).
- ``saltelli``: Saltelli's scheme for first-order and total Sobol indices (Saltelli 2002; Saltelli
  et al. 2010), N·(D + 2) runs from SALib, analysed by :mod:`pliant.sweep.analyze`.

Sampled designs draw on the unit hypercube and map each axis to its range, linearly or (scale
'log') log-uniformly. The same seed gives the same runs, bit for bit.
"""

from __future__ import annotations

import itertools
import math
import warnings
from typing import Any

import numpy as np

from .spec import Design, Parameter

__all__ = ["design_runs", "salib_problem"]


def _builtin(v: Any) -> Any:
    """Plain Python numbers (scene validation and TOML/JSON know no numpy scalars)."""
    if isinstance(v, np.integer):
        return int(v)
    if isinstance(v, np.floating):
        return float(v)
    return v


def _unit_to_range(u: np.ndarray, p: Parameter) -> np.ndarray:
    low, high = p.bounds
    if p.scale == "log":
        return np.exp(math.log(low) + u * (math.log(high) - math.log(low)))
    return low + u * (high - low)


def _qmc(kind: str, d: int, n: int, seed: int) -> np.ndarray:
    """n points of the unit hypercube [0, 1)^d, shape (n, d)."""
    from scipy.stats import qmc

    cls = qmc.LatinHypercube if kind == "lhs" else qmc.Sobol
    try:
        engine = cls(d=d, rng=seed)
    except TypeError:  # scipy < 1.15 names it seed
        engine = cls(d=d, seed=seed)
    with warnings.catch_warnings():  # Sobol' balance warning for n not a power of 2: documented
        warnings.simplefilter("ignore", UserWarning)
        return engine.random(n)


def salib_problem(parameters: list[Parameter]) -> dict:
    """SALib's problem description: the parameters and their bounds in the sampled space
    (the logarithm's for a log scale)."""
    return {
        "num_vars": len(parameters),
        "names": [p.key for p in parameters],
        "bounds": [
            [math.log(p.bounds[0]), math.log(p.bounds[1])] if p.scale == "log" else list(p.bounds)
            for p in parameters
        ],
    }


def _saltelli(parameters: list[Parameter], design: Design) -> np.ndarray:
    from SALib.sample import sobol as salib_sobol

    X = salib_sobol.sample(
        salib_problem(parameters), design.samples, calc_second_order=False, seed=design.seed
    )
    for j, p in enumerate(parameters):
        if p.scale == "log":
            X[:, j] = np.exp(X[:, j])
    return X


def design_runs(params: list[Parameter], d: Design) -> list[dict[str, Any]]:
    """The runs of a sweep of ``params`` by design ``d``, in order: a dict key path → value each."""
    keys = [p.key for p in params]
    rows: Any
    if d.type == "grid":
        rows = itertools.product(*(p.choices for p in params))
    elif d.type == "list":
        rows = zip(*(p.choices for p in params))
    elif d.type == "saltelli":
        rows = _saltelli(params, d)
    else:
        U = _qmc(d.type, len(params), d.samples, d.seed)
        rows = np.column_stack([_unit_to_range(U[:, j], p) for j, p in enumerate(params)])
    return [{k: _builtin(v) for k, v in zip(keys, row)} for row in rows]
