"""Hyperelastic materials (the table in the package docstring): constructors from native
constants or (E, ν), checks, small-strain Lamé constants, engine kind and parameters."""

from __future__ import annotations

import math

from .. import _core
from ..checks import as_real, shown
from ..errors import MaterialError

__all__ = [
    "Material",
    "NeoHookean",
    "MooneyRivlin",
    "NeoHookeanCoupled",
    "StVenantKirchhoff",
    "LinearElastic",
    "Polynomial",
    "ArrudaBoyce",
    "TransverselyIsotropic",
    "lame_from_young",
]


def _positive(name: str, value: float, cls: str) -> float:
    v = as_real(value)
    if not math.isfinite(v) or v <= 0.0:
        raise MaterialError(f"{cls}: {name} = {shown(value)}; expected a finite value > 0 [Pa]")
    return v


def lame_from_young(E: float, nu: float, cls: str = "material") -> tuple[float, float]:
    """(μ, λ) [Pa] from Young's modulus E [Pa] and Poisson's ratio ν (−1 < ν < 0.5)."""
    E = _positive("E", E, cls)
    given, nu = nu, as_real(nu)
    if not math.isfinite(nu) or nu >= 0.5 or nu <= -1.0:
        raise MaterialError(
            f"{cls}: nu = {shown(given)}; expected -1 < nu < 0.5 (0.5 is incompressible, "
            "which explicit dynamics cannot represent: use e.g. 0.49)"
        )
    return E / (2.0 * (1.0 + nu)), E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))


class Material:
    """Base class: ``kind`` (engine code), ``params`` (up to 8 floats), ``mu``/``lam`` small-strain
    Lamé constants [Pa]."""

    kind: _core.MaterialKind | None = None
    mu: float
    lam: float

    @property
    def params(self) -> tuple[float, float, float, float]:
        raise NotImplementedError

    @property
    def decoupled(self) -> bool:
        """Whether W splits into isochoric and volumetric parts (what T4ANP and viscoelasticity
        need); the engine says, per kind."""
        return self.kind is not None and bool(_core.is_decoupled(self.kind))

    @property
    def bulk_modulus(self) -> float:
        """Small-strain bulk modulus K = λ + 2μ/3 [Pa]."""
        return self.lam + 2.0 * self.mu / 3.0

    @property
    def young(self) -> float:
        """Small-strain Young's modulus E [Pa]."""
        K, mu = self.bulk_modulus, self.mu
        return 9.0 * K * mu / (3.0 * K + mu)

    @property
    def poisson(self) -> float:
        """Small-strain Poisson's ratio ν."""
        K, mu = self.bulk_modulus, self.mu
        return (3.0 * K - 2.0 * mu) / (2.0 * (3.0 * K + mu))

    def _key(self):
        return (self.kind, self.params)

    def __eq__(self, other):
        return isinstance(other, Material) and self._key() == other._key()

    def __hash__(self):
        return hash(self._key())

    def __repr__(self):
        return f"{type(self).__name__}(mu={self.mu:g}, lam={self.lam:g})"


def _mu_k(cls: str, mu, K, E, nu, k_name: str = "K") -> tuple[float, float]:
    if E is not None or nu is not None:
        if E is None or nu is None or mu is not None or K is not None:
            native = "mu" if cls != "MooneyRivlin" else "C10, C01"
            raise MaterialError(f"{cls}: give either (E, nu) or ({native}, {k_name})")
        m, lam = lame_from_young(E, nu, cls)
        return m, lam + 2.0 * m / 3.0
    if mu is None or K is None:
        raise MaterialError(f"{cls}: missing parameters; expected (E, nu) or (mu, {k_name})")
    return _positive("mu", mu, cls), _positive(k_name, K, cls)


class NeoHookean(Material):
    """Decoupled Neo-Hookean: W = μ/2 (Ī1 − 3) + K/2 (J − 1)² (Taylor et al. 2008, eq. 10).

    ``NeoHookean(mu=..., K=...)`` (shear and bulk modulus [Pa], NiftySim's order) or
    ``NeoHookean(E=..., nu=...)``.
    """

    kind = _core.MaterialKind.NeoHookean

    def __init__(self, mu=None, K=None, *, E=None, nu=None):
        self.mu, self.K = _mu_k("NeoHookean", mu, K, E, nu)
        self.lam = self.K - 2.0 * self.mu / 3.0

    @property
    def params(self):
        return (self.mu, self.K, 0.0, 0.0)


class MooneyRivlin(Material):
    """Decoupled Mooney–Rivlin: W = C10 (Ī1 − 3) + C01 (Ī2 − 3) + K/2 (J − 1)².

    Small-strain shear modulus μ = 2 (C10 + C01). ``MooneyRivlin(C10=..., C01=..., K=...)``.
    """

    kind = _core.MaterialKind.MooneyRivlin

    def __init__(self, C10, C01, K):
        self.C10 = _positive("C10", C10, "MooneyRivlin")
        self.C01 = as_real(C01)
        if not math.isfinite(self.C01) or self.C01 < 0.0:
            raise MaterialError(f"MooneyRivlin: C01 = {shown(C01)}; expected a finite value >= 0 [Pa]")
        self.K = _positive("K", K, "MooneyRivlin")
        self.mu = 2.0 * (self.C10 + self.C01)
        self.lam = self.K - 2.0 * self.mu / 3.0

    @property
    def params(self):
        return (self.C10, self.C01, self.K, 0.0)

    def __repr__(self):
        return f"MooneyRivlin(C10={self.C10:g}, C01={self.C01:g}, K={self.K:g})"


class _MuLambda(Material):
    _name = ""

    def __init__(self, mu=None, lam=None, *, E=None, nu=None):
        cls = type(self).__name__
        if E is not None or nu is not None:
            if E is None or nu is None or mu is not None or lam is not None:
                raise MaterialError(f"{cls}: give either (E, nu) or (mu, lam)")
            self.mu, self.lam = lame_from_young(E, nu, cls)
        else:
            if mu is None or lam is None:
                raise MaterialError(f"{cls}: missing parameters; expected (E, nu) or (mu, lam)")
            self.mu = _positive("mu", mu, cls)
            self.lam = as_real(lam)
            if not math.isfinite(self.lam) or self.lam + 2.0 * self.mu / 3.0 <= 0.0:
                raise MaterialError(
                    f"{cls}: lam = {shown(lam)}; expected lam + 2 mu / 3 > 0 (positive bulk modulus)"
                )

    @property
    def params(self):
        return (self.mu, self.lam, 0.0, 0.0)


class NeoHookeanCoupled(_MuLambda):
    """Coupled compressible Neo-Hookean: W = μ/2 (I1 − 3) − μ ln J + λ/2 (ln J)²
    (Bonet & Wood 2008, §6.4.3; FEBio's "neo-Hookean")."""

    kind = _core.MaterialKind.NeoHookeanCoupled


class StVenantKirchhoff(_MuLambda):
    """St Venant–Kirchhoff: W = λ/2 (tr E)² + μ E:E (Bonet & Wood 2008, §6.4.2)."""

    kind = _core.MaterialKind.StVenantKirchhoff


class LinearElastic(_MuLambda):
    """Small-strain linear elasticity, σ = λ tr(ε) I + 2μ ε; for small displacements only."""

    kind = _core.MaterialKind.LinearElastic


def _finite(name: str, value, cls: str, minimum: float | None = None) -> float:
    v = as_real(value)
    if not math.isfinite(v) or (minimum is not None and v < minimum):
        raise MaterialError(
            f"{cls}: {name} = {shown(value)}; expected a finite value"
            + (f" >= {minimum:g}" if minimum is not None else "")
        )
    return v


class Polynomial(Material):
    """Decoupled polynomial of order 2 (NiftySim "PY"): W = C10 (Ī1 − 3) + C01 (Ī2 − 3) +
    C20 (Ī1 − 3)² + C02 (Ī2 − 3)² + C11 (Ī1 − 3)(Ī2 − 3) + K/2 (J − 1)². Small-strain shear
    modulus μ = 2 (C10 + C01). ``Polynomial(C10=..., C01=..., C20=..., C02=..., C11=..., K=...)``."""

    kind = _core.MaterialKind.Polynomial

    def __init__(self, C10, C01=0.0, C20=0.0, C02=0.0, C11=0.0, *, K):
        c = "Polynomial"
        self.C10, self.C01 = _finite("C10", C10, c), _finite("C01", C01, c)
        self.C20, self.C02, self.C11 = (
            _finite(n, v, c) for n, v in (("C20", C20), ("C02", C02), ("C11", C11))
        )
        self.K = _positive("K", K, c)
        self.mu = 2.0 * (self.C10 + self.C01)
        if not self.mu > 0:
            raise MaterialError(f"{c}: 2 (C10 + C01) = {shown(self.mu)}; expected a positive shear modulus")
        self.lam = self.K - 2.0 * self.mu / 3.0

    @property
    def params(self):
        return (self.C10, self.C01, self.C20, self.C02, self.C11, self.K)

    def __repr__(self):
        return (
            f"Polynomial(C10={self.C10:g}, C01={self.C01:g}, C20={self.C20:g}, "
            f"C02={self.C02:g}, C11={self.C11:g}, K={self.K:g})"
        )


class ArrudaBoyce(Material):
    """Decoupled Arruda–Boyce (eight-chain; NiftySim "AB"): W = μ Σ_{i=1..5} Ci / λm^(2i−2)
    (Ī1^i − 3^i) + K/2 ((J² − 1)/2 − ln J), Ci = 1/2, 1/20, 11/1050, 19/7000, 519/673750
    (Arruda & Boyce 1993). ``ArrudaBoyce(mu=..., lambda_m=..., K=...)``: λm the locking stretch
    (> 1); the small-strain shear modulus is μ (1 + 3/(5 λm²) + 99/(175 λm⁴) + …)."""

    kind = _core.MaterialKind.ArrudaBoyce

    def __init__(self, mu, lambda_m, K):
        c = "ArrudaBoyce"
        self.mu0, self.K = _positive("mu", mu, c), _positive("K", K, c)
        self.lambda_m = _finite("lambda_m", lambda_m, c)
        if not self.lambda_m > 1.0:
            raise MaterialError(f"{c}: lambda_m = {shown(lambda_m)}; expected a locking stretch > 1")
        x = 3.0 / self.lambda_m**2  # small-strain shear modulus 2 ∂W/∂Ī1 at Ī1 = 3
        self.mu = 2 * self.mu0 * (0.5 + x * (2 / 20 + x * (33 / 1050 + x * (76 / 7000 + x * 2595 / 673750))))
        self.lam = self.K - 2.0 * self.mu / 3.0

    @property
    def params(self):
        return (self.mu0, self.lambda_m, self.K)

    def __repr__(self):
        return f"ArrudaBoyce(mu={self.mu0:g}, lambda_m={self.lambda_m:g}, K={self.K:g})"


class TransverselyIsotropic(Material):
    """Decoupled transversely isotropic (NiftySim "TI"): W = μ/2 (Ī1 − 3) + η/2 (Ī4 − 1)² +
    K/2 (J − 1)², Ī4 = J^(−2/3) a·Ca, fibres along the unit vector a (normalized here).
    ``TransverselyIsotropic(mu=..., K=..., eta=..., direction=(a1, a2, a3))``."""

    kind = _core.MaterialKind.TransverselyIsotropic

    def __init__(self, mu, K, eta, direction):
        c = "TransverselyIsotropic"
        self.mu, self.K = _positive("mu", mu, c), _positive("K", K, c)
        self.eta = _finite("eta", eta, c, minimum=0.0)
        a = [as_real(v) for v in direction] if hasattr(direction, "__len__") else []
        n = math.sqrt(sum(v * v for v in a)) if len(a) == 3 else 0.0
        if not (math.isfinite(n) and n > 0):
            raise MaterialError(f"{c}: direction = {shown(direction)}; expected a non-zero 3-vector")
        self.direction = tuple(v / n for v in a)
        self.lam = self.K - 2.0 * self.mu / 3.0

    @property
    def params(self):
        return (self.mu, self.K, self.eta, *self.direction)

    def __repr__(self):
        return (
            f"TransverselyIsotropic(mu={self.mu:g}, K={self.K:g}, eta={self.eta:g}, "
            f"direction={self.direction})"
        )
