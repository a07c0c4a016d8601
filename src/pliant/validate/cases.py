"""The verification cases of ``pliant validate``: each runs models of
:mod:`pliant.validate.models` and compares them with a closed form, returning :class:`Check` rows
(each with its tolerance and why it is that size) and, for some, a figure."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

import numpy as np

from ..materials import LinearElastic
from ..tled import Simulation
from . import models
from .references import (
    MU,
    nominal,
    balloon_limit_pressure,
    balloon_stretch,
    tension_field,
    UNIAXIAL,
    hertz_force,
    lame_volumetric_strain,
    elastica_tip,
    p_wave_speed,
    timoshenko_tip_deflection,
    torsion_axial_force,
    torsion_torque,
    uniaxial_reference,
)

__all__ = ["Check", "CASES"]


@dataclass
class Check:
    """One compared figure: ``value`` against ``reference`` in ``unit``. ``kind`` "match": the
    relative error ``abs(value − reference) / abs(reference)`` at most ``tolerance``; "at most" /
    "at least": value ≤ or ≥ reference (a bound). ``why``: where the tolerance or bound comes
    from."""

    case: str
    quantity: str
    value: float
    reference: float
    unit: str
    why: str
    tolerance: float = 0.0
    kind: str = "match"
    error: float = field(init=False)
    passed: bool = field(init=False)

    def __post_init__(self):
        self.value, self.reference = float(self.value), float(self.reference)
        self.error = abs(self.value - self.reference) / max(abs(self.reference), 1e-300)
        if self.kind == "match":
            self.passed = bool(self.error <= self.tolerance)
        else:
            self.passed = bool(
                self.value <= self.reference if self.kind == "at most" else self.value >= self.reference
            )

    def as_dict(self) -> dict:
        return asdict(self)


def uniaxial(quick: bool) -> tuple[list[Check], dict]:
    """Uniaxial stress of every material on a jittered 3 × 3 × 3 cube, quasi-static: nominal stress
    (reaction / area) against ∂W/∂λ of the strain energy in principal stretches (Ogden 1984)."""
    rows: list[Check] = []
    curves: dict[str, list] = {}
    for name, (material, W, stretches) in UNIAXIAL.items():
        for s in (1.2,) if quick else stretches:
            X, model, right = models.cube_with_symmetry_bcs(material, s, dtype="float64")
            sim = Simulation(model)
            sim.relax(tol=1e-8, increments=10)
            P_ref, _ = uniaxial_reference(W, s)
            P = float(model.internal_forces(sim.state)[right, 0].sum())
            rows.append(
                Check(
                    "uniaxial stress",
                    f"{name} P_x at λ = {s}",
                    P,
                    P_ref,
                    "Pa",
                    "relaxation residual 1e-8 and the reference's finite difference: "
                    "0.5 % bounds both by far",
                    5e-3,
                )
            )
            curves.setdefault(name, []).append((s, P, P_ref))
    return rows, {"uniaxial": curves}


def cantilever(quick: bool) -> tuple[list[Check], dict]:
    """Cantilever under a tip load against Timoshenko, refined 1, 2, 4 (and 8) elements through
    the depth (ν = 0: the clamp adds no Poisson stiffening): the error at the finest level and the
    observed rate of convergence (theory O(h²) for linear tets' displacements); and the error with
    edge-smoothed strain."""
    L, H, E, P = 1.0, 0.1, 1.0e6, 1.0e-2
    ref = timoshenko_tip_deflection(P, L, H, E, 0.0)
    levels = (1, 2, 4) if quick else (1, 2, 4, 8)
    errors = [
        abs(models.cantilever_tip_deflection(n, LinearElastic(E=E, nu=0.0)) - ref) / ref for n in levels
    ]
    edge = [
        abs(models.cantilever_tip_deflection(n, LinearElastic(E=E, nu=0.0), smoothing="edge") - ref) / ref
        for n in levels
    ]
    rate = math.log2(errors[-2] / errors[-1])
    finest = levels[-1]
    rows = [
        Check(
            "cantilever bending",
            f"tip deflection error, {finest} elements through the depth",
            errors[-1],
            0.25 if quick else 0.07,
            "1",
            "linear tets are stiff in bending: measured 17.6 % at 4 and 5.1 % at 8",
            kind="at most",
        ),
        Check(
            "cantilever bending",
            f"observed rate, {levels[-2]} → {finest} elements",
            rate,
            1.3 if quick else 1.5,
            "1",
            "theory 2; shear locking keeps coarse levels pre-asymptotic (0.7, 1.4, 1.8 measured)",
            kind="at least",
        ),
        Check(
            "cantilever bending",
            f"edge-smoothed strain: error, {finest} elements through the depth",
            edge[-1],
            0.02,
            "1",
            "ES-FEM-T4 removes most shear locking: measured 0.8 % at 4 and 0.36 % at 8 (above "
            "Timoshenko; 3-D elasticity and beam theory differ by ~0.1 %)",
            kind="at most",
        ),
    ]
    return rows, {"cantilever": {"levels": list(levels), "errors": errors, "edge": edge}}


def lame_sphere(quick: bool) -> tuple[list[Check], dict]:
    """Thick-walled sphere under internal pressure (ν = 0.49, and 0.499 in the full run) against
    Lamé: T4ANP's radial displacement, and its median element volumetric strain."""
    shell = models.hollow_sphere()
    rows = []
    for nu in (0.49,) if quick else (0.49, 0.499):
        err, dJ = models.lame_solve(shell, nu, anp=True)
        rows.append(
            Check(
                "Lamé sphere (T4ANP)",
                f"RMS u_r error, ν = {nu}",
                err,
                0.04,
                "1",
                "a 6 mm mesh across a 2 cm wall: 1.9 % and 2.3 % measured",
                kind="at most",
            )
        )
        if nu == 0.49:
            rows.append(
                Check(
                    "Lamé sphere (T4ANP)",
                    "median element J − 1, ν = 0.49",
                    float(np.median(dJ)),
                    lame_volumetric_strain(0.02, 0.04, 30.0, 3e3, nu),
                    "1",
                    "element J scatters about the uniform exact value (volume modes); its median is 6 % off",
                    0.15,
                )
            )
    return rows, {}


def damping(quick: bool) -> tuple[list[Check], dict]:
    """Mass-proportional damping α: a bent free block's energy decays as exp(−αt) (every mode's
    amplitude as exp(−αt/2)). Stiffness-proportional damping β: a released cantilever's first
    bending mode decays at β ω²/2 (ζ = βω/2)."""
    rows = []
    alpha = 20.0
    rows.append(
        Check(
            "damped decay",
            f"energy decay rate with α = {alpha:g} /s (α)",
            models.energy_decay_rate(alpha),
            alpha,
            "1/s",
            "every mode's energy decays as exp(−αt); the envelope ripples at α/ω ≈ 0.02",
            0.02,
        )
    )
    beta = 4e-4
    omega, sigma = models.decay_of_first_mode(*models.ringing_cantilever(beta=beta))
    rows.append(
        Check(
            "damped decay",
            f"decay rate with β = {beta} s (β ω²/2, ω = {omega:.1f} rad/s)",
            sigma,
            beta * omega**2 / 2,
            "1/s",
            "the same fit; the half-step velocity's lag errs below 0.1 %",
            0.02,
        )
    )
    return rows, {}


def _patch_check(case: str, quantity: str, error: float) -> Check:
    """A patch test's row: the interior displacement error over γ, at most 1e-7."""
    return Check(
        case, quantity, error, 1e-7, "1", "relaxation residual 1e-10 times the size of u", kind="at most"
    )


def patch_and_shear(quick: bool) -> tuple[list[Check], dict]:
    """Patch test: simple shear u = γ Y e_x imposed on the boundary of a jittered cube is
    reproduced inside, and the decoupled Neo-Hookean shear stress is σ_xy = μγ exactly (J = 1)."""
    from .. import mesh

    X, T = mesh.box_tets((1.0, 1.0, 1.0), (4, 4, 4), jitter=0.3, seed=3)
    gamma, mu = 0.2, 1.0e3
    model, sim, err = models.sheared_unit_cube(X, T, gamma, mu)
    sig = model.element_results(sim.state)["cauchy"]
    return [
        _patch_check("patch test", "interior displacement error / γ", err / gamma),
        Check(
            "simple shear",
            "mean σ_xy (μγ for Neo-Hookean)",
            float(sig[:, 3].mean()),
            mu * gamma,
            "Pa",
            "homogeneous and isochoric: exact up to the solve's residual",
            1e-6,
        ),
    ], {}


def rigid_rotation(quick: bool) -> tuple[list[Check], dict]:
    """Frame indifference of every material of the uniaxial case, on a jittered cube turned by 2 rad
    about (1, 2, 3): turned alone it carries no force; stretched by diag(1.2, 0.9, 1.05), then
    turned, every element's Cauchy stress is R σ Rᵀ, σ the principal Cauchy stresses λ_i ∂W/∂λ_i / J of
    its strain energy (Ogden 1984, §4.3)."""
    R = models.rotation((1.0, 2.0, 3.0), 2.0)
    stretch = (1.2, 0.9, 1.05)
    J = stretch[0] * stretch[1] * stretch[2]
    rows, largest = [], 0.0
    for name, (material, W, _) in UNIAXIAL.items():
        (forces, _), (_, sigma) = models.deformed_cube(material, (R, R @ np.diag(stretch)))
        largest = max(largest, float(np.abs(forces).max()) / MU)
        s = R @ np.diag([stretch[i] * nominal(W, stretch, i) / J for i in range(3)]) @ R.T
        ref = np.array([s[0, 0], s[1, 1], s[2, 2], s[0, 1], s[1, 2], s[0, 2]])
        rows.append(
            Check(
                "rigid rotation",
                f"{name}: largest |σ − R σ0 Rᵀ| / μ, stretched then turned",
                float(np.abs(sigma - ref).max()) / MU,
                1e-8,
                "1",
                "the reference's central difference (step 1e-6 on W): 4e-10 measured",
                kind="at most",
            )
        )
    why = "round-off of the turned positions (1e-16 a value): 2e-15 measured"
    rows.insert(
        0,
        Check(
            "rigid rotation",
            "largest internal force / (μ L²), turned alone",
            largest,
            1e-12,
            "1",
            why,
            kind="at most",
        ),
    )
    return rows, {}


def hexahedra(quick: bool) -> tuple[list[Check], dict]:
    """Hexahedra split into tetrahedra (pliant.mesh.split): simple shear imposed on the boundary of
    a jittered 4 × 4 × 4 grid of hexahedra numbered at random is reproduced inside (a quad cut
    differently by two neighbours would not be); and the NiftySim user guide's first model, one H8
    cube stretched 30 % with y and z held (F = diag(1.3, 1, 1)), carries the decoupled
    Neo-Hookean's σ_xx in every tet."""
    from ..mesh.primitives import grid_hexahedra
    from ..mesh.split import split_cells

    rng = np.random.default_rng(5)
    g, H = grid_hexahedra(*(np.linspace(0, 1, 5),) * 3)
    inner = np.all((g > 1e-9) & (g < 1 - 1e-9), axis=1)
    X = g + np.where(inner[:, None], rng.uniform(-0.05, 0.05, g.shape), 0.0)  # 20 % of a cell
    perm = rng.permutation(len(X))
    X, H = X[perm], np.argsort(perm)[H]
    T, _ = split_cells(X, "hexahedron", H)
    gamma = 0.2
    err = models.sheared_unit_cube(X, T, gamma, 1.0e3)[2]
    sigma = models.guide_h8_stress()
    J, mu_g, K_g = 1.3, 1052.0, 52249.0  # the user guide's NH
    sxx = mu_g * J ** (-5 / 3) * (1.69 - (1.69 + 2) / 3) + K_g * (J - 1)
    return [
        _patch_check(
            "hexahedra split",
            "interior displacement error / γ, 384 tets of 64 randomly numbered hexahedra",
            err / gamma,
        ),
        Check(
            "NiftySim H8 (user guide §3.1)",
            "σ_xx of the cube stretched 30 %, largest deviation over its 6 tets",
            float(sigma[np.argmax(np.abs(sigma - sxx))]),
            sxx,
            "Pa",
            "homogeneous: exact up to float64 round-off",
            1e-9,
        ),
    ], {}


def wave_speed(quick: bool) -> tuple[list[Check], dict]:
    """Longitudinal waves: a laterally held column carries the P wave at c_p = √((λ + 2μ)/ρ), a
    free slender bar the bar wave at c_0 = √(E/ρ) (Graff 1975, §2.1 and §5.1), for a small-strain
    and a Neo-Hookean material; the pushed end's speed reaches the probe unchanged."""
    E, nu, rho, v0 = 1e5, 0.3, 1000.0, 1e-3
    why = (
        "dispersion of the discrete front (lumped-mass linear elements: phase error (kh)²/24) and, "
        "in the bar, lateral inertia (Rayleigh–Love: ν²(kr)²/2) stay below 1e-3 for the "
        "wavelengths the fit sees (1e-5 to 7e-4 measured)"
    )
    rows = []
    for material in ("linear",) if quick else ("linear", "neo-hookean"):
        for constrained, name, c in (
            (True, "P wave c_p", p_wave_speed(E, nu, rho)),
            (False, "bar wave c_0", math.sqrt(E / rho)),
        ):
            speed, slope = models.wave_arrival(constrained, E=E, nu=nu, rho=rho, v0=v0, material=material)
            rows.append(Check("wave speed", f"{name}, {material}", speed, c, "m/s", why, 5e-3))
            if constrained:
                rows.append(
                    Check(
                        "wave speed",
                        f"particle speed behind the front, {material}",
                        slope,
                        v0,
                        "m/s",
                        why,
                        5e-3,
                    )
                )
    return rows, {}


def elastica(quick: bool) -> tuple[list[Check], dict]:
    """Large deflection (full run only): a slender cantilever (L/H = 20, 2 elements through the
    depth) under a dead tip load α = PL²/(EI) = 2 and 5, against the elastica of the mesh's own
    bending stiffness (EI_eff from its small-load deflection: linear tets' locking is the
    discretization's, checked by the cantilever case; this checks the large-rotation kinematics)."""
    if quick:
        return [], {}
    ratio = models.bent_beam_tip(0.01, n=2, increments=1)[0] / (0.01 / 3)
    rows = []
    for alpha in (2.0, 5.0):
        deflection, shortening = models.bent_beam_tip(alpha, n=2)
        ref_d, ref_s, rotation = elastica_tip(alpha * ratio)
        why = (
            "shear deformation ((H/L)² = 1/400), axial stretch (1e-4), relaxation tolerance, and "
            "locking's departure from a constant stiffness factor: 0.1–0.4 % measured"
        )
        rows.append(
            Check(
                "elastica",
                f"tip deflection / L, α = {alpha:g} (tip rotation {rotation:.2f} rad)",
                deflection,
                ref_d,
                "1",
                why,
                0.01,
            )
        )
        rows.append(
            Check("elastica", f"tip shortening / L, α = {alpha:g}", shortening, ref_s, "1", why, 0.02)
        )
    return rows, {}


def bending_sheets(quick: bool) -> tuple[list[Check], dict]:
    """A strip of bending membranes (docs/engine.md, "Bending"; 20 × 4 cells, ν = 0: a beam of the
    sheet's thickness) under a dead tip load: at α = PL²/(EI) = 0.01 against P L³/(3 E I), and at
    α = 10 (the tip turned 82°) against the elastica."""
    why = "the mesh's discretization error, falling at second order (0.19 % on 20 × 4)"
    small = models.bending_strip_tip(0.01)[0]
    rows = [Check("bending sheets", "tip deflection / L, α = 0.01", small, 0.01 / 3, "1", why, 5e-3)]
    deflection, shortening = models.bending_strip_tip(10.0)
    ref_d, ref_s, rotation = elastica_tip(10.0)
    why = (
        "the mesh's discretization error at large rotation (0.45 % and 0.71 % on 20 × 4, 0.13 % and "
        "0.19 % on 40 × 8)"
    )
    rows.append(
        Check(
            "bending sheets",
            f"tip deflection / L, α = 10 (tip rotation {rotation:.2f} rad)",
            deflection,
            ref_d,
            "1",
            why,
            0.01,
        )
    )
    rows.append(Check("bending sheets", "tip shortening / L, α = 10", shortening, ref_s, "1", why, 0.015))
    return rows, {}


def torsion(quick: bool) -> tuple[list[Check], dict]:
    """Finite torsion of a nearly incompressible Neo-Hookean cylinder (ν = 0.499, T4ANP; ψ a = 0.3,
    its top turned 69°) at fixed length, refined n = 4, 6 (and 8) cells across: the torque and the
    Poynting effect's axial force against Rivlin's exact ones, each extrapolated (Richardson, the
    two finest levels at O(h²)), and the torque's observed rate."""
    mu, psi, a = 1e4, 30.0, 0.01
    levels = (4, 6) if quick else (4, 6, 8)
    runs = [models.twisted_cylinder(n, psi, mu) for n in levels]
    ref_m, ref_n = torsion_torque(mu, psi, a), torsion_axial_force(mu, psi, a)
    (n1, n2), (r1, r2) = levels[-2:], runs[-2:]
    w = n2**2 / (n2**2 - n1**2)  # Richardson at O(h²), h ∝ 1/n
    torque, axial = w * r2[0] + (1 - w) * r1[0], w * r2[1] + (1 - w) * r1[1]
    e1, e2 = abs(r1[0] / ref_m - 1), abs(r2[0] / ref_m - 1)
    why = f"T4ANP's error falls at second order ({n1} → {n2} cells across: measured"
    rows = [
        Check(
            "finite torsion (Rivlin)",
            f"torque, extrapolated from {n1} and {n2} cells across",
            torque,
            ref_m,
            "N·m",
            f"{why} 15.8 % → 0.08 % extrapolated from 4 and 6; 8.9 % → 0.15 % from 6 and 8)",
            0.01,
        ),
        Check(
            "finite torsion (Rivlin)",
            f"Poynting axial force, extrapolated from {n1} and {n2} cells across",
            axial,
            ref_n,
            "N",
            f"{why} 14.9 % → 2.7 % from 4 and 6; 7.9 % → 1.0 % from 6 and 8: its own rate is 2.2, "
            "above the extrapolation's 2)",
            0.04 if quick else 0.02,
        ),
        Check(
            "finite torsion (Rivlin)",
            f"torque: observed rate, {n1} → {n2} cells across",
            math.log(e1 / e2) / math.log(n2 / n1),
            1.7,
            "1",
            "theory 2 (linear tets); measured 1.99 (4 → 6) and 1.98 (6 → 8)",
            kind="at least",
        ),
    ]
    data = {"levels": list(levels), "torque": [r[0] for r in runs], "axial": [r[1] for r in runs]}
    return rows, {"torsion": {**data, "torque_exact": ref_m, "axial_exact": ref_n}}


def hertz(quick: bool) -> tuple[list[Check], dict]:
    """Rigid sphere pressed into a thick block (196,608 tets; full run only): force against Hertz
    at δ/R = 0.25, 0.5, 1 %, the fitted exponent against 1.5, and the supports' reaction against
    the tool's force (equilibrium)."""
    if quick:
        return [], {}
    R, E, nu = 0.01, 1e4, 0.3
    depths = np.array([0.0025, 0.005, 0.01]) * R
    F, reaction = models.hertz_indentation(depths, R, E, nu)
    rows = [
        Check(
            "Hertz indentation",
            f"force at δ/R = {d / R:.2%}",
            f,
            hertz_force(d, R, E, nu),
            "N",
            "finite block (+0.5 to 1 %), load on the deformed surface (+0.4 to 1.5 %), linear "
            "tets (+2 %): 3.2–4.2 % measured",
            0.05,
        )
        for d, f in zip(depths, F)
    ]
    rows.append(
        Check(
            "Hertz indentation",
            "exponent of F(δ)",
            np.polyfit(np.log(depths), np.log(F), 1)[0],
            1.5,
            "1",
            "the depth-dependent errors above tilt the fit by about 0.015",
            0.02,
        )
    )
    rows.append(
        Check(
            "Hertz indentation",
            "support reaction / tool force at the deepest step",
            reaction[-1] / F[-1],
            1.0,
            "1",
            "the relaxation's 1e-5 out-of-balance force (2e-4 measured)",
            2e-3,
        )
    )
    return rows, {}


def hertz_soft(quick: bool) -> tuple[list[Check], dict]:
    """Two equal elastic paraboloids pressed together through soft contact (quarter models, 93,750
    tets each; full run only): force against Hertz (E* = E/(2(1 − ν²)), R* = R/2) at δ/R = 0.5, 1,
    2 %, and against the same body on a rigid plane at δ/2 (the same problem by symmetry)."""
    if quick:
        return [], {}
    R, E, nu = 0.02, 1e4, 0.3
    depths = np.array([0.005, 0.01, 0.02]) * R
    soft = models.hertz_two_bodies(depths, R, E, nu, soft=True)
    plane = models.hertz_two_bodies(depths, R, E, nu, soft=False)
    rows = [
        Check(
            "Hertz, two soft bodies",
            f"force at δ/R = {d / R:.1%}",
            f,
            hertz_force(d, R / 2, E / 2, nu),
            "N",
            "3-5 cells across the contact radius, finite bodies, the gap closed on the deformed "
            "surfaces: 3.3-3.8 % measured",
            0.05,
        )
        for d, f in zip(depths, soft)
    ]
    rows += [
        Check(
            "Hertz, two soft bodies",
            f"force / rigid plane at δ/2, δ/R = {d / R:.1%}",
            f / p,
            1.0,
            "1",
            "the same mesh and problem, two contact methods, each relaxed to 1e-4: 0.13 % measured",
            0.01,
        )
        for d, f, p in zip(depths, soft, plane)
    ]
    return rows, {}


def membranes(quick: bool) -> tuple[list[Check], dict]:
    """Membranes alone (docs/engine.md, "Membranes"): a sheet stretched to λ in uniaxial membrane
    stress contracts to λ^(−1/2) (incompressible Neo-Hookean, λ = 1.5; Bonet et al. 2000) or
    √(1 − 2 ν E_xx) (plane-stress St Venant–Kirchhoff, λ = 1.3, E_xx the Green strain; it stiffens
    in tension, and 1.4 no longer relaxes at the small-strain step) and pulls with the resultant
    times its width: μ h (λ − λ⁻²), or λ h E E_xx."""
    h = 1e-3
    why = "homogeneous: exact up to the relaxation's 1e-10"
    rows = []
    for kind, lam in (("neo-hookean", 1.5), ("st-venant-kirchhoff", 1.3)):
        Exx = (lam**2 - 1) / 2
        width, pull = (
            (lam**-0.5, 1e3 * h * (lam - lam**-2))
            if kind == "neo-hookean"
            else (math.sqrt(1 - 2 * 0.3 * Exx), lam * h * 3e3 * Exx)
        )
        w, f = models.membrane_sheet(kind, lam)
        what = f"{kind} sheet stretched {lam - 1:.0%}"
        rows.append(Check("membranes", f"{what}: width", w, width, "1", why, 1e-6))
        rows.append(Check("membranes", f"{what}: pull", f, pull, "N", why, 1e-6))
    rows += _balloons() + [_wrinkled_shear()]
    return rows, {}


def _balloons() -> list[Check]:
    """A spherical balloon (R = 5 cm, h = 1 mm) inflated by p against the stretch of the spherical
    membrane (references.balloon_stretch): incompressible Neo-Hookean, μ = 10 kPa, at 0.6 of its
    limit pressure (on the stable branch), and St Venant–Kirchhoff, 30 kPa, ν = 0.3, at 200 Pa: the
    mean radius of 642 nodes against λ R."""
    R, h = 0.05, 1e-3
    p_nh = 0.6 * balloon_limit_pressure(1e4, h, R)
    why = "the facets' discretization error, falling as h² (5.1e-4 and 4.6e-4 at 642 nodes)"
    return [
        Check(
            "membranes",
            f"{kind} balloon at {p:.0f} Pa: mean radius",
            models.membrane_balloon(kind, p),
            lam * R,
            "m",
            why,
            1e-3,
        )
        for kind, p, lam in (
            ("neo-hookean", p_nh, balloon_stretch(p_nh, h, R, mu=1e4)),
            ("st-venant-kirchhoff", 200.0, balloon_stretch(200.0, h, R, E=3e4, nu=0.3)),
        )
    ]


def _wrinkled_shear() -> Check:
    """A sheet that wrinkles in simple shear γ = 0.2 (St Venant–Kirchhoff, E = 3 kPa, ν = 0.3,
    h = 1 mm) carries tension along its major principal direction alone (references.tension_field):
    the shear component of its Cauchy resultant t = F S Fᵀ / det F."""
    from ..materials.membrane import StVKMembrane

    gamma = 0.2
    Fg = np.array([[1.0, gamma], [0.0, 1.0]])
    S = tension_field(StVKMembrane(3e3, 0.3, 1e-3, 1e3, wrinkling=True), Fg)[1]
    t = Fg @ S @ Fg.T / np.linalg.det(Fg)
    return Check(
        "membranes",
        "wrinkling sheet in simple shear 0.2: t_xy",
        models.wrinkled_shear(gamma),
        t[0, 1],
        "N/m",
        "homogeneous: round-off",
        1e-9,
    )


CASES = {
    "uniaxial": uniaxial,
    "patch": patch_and_shear,
    "rotation": rigid_rotation,
    "hexahedra": hexahedra,
    "membranes": membranes,
    "bending_sheets": bending_sheets,
    "cantilever": cantilever,
    "lame": lame_sphere,
    "damping": damping,
    "waves": wave_speed,
    "elastica": elastica,
    "torsion": torsion,
    "hertz": hertz,
    "hertz_soft": hertz_soft,
}
