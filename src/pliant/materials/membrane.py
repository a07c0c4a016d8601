"""Membrane materials (SI units): the in-plane response of membrane triangles, with their
thickness h [m] and density ρ [kg/m³] (ModelBuilder.add_membrane). The stress functions live once,
in C++ (``cpp/include/pliant/membrane.hpp``), shared by every backend.

=====================  =========================================================  ==============
class                  2nd Piola–Kirchhoff stress S (per reference thickness)       parameters
=====================  =========================================================  ==============
StVKMembrane           λ' tr(E) I + 2 μ E, λ' = E ν / (1 − ν²), plane stress         E, nu
                       (NiftySim's "Linear" membrane at small displacement)
NeoHookeanMembrane     μ (I − C33 C⁻¹), C33 = 1 / det C: incompressible             mu
                       (Bonet et al. 2000; NiftySim's "NeoHookean" membrane)
=====================  =========================================================  ==============

``bending`` (either class): the sheet also resists bending, as a Kirchhoff plate of the same
thickness, D = E_b h³ / (12 (1 − ν_b²)), on rotation-free shell triangles (the Basic Shell Triangle
of Oñate & Zárate 2000, NiftySim's LinearShell; ``membrane.hpp``, ``membrane_bending_forces``):
``True`` bends with the material's own E and ν (E = 3 μ, ν = ½ incompressible), a number is the
bending modulus E_b [Pa], ``bending_nu`` ν_b (default the material's); with a bending modulus the
in-plane modulus (E, mu) may be 0: a sheet that only bends, as NiftySim's LinearShell "0 0 E_b ν_b"
(nothing then resists stretching in its plane: load it across, at small slopes). The reference shape is
unstressed; an edge of the sheet whose two nodes are held in all three directions is clamped (its
slope held), any other boundary edge is free to turn (a hinge, or a free edge).

``wrinkling=True`` (either class): the membrane carries no compression (tension-field theory,
Roddeman et al. 1987; Pipkin's relaxed energy, 1986): slack where its major principal strain is
≤ 0, uniaxial tension along the major direction where the material's minor principal stress would
be negative (wrinkled: S1 = E e1, or μ (1 − c1^(−3/2)) incompressible), the material's stress
otherwise (taut). A sheet without bending stiffness buckles at almost no compressive load; one that
carries compression crumples and stiffens until its step is unstable (``membrane.hpp``,
``membrane_wrinkle``).
"""

from __future__ import annotations

import copy
import math

import numpy as np

from .. import _core
from ..checks import as_real, shown
from ..errors import MaterialError

__all__ = ["MembraneMaterial", "StVKMembrane", "NeoHookeanMembrane"]


def _finite_positive(cls: str, name: str, value, unit: str) -> float:
    v = as_real(value)
    if not math.isfinite(v) or v <= 0.0:
        raise MaterialError(f"{cls}: {name} = {shown(value)}; expected a finite value > 0 [{unit}]")
    return v


def _modulus(cls: str, name: str, value, unit: str, bending) -> float:
    """An in-plane modulus: > 0, or 0 for a sheet that only bends (``bending`` a modulus E_b > 0,
    as NiftySim's LinearShell "0 0 E_b ν_b")."""
    v = as_real(value)
    only_bends = not isinstance(bending, (bool, np.bool_)) and isinstance(bending, (int, float, np.number))
    if v == 0.0 and only_bends and math.isfinite(as_real(bending)) and as_real(bending) > 0.0:
        return 0.0
    if v == 0.0:
        raise MaterialError(
            f"{cls}: {name} = 0; expected a finite value > 0 [{unit}], or 0 with a bending modulus "
            "(bending = E_b > 0 [Pa]) for a sheet that only bends"
        )
    return _finite_positive(cls, name, value, unit)


class MembraneMaterial:
    """Base class: ``kind`` (engine code, :class:`pliant._core.MembraneKind`), ``thickness`` h [m],
    ``density`` ρ [kg/m³] and ``params`` (two moduli, as the engine reads them)."""

    kind: _core.MembraneKind
    thickness: float
    density: float
    wrinkling: bool

    bending_E: float
    bending_nu: float

    def _set_sheet(self, thickness, density, wrinkling, bending=False, bending_nu=None) -> None:
        cls = type(self).__name__
        self.thickness = _finite_positive(cls, "thickness", thickness, "m")
        self.density = _finite_positive(cls, "density", density, "kg/m^3")
        if not isinstance(wrinkling, (bool, np.bool_)):
            raise MaterialError(f"{cls}: wrinkling = {shown(wrinkling)}; expected True or False")
        self.wrinkling = bool(wrinkling)
        if isinstance(bending, (bool, np.bool_)):
            self.bending_E = self.young if bending else 0.0
        elif isinstance(bending, (int, float, np.number)) and as_real(bending) == 0.0:
            self.bending_E = 0.0  # (NiftySim's LinearShell without bending)
        else:
            self.bending_E = _finite_positive(cls, "bending", bending, "Pa")
        nu = self.poisson if bending_nu is None else as_real(bending_nu)
        if not math.isfinite(nu) or not -1.0 < nu <= 0.5:
            raise MaterialError(f"{cls}: bending_nu = {shown(bending_nu)}; expected -1 < bending_nu <= 0.5")
        if bending_nu is not None and self.bending_E == 0.0:
            raise MaterialError(
                f"{cls}: bending_nu = {shown(bending_nu)} without bending; expected bending too"
            )
        self.bending_nu = nu if self.bending_E > 0.0 else 0.0

    @property
    def params(self) -> tuple[float, float]:
        raise NotImplementedError

    @property
    def young(self) -> float:
        """Young's modulus at small strain [Pa] (the bending modulus of ``bending=True``)."""
        raise NotImplementedError

    @property
    def poisson(self) -> float:
        """Poisson's ratio at small strain (the default ``bending_nu``)."""
        raise NotImplementedError

    @property
    def bends(self) -> bool:
        """Whether the sheet resists bending (``bending``)."""
        return self.bending_E > 0.0

    @property
    def bending_stiffness(self) -> float:
        """Flexural rigidity D = E_b h³ / (12 (1 − ν_b²)) [N·m] (0 without bending)."""
        return self.bending_E * self.thickness**3 / (12.0 * (1.0 - self.bending_nu**2))

    @property
    def wave_modulus(self) -> float:
        """In-plane P-wave modulus at small strain [Pa]: E/(1 − ν²), or 4μ when incompressible
        (the modulus in the membrane's stable time step)."""
        raise NotImplementedError

    def taut(self) -> "MembraneMaterial":
        """This material carrying compression (wrinkling off)."""
        m = copy.copy(self)
        m.wrinkling = False
        return m

    def _key(self):
        return (
            type(self),
            self.params,
            self.thickness,
            self.density,
            self.wrinkling,
            self.bending_E,
            self.bending_nu,
        )

    def _sheet_repr(self) -> str:
        wrinkles = ", wrinkling=True" if self.wrinkling else ""
        bends = f", bending={self.bending_E:g}, bending_nu={self.bending_nu:g}" if self.bends else ""
        return f"thickness={self.thickness:g}, density={self.density:g}{wrinkles}{bends}"

    def __eq__(self, other):
        return isinstance(other, MembraneMaterial) and self._key() == other._key()

    def __hash__(self):
        return hash(self._key())


class StVKMembrane(MembraneMaterial):
    """Plane-stress St Venant–Kirchhoff membrane: S = λ' tr(E) I + 2 μ E in the membrane's plane,
    λ' = E ν/(1 − ν²) the plane-stress Lamé constant, μ = E/(2(1 + ν)) (Bonet & Wood, 2nd ed., §6.6
    for plane stress; E the in-plane Green strain). Young's modulus ``E`` [Pa] (0: only bends),
    Poisson's ratio ``nu`` (−1 < ν ≤ 0.5), ``thickness`` [m], ``density`` [kg/m³]; ``wrinkling``:
    carries no compression; ``bending``, ``bending_nu``: resists bending (the module's docstring)."""

    kind = _core.MembraneKind.StVenantKirchhoff

    def __init__(self, E, nu, thickness, density, wrinkling: bool = False, bending=False, bending_nu=None):
        self.E = _modulus("StVKMembrane", "E", E, "Pa", bending)
        self.nu = as_real(nu)
        if not math.isfinite(self.nu) or not -1.0 < self.nu <= 0.5:
            raise MaterialError(f"StVKMembrane: nu = {shown(nu)}; expected -1 < nu <= 0.5")
        self._set_sheet(thickness, density, wrinkling, bending, bending_nu)

    @property
    def params(self) -> tuple[float, float]:
        return (self.E, self.nu)

    @property
    def young(self) -> float:
        return self.E

    @property
    def poisson(self) -> float:
        return self.nu

    @property
    def wave_modulus(self) -> float:
        return self.E / (1.0 - self.nu**2)

    def __repr__(self):
        return f"StVKMembrane(E={self.E:g}, nu={self.nu:g}, {self._sheet_repr()})"


class NeoHookeanMembrane(MembraneMaterial):
    """Incompressible Neo-Hookean membrane: W = μ/2 (tr C + 1/det C − 3) per reference volume,
    C the in-plane right Cauchy–Green tensor, the thickness stretch λ3 = 1/√det C; S = μ (I − C⁻¹/det C)
    (Bonet, Wood, Mahaney & Heywood 2000, CMAME 190:579, eq. 18). Shear modulus ``mu`` [Pa] (0: only
    bends), ``thickness`` [m], ``density`` [kg/m³]; ``wrinkling``: carries no compression;
    ``bending``, ``bending_nu``: resists bending (the module's docstring)."""

    kind = _core.MembraneKind.NeoHookean

    def __init__(self, mu, thickness, density, wrinkling: bool = False, bending=False, bending_nu=None):
        self.mu = _modulus("NeoHookeanMembrane", "mu", mu, "Pa", bending)
        self._set_sheet(thickness, density, wrinkling, bending, bending_nu)

    @property
    def params(self) -> tuple[float, float]:
        return (self.mu, 0.0)

    @property
    def young(self) -> float:
        return 3.0 * self.mu

    @property
    def poisson(self) -> float:
        return 0.5

    @property
    def wave_modulus(self) -> float:
        return 4.0 * self.mu

    def __repr__(self):
        return f"NeoHookeanMembrane(mu={self.mu:g}, {self._sheet_repr()})"
