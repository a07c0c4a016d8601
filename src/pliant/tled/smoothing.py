"""Strain smoothing of linear tetrahedra: the StrainSmoothing kinds (bound from the engine) and
their names in scenes and the API ('element': plain T4; 'edge': edge-smoothed, ES-FEM-T4)."""

from __future__ import annotations

from .. import _core
from ..checks import shown
from ..errors import InputError

StrainSmoothing = _core.StrainSmoothing

__all__ = ["StrainSmoothing", "strain_smoothing"]


def strain_smoothing(value) -> _core.StrainSmoothing:
    """A StrainSmoothing from itself or its name ('element', 'edge', any case); InputError names
    the value and the choices otherwise."""
    if isinstance(value, StrainSmoothing):
        return value
    kinds = {k.name.lower(): k for k in StrainSmoothing}
    if isinstance(value, str) and value.lower() in kinds:
        return kinds[value.lower()]
    raise InputError(f"strain_smoothing = {shown(value)}; expected one of {', '.join(map(repr, kinds))}")
