"""Closed-form references for verification, written independently of the engine's stress code:
strain energies in principal stretches (differentiated numerically), beam theory, Lamé's thick
sphere. Used by ``pliant validate`` and by the test suite.
"""

from __future__ import annotations

import math

from scipy.optimize import brentq

from .. import materials as mat

__all__ = [
    "MU",
    "K",
    "LAM",
    "UNIAXIAL",
    "nominal",
    "uniaxial_reference",
    "timoshenko_tip_deflection",
    "lame_radial_displacement",
    "lame_volumetric_strain",
    "hertz_force",
    "torsion_torque",
    "torsion_axial_force",
]

MU, K = 1.0e3, 10.0e3  # Pa; K/μ = 10 (ν ≈ 0.45), soft tissue-like
LAM = K - 2 * MU / 3


def _J(l):
    return l[0] * l[1] * l[2]


def _I2(l):
    return l[0] ** 2 * l[1] ** 2 + l[1] ** 2 * l[2] ** 2 + l[2] ** 2 * l[0] ** 2


def W_nh(l, mu=MU, k=K):
    J = _J(l)
    return mu / 2 * (J ** (-2 / 3) * sum(x * x for x in l) - 3) + k / 2 * (J - 1) ** 2


def W_mr(l, c10=0.3 * MU, c01=0.2 * MU, k=K):
    J = _J(l)
    return (
        c10 * (J ** (-2 / 3) * sum(x * x for x in l) - 3)
        + c01 * (J ** (-4 / 3) * _I2(l) - 3)
        + k / 2 * (J - 1) ** 2
    )


def W_nhc(l, mu=MU, lam=LAM):
    lnJ = math.log(_J(l))
    return mu / 2 * (sum(x * x for x in l) - 3) - mu * lnJ + lam / 2 * lnJ**2


def W_svk(l, mu=MU, lam=LAM):
    E = [(x * x - 1) / 2 for x in l]
    return lam / 2 * sum(E) ** 2 + mu * sum(e * e for e in E)


def W_py(l, c=(0.3 * MU, 0.2 * MU, 0.1 * MU, 0.05 * MU, 0.08 * MU), k=K):
    J = _J(l)
    x, y = J ** (-2 / 3) * sum(v * v for v in l) - 3, J ** (-4 / 3) * _I2(l) - 3
    return c[0] * x + c[1] * y + c[2] * x * x + c[3] * y * y + c[4] * x * y + k / 2 * (J - 1) ** 2


def W_ab(l, mu=MU, lm=2.0, k=K):
    J = _J(l)
    I1b = J ** (-2 / 3) * sum(x * x for x in l)
    C = (1 / 2, 1 / 20, 11 / 1050, 19 / 7000, 519 / 673750)
    w = sum(C[i] / lm ** (2 * i) * (I1b ** (i + 1) - 3 ** (i + 1)) for i in range(5))
    return mu * w + k / 2 * ((J * J - 1) / 2 - math.log(J))


def W_ti(l, mu=MU, k=K, eta=2 * MU):  # fibres along x, the loading axis
    J = _J(l)
    I1b = J ** (-2 / 3) * sum(x * x for x in l)
    I4b = J ** (-2 / 3) * l[0] ** 2
    return mu / 2 * (I1b - 3) + eta / 2 * (I4b - 1) ** 2 + k / 2 * (J - 1) ** 2


# Material name → (pliant material, strain energy W(λ1, λ2, λ3) [Pa], stretches where the
# homogeneous solution is what a quasi-static solve finds: the polynomial's C20/C02 stiffening at
# 1.5 outruns the step set by its small-strain modulus (1.4 is fine), and fibres in compression (TI
# at 0.7) lose ellipticity (η/2 (Ī4 − 1)² is not convex for Ī4 < 1: the cube deforms unevenly)).
UNIAXIAL = {
    "NeoHookean": (mat.NeoHookean(mu=MU, K=K), W_nh, (0.7, 1.2, 1.5)),
    "MooneyRivlin": (mat.MooneyRivlin(C10=0.3 * MU, C01=0.2 * MU, K=K), W_mr, (0.7, 1.2, 1.5)),
    "NeoHookeanCoupled": (mat.NeoHookeanCoupled(mu=MU, lam=LAM), W_nhc, (0.7, 1.2, 1.5)),
    "StVenantKirchhoff": (mat.StVenantKirchhoff(mu=MU, lam=LAM), W_svk, (0.7, 1.2, 1.5)),
    "Polynomial": (
        mat.Polynomial(0.3 * MU, 0.2 * MU, 0.1 * MU, 0.05 * MU, 0.08 * MU, K=K),
        W_py,
        (0.7, 1.2, 1.4),
    ),
    "ArrudaBoyce": (mat.ArrudaBoyce(mu=MU, lambda_m=2.0, K=K), W_ab, (0.7, 1.2, 1.5)),
    "TransverselyIsotropic": (
        mat.TransverselyIsotropic(MU, K, 2 * MU, (2.0, 0.0, 0.0)),
        W_ti,
        (0.9, 1.2, 1.5),
    ),
}


def nominal(W, l, i, h=1e-6):
    """Principal nominal stress P_i = ∂W/∂λ_i [Pa] (Ogden 1984, §4.3), central difference."""
    a, b = list(l), list(l)
    a[i] += h
    b[i] -= h
    return (W(a) - W(b)) / (2 * h)


def uniaxial_reference(W, stretch):
    """Uniaxial stress along x at ``stretch``: (P_x [Pa], lateral stretch) with P_y = P_z = 0."""
    lt = brentq(lambda t: nominal(W, (stretch, t, t), 1), 0.3, 3.0, xtol=1e-14)
    return nominal(W, (stretch, lt, lt), 0), lt


def timoshenko_tip_deflection(P, L, H, E, nu):
    """Tip deflection [m] of a square (H × H) cantilever of length L under a tip load P [N]:
    δ = PL³/(3EI) + PL/(κGA), κ = 5/6 (Timoshenko & Gere, Mechanics of Materials; Cowper 1966)."""
    I, A, G, kappa = H**4 / 12, H * H, E / (2 * (1 + nu)), 5.0 / 6.0
    return P * L**3 / (3 * E * I) + P * L / (kappa * G * A)


def lame_radial_displacement(r, a, b, p, E, nu):
    """Radial displacement [m] at radius r of a thick-walled sphere (radii a < b) under internal
    pressure p [Pa]: u_r = p a³ / (E (b³ − a³)) [(1 − 2ν) r + (1 + ν) b³ / (2 r²)] (Timoshenko &
    Goodier, Theory of Elasticity, §141)."""
    return p * a**3 / (E * (b**3 - a**3)) * ((1 - 2 * nu) * r + (1 + nu) * b**3 / (2 * r**2))


def lame_volumetric_strain(a, b, p, E, nu):
    """The uniform volumetric strain tr ε = 3 (1 − 2ν) p a³ / (E (b³ − a³)) of Lamé's sphere."""
    return 3 * (1 - 2 * nu) * p * a**3 / (E * (b**3 - a**3))


def hertz_force(delta, R, E, nu):
    """Force [N] of a rigid sphere of radius R pressed δ [m] into an elastic half-space:
    F = 4/3 E* √R δ^1.5, E* = E / (1 − ν²) (Johnson, Contact Mechanics, 1985, §4.2, eq. 4.22-4.23)."""
    return 4.0 / 3.0 * E / (1 - nu**2) * math.sqrt(R) * delta**1.5


def torsion_torque(mu, psi, a):
    """Torque [N·m] that twists a solid circular cylinder of incompressible Neo-Hookean material
    (shear modulus mu [Pa], radius a [m]) by ψ [rad/m] at fixed length, each cross-section turning
    rigidly: M = π μ ψ a⁴ / 2, exact at any twist (Rivlin 1949, Phil. Trans. R. Soc. A 242:173,
    with C2 = 0; Ogden, Non-linear Elastic Deformations, 1984, §5.2.3)."""
    return math.pi * mu * psi * a**4 / 2.0


def torsion_axial_force(mu, psi, a):
    """Axial force [N] on the ends of that twisted cylinder to hold its length: N = −π μ ψ² a⁴ / 4
    (compressive: the Poynting effect, second order in the twist; same sources)."""
    return -math.pi * mu * psi**2 * a**4 / 4.0


def p_wave_speed(E, nu, rho):
    """Speed [m/s] of a plane longitudinal (P) wave, c_p = √((λ + 2μ)/ρ) with the constrained
    modulus λ + 2μ = E(1 − ν)/((1 + ν)(1 − 2ν)) (Graff, Wave Motion in Elastic Solids, 1975, §5.1)."""
    return math.sqrt(E * (1 - nu) / ((1 + nu) * (1 - 2 * nu) * rho))


def elastica_tip(alpha):
    """Tip of a clamped inextensible elastica under a dead transverse tip load, α = PL²/(EI):
    (transverse deflection / L, axial shortening / L, tip rotation [rad]). θ'' = −α cos θ on
    s ∈ [0, 1], θ(0) = 0, θ'(1) = 0, solved by collocation (scipy's solve_bvp, tolerance 1e-10),
    then integrated; it reproduces Bisshopp & Drucker's table (Q. Appl. Math. 3, 1945: 0.302,
    0.494, 0.603 at α = 1, 2, 3)."""
    import numpy as np
    from scipy.integrate import quad, solve_bvp

    s = np.linspace(0.0, 1.0, 201)
    guess = np.vstack([0.25 * alpha * s * (2 - s), 0.5 * alpha * (1 - s)])
    sol = solve_bvp(
        lambda _, y: np.vstack([y[1], -alpha * np.cos(y[0])]),
        lambda a, b: np.array([a[0], b[1]]),
        s,
        guess,
        tol=1e-10,
        max_nodes=100_000,
    )
    if not sol.success:
        raise RuntimeError(f"elastica at α = {alpha}: {sol.message}")
    theta = lambda x: float(sol.sol(x)[0])  # noqa: E731
    transverse = quad(lambda x: math.sin(theta(x)), 0.0, 1.0, epsabs=1e-12)[0]
    shortening = 1.0 - quad(lambda x: math.cos(theta(x)), 0.0, 1.0, epsabs=1e-12)[0]
    return transverse, shortening, theta(1.0)


def membrane_stress_2d(material, C):
    """A membrane material's own 2nd Piola–Kirchhoff resultant S h [N/m] (2 × 2) and energy per
    reference area h W [J/m²] at the in-plane C (2 × 2), compression carried (pliant's
    NeoHookeanMembrane or StVKMembrane): Neo-Hookean S = μ h (I − C⁻¹/det C), W h = μ h/2 (tr C +
    1/det C − 3) (Bonet et al. 2000); St Venant–Kirchhoff S = h (λ' tr E I + 2 μ E),
    W h = h (λ'/2 tr² E + μ E:E), λ' = E ν/(1 − ν²) (plane stress)."""
    import numpy as np

    from ..materials.membrane import NeoHookeanMembrane

    h = material.thickness
    if isinstance(material, NeoHookeanMembrane):
        mu, J2 = material.mu, np.linalg.det(C)
        return mu * h * (np.eye(2) - np.linalg.inv(C) / J2), 0.5 * mu * h * (np.trace(C) + 1 / J2 - 3)
    Y, nu = material.E, material.nu
    lam, mu = Y * nu / (1 - nu**2), Y / (2 * (1 + nu))
    E = 0.5 * (C - np.eye(2))
    S = h * (lam * np.trace(E) * np.eye(2) + 2 * mu * E)
    return S, h * (0.5 * lam * np.trace(E) ** 2 + mu * np.sum(E * E))


def tension_field(material, F2):
    """Tension-field theory (Roddeman, Drukker, Oomens & Janssen 1987; Pipkin 1986) in Cartesian
    components for a membrane material (membrane_stress_2d) at the in-plane gradient F2 (2 × 2):
    the state ('taut', 'slack', 'wrinkled'), S h [N/m] (2 × 2) and h W [J/m²]. Slack where the major
    principal Green strain e1 ≤ 0; taut where the material's smaller principal stress is ≥ 0;
    wrinkled otherwise: uniaxial S1 along e1's direction at the free width (Neo-Hookean
    c2 = c1^(−1/2): S1 = μ (1 − c1^(−3/2)), W = μ/2 (c1 + 2/√c1 − 3); St Venant–Kirchhoff by
    Poisson: S1 = E e1, W = E e1²/2)."""
    import numpy as np

    from ..materials.membrane import NeoHookeanMembrane

    C = F2.T @ F2
    e, N = np.linalg.eigh(0.5 * (C - np.eye(2)))  # ascending: e2, e1
    e1, n1 = e[1], N[:, 1]
    S, W = membrane_stress_2d(material, C)
    if e1 <= 0:
        return "slack", np.zeros((2, 2)), 0.0
    if np.linalg.eigvalsh(S)[0] >= 0:
        return "taut", S, W
    h, c1 = material.thickness, 1 + 2 * e1
    if isinstance(material, NeoHookeanMembrane):
        s1, W = material.mu * h * (1 - c1**-1.5), 0.5 * material.mu * h * (c1 + 2 / np.sqrt(c1) - 3)
    else:
        s1, W = material.E * h * e1, 0.5 * material.E * h * e1**2
    return "wrinkled", s1 * np.outer(n1, n1), W


def balloon_limit_pressure(mu, h, R):
    """The largest internal pressure [Pa] a spherical incompressible Neo-Hookean membrane (shear
    modulus μ, thickness h, radius R) holds: p(λ) = 2 μ h/R (λ⁻¹ − λ⁻⁷) peaks at λ = 7^(1/6)."""
    return 2 * mu * h / R * (7 ** (-1 / 6) - 7 ** (-7 / 6))


def balloon_stretch(p, h, R, mu=None, E=None, nu=None):
    """Equibiaxial stretch λ of a spherical membrane (thickness h, radius R [m]) under internal
    pressure p [Pa], from Laplace's p = 2 t/r with the membrane's tension t: incompressible
    Neo-Hookean (``mu``) p = 2 μ h/R (λ⁻¹ − λ⁻⁷), on the stable branch below the limit pressure;
    plane-stress St Venant–Kirchhoff (``E``, ``nu``) p = E h (λ² − 1)/((1 − ν) λ R)."""
    from scipy.optimize import brentq

    if mu is not None:
        return brentq(lambda lam: 2 * mu * h / R * (1 / lam - lam**-7) - p, 1.0, 7 ** (1 / 6))
    return brentq(lambda lam: E * h * (lam**2 - 1) / ((1 - nu) * lam * R) - p, 1.0, 10.0)
