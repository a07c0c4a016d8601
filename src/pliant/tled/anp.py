"""The stabilization of average nodal pressure tetrahedra (T4ANP) as a setting: what
``ModelBuilder.nodal_pressure_stabilization`` and scenes' ``solver.nodal_pressure_stabilization``
accept, and its default (docs/engine.md, "Volume modes and the stabilization")."""

from __future__ import annotations

import math
import numbers

from ..checks import shown
from ..errors import InputError

__all__ = ["ANP_STABILIZATION", "anp_stabilization"]

# Default T4ANP stabilization (docs/engine.md, "Volume modes and the stabilization"): none, plain
# T4ANP. Any mix of the element's own pressure costs bending accuracy on coarse meshes ("shear":
# the ν = 0.49 cantilever at 2 elements through the depth 0.579 → 0.515 of Timoshenko with T4ANP,
# 0.890 → 0.736 with edge smoothing); choose it where element volumes must be held (edge-smoothed
# T4ANP inverted elements of examples/liver_pressure.toml without it).
ANP_STABILIZATION = 0.0


def anp_stabilization(value) -> tuple[float, bool]:
    """The T4ANP stabilization as the engine takes it: (γ, False) for a fraction γ of each element's
    own pressure, from 0 (plain T4ANP) to 1 (plain T4); (0, True) for "shear", γ = μ/K of each
    group's material at small strain. InputError for anything else."""
    if isinstance(value, str) and value == "shear":
        return 0.0, True
    gamma = float(value) if isinstance(value, numbers.Real) and not isinstance(value, bool) else math.nan
    if not 0.0 <= gamma <= 1.0:
        raise InputError(
            f'nodal_pressure_stabilization = {shown(value)}; expected "shear" (γ = μ/K of each '
            "material) or a fraction from 0 (plain T4ANP) to 1 (plain T4)"
        )
    return gamma, False
