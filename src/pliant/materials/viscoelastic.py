"""Visco-hyperelasticity: Prony series on the isochoric and volumetric stresses of a decoupled
material (NiftySim's NHV/TIV)."""

from __future__ import annotations

import math

from .. import _core
from ..checks import as_real, shown
from ..errors import MaterialError
from .hyperelastic import Material

__all__ = ["Viscoelastic"]


def decoupled_materials() -> list[str]:
    """Names of the decoupled material classes (the engine decides which kinds are)."""
    from . import hyperelastic as h

    return [
        c.__name__
        for c in vars(h).values()
        if isinstance(c, type)
        and issubclass(c, Material)
        and isinstance(getattr(c, "kind", None), _core.MaterialKind)
        and _core.is_decoupled(c.kind)
    ]


class Viscoelastic(Material):
    """Visco-hyperelastic version of a decoupled material (NiftySim "NHV" / "TIV"): Prony series
    α(t) = α∞ + Σ α_i e^(−t/τ_i) on its isochoric and volumetric stresses (user guide v2.4,
    App. A.2, eqs. 9–10; Taylor et al. 2009). ``iso`` / ``vol``: up to 4 pairs (α_i, τ_i [s]) each,
    α_i ≥ 0 with Σ α_i < 1 (α∞ = 1 − Σ α_i is the long-term fraction of the stress). The base
    material's moduli are the instantaneous ones."""

    def __init__(self, base: Material, iso=(), vol=()):
        c = "Viscoelastic"
        if not isinstance(base, Material) or isinstance(base, Viscoelastic) or not base.decoupled:
            raise MaterialError(
                f"{c}: base {shown(base)}; expected a decoupled material ({', '.join(decoupled_materials())})"
            )
        terms = []
        for name, series in (("iso", iso), ("vol", vol)):
            most = _core.prony_max // 2
            try:
                series = list(series)  # iterated twice below (a generator would be empty the second time)
                pairs = [tuple(as_real(v) for v in p) for p in series]
            except (TypeError, ValueError):
                pairs = None
            if pairs is None or len(pairs) > most or any(len(p) != 2 for p in pairs):
                raise MaterialError(
                    f"{c}: {name} = {shown(series)}; expected up to {most} pairs (alpha, tau [s])"
                )
            for (a, tau), given in zip(pairs, series):
                if not (math.isfinite(a) and a >= 0 and math.isfinite(tau) and tau > 0):
                    raise MaterialError(
                        f"{c}: {name} term (alpha={shown(given[0])}, tau={shown(given[1])}); expected "
                        "alpha >= 0 and tau > 0 [s]"
                    )
            if sum(a for a, _ in pairs) >= 1.0:
                raise MaterialError(
                    f"{c}: {name} alphas sum to {sum(a for a, _ in pairs):g}; "
                    "expected < 1 (a positive long-term modulus)"
                )
            terms.append(tuple(pairs))
        self.base, self.prony = base, tuple(terms)
        self.kind, self.mu, self.lam = base.kind, base.mu, base.lam

    @property
    def params(self):
        return self.base.params

    def _key(self):
        return (self.kind, self.params, self.prony)

    def __repr__(self):
        return f"Viscoelastic({self.base!r}, iso={self.prony[0]!r}, vol={self.prony[1]!r})"
