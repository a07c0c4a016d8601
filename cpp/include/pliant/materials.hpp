// pliant — hyperelastic materials, header-only, host and device.
//
// Each material is a small functor with three methods over the element's kinematics k (F, the
// displacement gradient H = F − I, the Green–Lagrange strain E, J and J − 1):
//   pk2(k)    second Piola–Kirchhoff stress S [Pa]
//   pk1(k)    first Piola–Kirchhoff stress P = F S [Pa] (what TLED's nodal forces need)
//   energy(k) strain-energy density W [J/m³ = Pa]
// and the parameter-only `dilatational_modulus()` = λ + 2μ [Pa] for the critical time step and
// `shear_modulus()` = μ [Pa] at small strain (with it, stiffness-proportional damping's viscous stress).
// Conventions: C = FᵀF = I + 2E, J = det F, I1 = tr C, I2 = ½(I1² − tr C²), Ī1 = J^(−2/3) I1,
// Ī2 = J^(−4/3) I2.
//
// Precision: stresses are formed from E and J − 1 computed from H, never as differences of
// numbers near 1 (C − I, J − 1, I − I1/3 C⁻¹): in float32 those lose every digit of a strain of
// 1e-7 and leave a force noise of ε_float·E·area per element, which set a floor on quasi-static
// residuals (a 1e-5-strain Hertz block stalled at 10 % in float32). Identities used:
// I − I1/3 C⁻¹ = 2 C⁻¹ dev E;  I − C⁻¹ = 2 C⁻¹ E;
// I1 I − C − 2/3 I2 C⁻¹ = C⁻¹ dev(I1 C − C²) = C⁻¹ [(2 I1 − 4) dev E − 4 dev E²].
#pragma once

#include <type_traits>

#include <cmath>

#include "mat3.hpp"

namespace pliant {

/// Material type codes, shared with Python (pliant.materials) and the model description.
enum class MaterialKind : int {
    NeoHookean = 0,             // decoupled, params (mu, K)
    MooneyRivlin = 1,           // decoupled, params (C10, C01, K)
    NeoHookeanCoupled = 2,      // Bonet & Wood, params (mu, lambda)
    StVenantKirchhoff = 3,      // params (mu, lambda)
    LinearElastic = 4,          // small strain, params (mu, lambda)
    Polynomial = 5,             // decoupled, params (C10, C01, C20, C02, C11, K)
    ArrudaBoyce = 6,            // decoupled, params (mu, lambda_m, K)
    TransverselyIsotropic = 7,  // decoupled, params (mu, K, eta, a1, a2, a3)
};

/// Kinematics of one element from its displacement gradient H = ∇X u (dimensionless).
template <class T>
struct Kinematics {
    Mat3<T> H, F;  // displacement and deformation gradients, F = I + H
    Sym3<T> E;     // Green–Lagrange strain ½(H + Hᵀ + HᵀH)
    T J, Jm1;      // det F and det F − 1 = tr H + ½((tr H)² − tr H²) + det H
    T j23;         // J^(−2/3) (inv_cbrt; the decoupled materials' isochoric factor)
};

/// Kinematics of H without j23 (kinematics, below, sets it).
template <class T>
PLIANT_HD Kinematics<T> kinematics_of(const Mat3<T>& H) {
    Kinematics<T> k;
    const T* h = H.a;
    k.H = H;
    k.F = H;
    k.F.a[0] += T(1);
    k.F.a[4] += T(1);
    k.F.a[8] += T(1);
    const T hf = T(0.5);
    k.E = {h[0] + hf * (h[0] * h[0] + h[3] * h[3] + h[6] * h[6]),
           h[4] + hf * (h[1] * h[1] + h[4] * h[4] + h[7] * h[7]),
           h[8] + hf * (h[2] * h[2] + h[5] * h[5] + h[8] * h[8]),
           hf * (h[1] + h[3] + h[0] * h[1] + h[3] * h[4] + h[6] * h[7]),
           hf * (h[5] + h[7] + h[1] * h[2] + h[4] * h[5] + h[7] * h[8]),
           hf * (h[2] + h[6] + h[0] * h[2] + h[3] * h[5] + h[6] * h[8])};
    const T tr = h[0] + h[4] + h[8];
    const T tr2 =
        h[0] * h[0] + h[4] * h[4] + h[8] * h[8] + T(2) * (h[1] * h[3] + h[2] * h[6] + h[5] * h[7]);  // tr H²
    k.Jm1 = tr + hf * (tr * tr - tr2) + det(H);
    k.J = T(1) + k.Jm1;
    k.j23 = T(0);
    return k;
}

/// Kinematics of H, J^(−2/3) included (dropped by the compiler where no material reads it).
template <class T>
PLIANT_HD Kinematics<T> kinematics(const Mat3<T>& H) {
    Kinematics<T> k = kinematics_of(H);
    k.j23 = inv_cbrt(k.J * k.J);
    return k;
}

/// kinematics(H) with J^(−2/3) given (j23: computed earlier from the same H, e.g. by T4ANP's
/// pass (1)), not computed again.
template <class T>
PLIANT_HD Kinematics<T> kinematics(const Mat3<T>& H, T j23) {
    Kinematics<T> k = kinematics_of(H);
    k.j23 = j23;
    return k;
}

/// C⁻¹ = (I + 2E)⁻¹ with det C = J².
template <class T>
PLIANT_HD Sym3<T> inverse_cauchy_green(const Kinematics<T>& k) {
    return inverse(add_identity(T(1), scale(T(2), k.E)), k.J * k.J);
}

/// S of a decoupled material W = W_iso(C̄) + U(J) with the pressure p (U'(J), or an averaged one):
/// S = S_iso + J p C⁻¹ (Holzapfel 2000, §6.4, eq. 6.89). Materials with `decoupled = true` provide
/// pk2_iso(k, C⁻¹) and pressure(k).
template <class M, class T>
PLIANT_HD Sym3<T> decoupled_pk2(const M& m, const Kinematics<T>& k, T p) {
    const Sym3<T> Ci = inverse_cauchy_green(k);
    return axpby(T(1), m.pk2_iso(k, Ci), k.J * p, Ci);
}

/// Decoupled Neo-Hookean, W = μ/2 (Ī1 − 3) + K/2 (J − 1)²;
/// S = μ J^(−2/3) (I − I1/3 C⁻¹) + K J (J − 1) C⁻¹ (Taylor et al. 2008, IEEE TMI 27(5), eq. 10;
/// NiftySim's "NH"), evaluated as 2μ J^(−2/3) C⁻¹ dev E + K J (J − 1) C⁻¹.
template <class T>
struct NeoHookean {
    T mu, K;
    static constexpr bool decoupled = true;
    PLIANT_HD T dilatational_modulus() const { return K + T(4) / T(3) * mu; }
    PLIANT_HD T shear_modulus() const { return mu; }
    PLIANT_HD T pressure(const Kinematics<T>& k) const { return K * k.Jm1; }  // U'(J)
    PLIANT_HD Sym3<T> pk2_iso(const Kinematics<T>& k, const Sym3<T>& Ci) const {
        return scale(T(2) * mu * k.j23, mul_commuting(Ci, dev(k.E)));
    }
    PLIANT_HD Sym3<T> pk2(const Kinematics<T>& k) const { return decoupled_pk2(*this, k, pressure(k)); }
    PLIANT_HD Mat3<T> pk1(const Kinematics<T>& k) const { return mul(k.F, pk2(k)); }
    PLIANT_HD T energy(const Kinematics<T>& k) const {
        const T I1 = T(3) + T(2) * trace(k.E);
        return mu / T(2) * (k.j23 * I1 - T(3)) + K / T(2) * k.Jm1 * k.Jm1;
    }
};

/// ln J from J − 1 without cancellation: u = 1 + x rounded, ln J = ln u + (x − (u − 1))/u (the
/// first-order correction for the rounding of u; Goldberg 1991, "What every computer scientist
/// should know about floating-point arithmetic", Theorem 4), ln u by log_plain: branch-free, so
/// it vectorizes, and within a few ulps for every J > 0.
template <class T>
PLIANT_HD T log_J(T Jm1) {
    const T u = T(1) + Jm1;
    return log_plain(u) + (Jm1 - (u - T(1))) / u;
}

/// Isochoric 2nd Piola–Kirchhoff stress of a decoupled W(Ī1, Ī2) with W1 = ∂W/∂Ī1, W2 = ∂W/∂Ī2:
/// S_iso = 2W1 J^(−2/3)(I − I1/3 C⁻¹) + 2W2 J^(−4/3)(I1 I − C − 2/3 I2 C⁻¹) (Holzapfel, Nonlinear
/// Solid Mechanics 2000, §6.5, eqs. 6.142–6.147), evaluated through E as
/// C⁻¹ [(2a + b (2 I1 − 4)) dev E − 4b dev E²], a = 2W1 J^(−2/3), b = 2W2 J^(−4/3).
template <class T>
PLIANT_HD Sym3<T> isochoric_pk2(const Kinematics<T>& k, const Sym3<T>& Ci, T W1, T W2, T j23) {
    const T I1 = T(3) + T(2) * trace(k.E);
    const T a = T(2) * W1 * j23;
    const T b = T(2) * W2 * j23 * j23;
    const Sym3<T> D =
        axpby(T(2) * a + b * (T(2) * I1 - T(4)), dev(k.E), T(-4) * b, dev(mul_commuting(k.E, k.E)));
    return mul_commuting(Ci, D);
}

/// Isochoric invariants Ī1 = J^(−2/3) I1, Ī2 = J^(−4/3) I2 of C = I + 2E, given j23 = J^(−2/3).
template <class T>
PLIANT_HD void isochoric_invariants(const Kinematics<T>& k, T j23, T& I1b, T& I2b) {
    const Sym3<T> C = add_identity(T(1), scale(T(2), k.E));
    const T I1 = trace(C);
    I1b = j23 * I1;
    I2b = j23 * j23 * T(0.5) * (I1 * I1 - ddot(C));
}

/// Decoupled polynomial (N = 2), W = Σ_{i+j=1,2} Cij (Ī1 − 3)^i (Ī2 − 3)^j + K/2 (J − 1)²
/// (NiftySim user guide v2.4, App. A.1.3, eq. 7; Holzapfel 2000, §6.5); Mooney–Rivlin is
/// C20 = C02 = C11 = 0. Parameters (C10, C01, C20, C02, C11, K).
template <class T>
struct Polynomial {
    T C10, C01, C20, C02, C11, K;
    static constexpr bool decoupled = true;
    PLIANT_HD T dilatational_modulus() const { return K + T(8) / T(3) * (C10 + C01); }
    PLIANT_HD T shear_modulus() const { return T(2) * (C10 + C01); }
    PLIANT_HD T pressure(const Kinematics<T>& k) const { return K * k.Jm1; }
    PLIANT_HD Sym3<T> pk2_iso(const Kinematics<T>& k, const Sym3<T>& Ci) const {
        const T j23 = k.j23;
        T I1b, I2b;
        isochoric_invariants(k, j23, I1b, I2b);
        const T W1 = C10 + T(2) * C20 * (I1b - T(3)) + C11 * (I2b - T(3));
        const T W2 = C01 + T(2) * C02 * (I2b - T(3)) + C11 * (I1b - T(3));
        return isochoric_pk2(k, Ci, W1, W2, j23);
    }
    PLIANT_HD Sym3<T> pk2(const Kinematics<T>& k) const { return decoupled_pk2(*this, k, pressure(k)); }
    PLIANT_HD Mat3<T> pk1(const Kinematics<T>& k) const { return mul(k.F, pk2(k)); }
    PLIANT_HD T energy(const Kinematics<T>& k) const {
        T I1b, I2b;
        isochoric_invariants(k, k.j23, I1b, I2b);
        const T x = I1b - T(3), y = I2b - T(3);
        return C10 * x + C01 * y + C20 * x * x + C02 * y * y + C11 * x * y + K / T(2) * k.Jm1 * k.Jm1;
    }
};

/// Decoupled Mooney–Rivlin, W = C10 (Ī1 − 3) + C01 (Ī2 − 3) + K/2 (J − 1)² (Holzapfel 2000,
/// §6.5): the polynomial with C20 = C02 = C11 = 0. Parameters (C10, C01, K).
template <class T>
struct MooneyRivlin : Polynomial<T> {
    PLIANT_HD MooneyRivlin(T c10, T c01, T k) : Polynomial<T>{c10, c01, T(0), T(0), T(0), k} {}
};

/// Decoupled Arruda–Boyce (eight-chain), W = μ Σ_{i=1..5} C_i / λm^(2i−2) (Ī1^i − 3^i)
/// + K/2 ((J² − 1)/2 − ln J), C = 1/2, 1/20, 11/1050, 19/7000, 519/673750 (Arruda & Boyce 1993,
/// JMPS 41:389; NiftySim user guide v2.4, App. A.1.2, eq. 6). S = 2W1 J^(−2/3)(I − I1/3 C⁻¹) +
/// K/2 (J² − 1) C⁻¹. Parameters (μ, λm, K); small-strain shear modulus μ (1 + 3/(5λm²) + …).
template <class T>
struct ArrudaBoyce {
    T mu, lambda_m, K;
    PLIANT_HD T W1(T I1b) const {  // ∂W/∂Ī1 = μ Σ i C_i Ī1^(i−1) / λm^(2i−2) (Horner in Ī1/λm²)
        const T x = I1b / (lambda_m * lambda_m);
        return mu * (T(0.5) + x * (T(2) / T(20) +
                                   x * (T(33) / T(1050) + x * (T(76) / T(7000) + x * T(2595) / T(673750)))));
    }
    static constexpr bool decoupled = true;
    PLIANT_HD T dilatational_modulus() const { return K + T(8) / T(3) * W1(T(3)); }
    PLIANT_HD T shear_modulus() const { return T(2) * W1(T(3)); }
    PLIANT_HD T pressure(const Kinematics<T>& k) const {  // U'(J) = K/2 (J − 1/J)
        return K / T(2) * k.Jm1 * (k.J + T(1)) / k.J;
    }
    PLIANT_HD Sym3<T> pk2_iso(const Kinematics<T>& k, const Sym3<T>& Ci) const {
        const T j23 = k.j23;
        return isochoric_pk2(k, Ci, W1(j23 * (T(3) + T(2) * trace(k.E))), T(0), j23);
    }
    PLIANT_HD Sym3<T> pk2(const Kinematics<T>& k) const { return decoupled_pk2(*this, k, pressure(k)); }
    PLIANT_HD Mat3<T> pk1(const Kinematics<T>& k) const { return mul(k.F, pk2(k)); }
    PLIANT_HD T energy(const Kinematics<T>& k) const {
        const T I1b = k.j23 * (T(3) + T(2) * trace(k.E));
        const T c[5] = {T(0.5), T(1) / T(20), T(11) / T(1050), T(19) / T(7000), T(519) / T(673750)};
        T w = T(0), p = T(1), q = T(1), l = T(1);
        for (int i = 0; i < 5; ++i) {
            p *= I1b;
            q *= T(3);
            w += c[i] / l * (p - q);
            l *= lambda_m * lambda_m;
        }
        return mu * w + K / T(2) * (T(0.5) * k.Jm1 * (k.J + T(1)) - log_J(k.Jm1));
    }
};

/// Transversely isotropic (decoupled), W = μ/2 (Ī1 − 3) + η/2 (Ī4 − 1)² + K/2 (J − 1)², Ī4 =
/// J^(−2/3) a·Ca with the unit fibre direction a (NiftySim user guide v2.4, App. A.1.4, eq. 8;
/// Holzapfel 2000, §6.7). S = NH + 2η (Ī4 − 1) J^(−2/3)(a ⊗ a − I4/3 C⁻¹). Parameters (μ, K, η, a).
template <class T>
struct TransverselyIsotropic {
    T mu, K, eta, a[3];
    static constexpr bool decoupled = true;
    PLIANT_HD T dilatational_modulus() const { return K + T(4) / T(3) * mu + T(4) * eta; }
    PLIANT_HD T shear_modulus() const { return mu; }  // of the matrix (the fibre adds along a)
    PLIANT_HD T pressure(const Kinematics<T>& k) const { return K * k.Jm1; }
    PLIANT_HD T I4(const Kinematics<T>& k) const {  // a·Ca = 1 + 2 a·Ea
        const Sym3<T>& E = k.E;
        return T(1) + T(2) * (a[0] * (E.xx * a[0] + E.xy * a[1] + E.xz * a[2]) +
                              a[1] * (E.xy * a[0] + E.yy * a[1] + E.yz * a[2]) +
                              a[2] * (E.xz * a[0] + E.yz * a[1] + E.zz * a[2]));
    }
    PLIANT_HD Sym3<T> pk2_iso(const Kinematics<T>& k, const Sym3<T>& Ci) const {
        const T j23 = k.j23;
        const T i4 = I4(k);
        const T g = T(2) * eta * (j23 * i4 - T(1)) * j23;
        const Sym3<T> aa = {a[0] * a[0], a[1] * a[1], a[2] * a[2], a[0] * a[1], a[1] * a[2], a[0] * a[2]};
        return axpby(T(2) * mu * j23, mul_commuting(Ci, dev(k.E)), g, axpby(T(1), aa, -i4 / T(3), Ci));
    }
    PLIANT_HD Sym3<T> pk2(const Kinematics<T>& k) const { return decoupled_pk2(*this, k, pressure(k)); }
    PLIANT_HD Mat3<T> pk1(const Kinematics<T>& k) const { return mul(k.F, pk2(k)); }
    PLIANT_HD T energy(const Kinematics<T>& k) const {
        const T j23 = k.j23;
        const T d4 = j23 * I4(k) - T(1);
        return mu / T(2) * (j23 * (T(3) + T(2) * trace(k.E)) - T(3)) + eta / T(2) * d4 * d4 +
               K / T(2) * k.Jm1 * k.Jm1;
    }
};

/// Coupled compressible Neo-Hookean, W = μ/2 (I1 − 3) − μ ln J + λ/2 (ln J)²;
/// S = μ (I − C⁻¹) + λ ln J C⁻¹ (Bonet & Wood, Nonlinear Continuum Mechanics for FEA, 2nd ed.,
/// §6.4.3, eq. 6.28; FEBio's "neo-Hookean"), evaluated as 2μ C⁻¹ E + λ ln J C⁻¹.
template <class T>
struct NeoHookeanCoupled {
    T mu, lambda;
    static constexpr bool decoupled = false;
    PLIANT_HD T dilatational_modulus() const { return lambda + T(2) * mu; }
    PLIANT_HD T shear_modulus() const { return mu; }
    PLIANT_HD Sym3<T> pk2(const Kinematics<T>& k) const {
        const Sym3<T> Ci = inverse_cauchy_green(k);
        return axpby(T(2) * mu, mul_commuting(Ci, k.E), lambda * log_J(k.Jm1), Ci);
    }
    PLIANT_HD Mat3<T> pk1(const Kinematics<T>& k) const { return mul(k.F, pk2(k)); }
    PLIANT_HD T energy(const Kinematics<T>& k) const {
        const T lnJ = log_J(k.Jm1);
        return mu * trace(k.E) - mu * lnJ + lambda / T(2) * lnJ * lnJ;
    }
};

/// St Venant–Kirchhoff, W = λ/2 (tr E)² + μ E:E with E = ½(C − I); S = λ tr(E) I + 2μ E
/// (Bonet & Wood, 2nd ed., §6.4.2, eq. 6.19).
template <class T>
struct StVenantKirchhoff {
    T mu, lambda;
    static constexpr bool decoupled = false;
    PLIANT_HD T dilatational_modulus() const { return lambda + T(2) * mu; }
    PLIANT_HD T shear_modulus() const { return mu; }
    PLIANT_HD Sym3<T> pk2(const Kinematics<T>& k) const {
        return add_identity(lambda * trace(k.E), scale(T(2) * mu, k.E));
    }
    PLIANT_HD Mat3<T> pk1(const Kinematics<T>& k) const { return mul(k.F, pk2(k)); }
    PLIANT_HD T energy(const Kinematics<T>& k) const {
        const T trE = trace(k.E);
        return lambda / T(2) * trE * trE + mu * ddot(k.E);
    }
};

/// Small-strain linear elasticity, σ = λ tr(ε) I + 2μ ε with ε = sym(H) = sym(F − I); the nodal
/// forces use P = σ (geometrically linear; Zienkiewicz & Taylor, The FEM vol. 1, §6.2). Not
/// objective: a baseline for small displacements only.
template <class T>
struct LinearElastic {
    T mu, lambda;
    static constexpr bool decoupled = false;
    PLIANT_HD T dilatational_modulus() const { return lambda + T(2) * mu; }
    PLIANT_HD T shear_modulus() const { return mu; }
    PLIANT_HD Sym3<T> pk2(const Kinematics<T>& k) const {
        const Sym3<T> e = sym(k.H);
        return add_identity(lambda * trace(e), scale(T(2) * mu, e));
    }
    PLIANT_HD Mat3<T> pk1(const Kinematics<T>& k) const {
        const Sym3<T> s = pk2(k);
        return {{s.xx, s.xy, s.xz, s.xy, s.yy, s.yz, s.xz, s.yz, s.zz}};
    }
    PLIANT_HD T energy(const Kinematics<T>& k) const {
        const Sym3<T> e = sym(k.H);
        const T tr = trace(e);
        return lambda / T(2) * tr * tr + mu * ddot(e);
    }
};

/// The T4ANP stabilization γ = μ/K (at most 1) of decoupled material m at small strain: an element's
/// volume change apart from its nodes' average then meets a stiffness of about μ whatever K (p(J_e) −
/// p̄ ≈ K (J_e − J̄)), which keeps it from collapsing without bringing back the locking that K
/// causes (docs/engine.md, "Volume modes and the stabilization").
template <class M>
PLIANT_HD auto anp_shear_gamma(const M& m) {
    const auto g = m.shear_modulus() / m.K;
    return g < decltype(g)(1) ? g : decltype(g)(1);
}

/// A decoupled material whose pressure is replaced by the element's average of the nodal pressures
/// (the average nodal pressure tetrahedron, T4ANP: Bonet & Burton 1998, Commun. Numer. Meth. Eng.
/// 14:437; Joldes, Wittek & Miller 2009, Commun. Numer. Meth. Eng. 25:827): S = S_iso + J p C⁻¹,
/// p = p̄ + γ (p(J_e) − p̄). γ = 0 is plain T4ANP, whose averaging leaves element-level volume
/// modes (a checkerboard of J) unresisted; γ > 0 mixes back that fraction of the element's own
/// pressure, a stabilization in the manner of Puso & Solberg (2006, IJNME 67:841, eq. 33: the
/// nodal strain plus α times the element's deviation from it).
template <class M, class T>
struct AveragedPressure {
    const M& m;
    T p;     // p̄ [Pa]
    T stab;  // γ [1]
    PLIANT_HD Sym3<T> pk2(const Kinematics<T>& k) const {
        return decoupled_pk2(m, k, p + stab * (m.pressure(k) - p));
    }
    PLIANT_HD Mat3<T> pk1(const Kinematics<T>& k) const { return mul(k.F, pk2(k)); }
    PLIANT_HD T energy(const Kinematics<T>& k) const { return m.energy(k); }
};

/// Prony series of a visco-hyperelastic material: isochoric terms (α_i, τ_i [s]), i < n_iso, then
/// volumetric ones at [kPronyMax/2 + i], i < n_vol (NiftySim user guide v2.4, App. A.2, eqs. 9-10).
constexpr int kPronyMax = 8;
template <class T>
struct Prony {
    int n_iso = 0, n_vol = 0;
    T alpha[kPronyMax] = {}, tau[kPronyMax] = {};
    PLIANT_HD int terms() const { return n_iso + n_vol; }  // 0: elastic
    /// Where state slot t's (α, τ) sit: the isochoric terms' slots first, then the volumetric ones.
    PLIANT_HD int term_index(int t) const { return t < n_iso ? t : kPronyMax / 2 + (t - n_iso); }
    /// The terms as the middle phases of a phased launch (visco_terms): the isochoric ones in one
    /// pass, the volumetric ones in another (at most kPronyMax / 2 = kPhaseItemsMax each).
    PLIANT_HD Phases phases() const {
        static_assert(kPronyMax / 2 <= kPhaseItemsMax);
        Phases ph;
        if (n_iso > 0) ph.first[ph.n] = 0, ph.size[ph.n++] = n_iso;
        if (n_vol > 0) ph.first[ph.n] = n_iso, ph.size[ph.n++] = n_vol;
        return ph;
    }
};

/// How a viscoelastic element treats its Prony state (ViscoMaterial::mode).
enum class ViscoMode : int {
    Advance = 0,       // a time step: advance the state by Δt
    Stored = 1,        // use the stored state (outputs, reactions)
    Relaxed = 2,       // fully relaxed, D_i = α_i S_e (quasi-static solutions)
    RelaxedStore = 3,  // the same, and store it (the state after a quasi-static solution)
};

/// The two elastic parts of a decoupled material's S that Prony terms relax (ViscoMaterial):
/// isochoric S_iso = pk2_iso and volumetric S_vol = J p C⁻¹ [Pa].
template <class T>
struct SplitStress {
    Sym3<T> iso, vol;
};
template <class M, class T>
PLIANT_HD SplitStress<T> split_pk2(const M& m, const Kinematics<T>& k) {
    const Sym3<T> Ci = inverse_cauchy_green(k);
    return {m.pk2_iso(k, Ci), scale(k.J * m.pressure(k), Ci)};
}

/// One Prony term's coefficients for a step dt [s]: α, and backward Euler's keep = τ/(Δt + τ) and
/// gain = Δt α/(Δt + τ) (prony_update). i: the term's (α, τ) slot (Prony::term_index).
template <class T>
struct PronyStep {
    T alpha, keep, gain;
};
template <class T>
PLIANT_HD PronyStep<T> prony_step(const Prony<T>& pr, int i, T dt) {
    const T den = dt + pr.tau[i];
    return {pr.alpha[i], pr.tau[i] / den, dt * pr.alpha[i] / den};
}

/// A Prony term's stress-like state D [Pa] of one element (Taylor et al. 2009, MICCAI, eqs. 9-12):
/// advanced by backward Euler, D ← τ/(Δt + τ) D + Δt α/(Δt + τ) S_e (k: prony_step), from the
/// elastic part S_e it relaxes (e: xx, yy, zz, xy, yz, xz); or the stored D; or the fully relaxed
/// D = α S_e (ViscoMode, fixed at compile time by kMode >= 0, else `mode`). d: the term's 6 state
/// values, stride `stride` apart. Output: D_out, the term's D.
template <int kMode, class T>
PLIANT_HD void prony_update(const PronyStep<T>& k, const T* e, T* d, int stride, ViscoMode mode, T* D_out) {
    const ViscoMode md = kMode >= 0 ? static_cast<ViscoMode>(kMode) : mode;
    PLIANT_UNROLL
    for (int c = 0; c < 6; ++c) {
        if (md == ViscoMode::Relaxed || md == ViscoMode::RelaxedStore) {
            D_out[c] = k.alpha * e[c];
            if (md == ViscoMode::RelaxedStore) d[c * stride] = D_out[c];
        } else if (md == ViscoMode::Stored) {
            D_out[c] = d[c * stride];
        } else {
            D_out[c] = k.keep * d[c * stride] + k.gain * e[c];
            d[c * stride] = D_out[c];
        }
    }
}

/// Prony term t's D (prony_update) from the element's elastic parts se: se.iso for an isochoric
/// term, se.vol for a volumetric one. d: the term's 6 state values, stride `stride` apart.
template <int kMode, class T>
PLIANT_HD Sym3<T> prony_term(const Prony<T>& pr, int t, T dt, const SplitStress<T>& se, T* d, int stride,
                             ViscoMode mode) {
    const T w = t < pr.n_iso ? T(1) : T(0);  // its stress: isochoric (1) or volumetric (0)
    const Sym3<T> s = axpby(w, se.iso, T(1) - w, se.vol);
    const T e[6] = {s.xx, s.yy, s.zz, s.xy, s.yz, s.xz};
    T D[6];
    prony_update<kMode>(prony_step(pr, pr.term_index(t), dt), e, d, stride, mode, D);
    return {D[0], D[1], D[2], D[3], D[4], D[5]};
}

/// Visco-hyperelastic response of a decoupled material (Taylor et al. 2009, "Modelling anisotropic
/// viscoelasticity for real-time soft tissue simulation", MICCAI, eqs. 9-12; NiftySim's NHV): each
/// Prony term keeps a stress-like state D_i (prony_term), and S = S_e,iso + S_e,vol − Σ D_i.
/// `mode` (ViscoMode): advance the state, use it, or the fully relaxed response D_i = α_i S_e (and
/// store it). q: the element's 6·(n_iso + n_vol) state values, stride `stride` between components.
/// The time step's kernels run the same terms as phases instead (visco_begin, below), which on
/// the CPU vectorize whatever the number of terms.
template <class M, class T>
struct ViscoMaterial {
    const M& m;
    const Prony<T>& pr;
    T dt;
    T* q;
    int stride;
    ViscoMode mode;
    PLIANT_HD Sym3<T> pk2(const Kinematics<T>& k) const {
        const SplitStress<T> se = split_pk2(m, k);
        Sym3<T> S = axpby(T(1), se.iso, T(1), se.vol);
        for (int t = 0; t < pr.terms(); ++t)
            S = axpby(T(1), S, T(-1), prony_term<-1>(pr, t, dt, se, q + 6 * t * stride, stride, mode));
        return S;
    }
    PLIANT_HD Mat3<T> pk1(const Kinematics<T>& k) const { return mul(k.F, pk2(k)); }
    PLIANT_HD T energy(const Kinematics<T>& k) const { return m.energy(k); }
};

/// ViscoMaterial's P = F S in phases over one slot's scratch s (s[k]: Dev::blocks_phased,
/// SlotScratch), so that the loop over the Prony terms runs around a SIMD loop over slots instead of
/// inside each slot (where its test stops the CPU's vectorizer; any number of terms then runs at
/// full width, the same arithmetic in the same order as ViscoMaterial). The scratch holds
/// kViscoScratch values: S [Pa] at 0..5 (xx, yy, zz, xy, yz, xz), S_iso at 6..11, S_vol at
/// 12..17, F at 18..26.
/// (1) visco_begin: S = S_iso + S_vol of kinematics k. (2) visco_terms, once for the isochoric terms
/// and once for the volumetric ones (Prony::phases): S −= D_t for each (prony_update; q: the slot's
/// state, stride apart). (3) visco_pk1: P = F S.
inline constexpr int kViscoScratch = 27;
template <class M, class T, class Scratch>
PLIANT_HD void visco_begin(const M& m, const Kinematics<T>& k, Scratch s) {
    const SplitStress<T> se = split_pk2(m, k);
    const auto put = [&](int o, const Sym3<T>& x) {
        s[o] = x.xx, s[o + 1] = x.yy, s[o + 2] = x.zz, s[o + 3] = x.xy, s[o + 4] = x.yz, s[o + 5] = x.xz;
    };
    put(0, axpby(T(1), se.iso, T(1), se.vol)), put(6, se.iso), put(12, se.vol);
    PLIANT_UNROLL
    for (int i = 0; i < 9; ++i) s[18 + i] = k.F.a[i];
}
/// Phase (2) for the K terms t0 .. t0 + K − 1, all isochoric or all volumetric: what the slots of a
/// block share (prony_chunk: the terms' coefficients, w = 1 for S_iso or 0 for S_vol, t0), then each
/// slot's terms (visco_terms), S and the stress they relax read once and S written once.
template <int K, class T>
struct PronyChunk {
    PronyStep<T> k[K];
    T w;
    int t0;
};
template <int K, class T>
PLIANT_HD PronyChunk<K, T> prony_chunk(const Prony<T>& pr, int t0, T dt) {
    PronyChunk<K, T> ch;
    PLIANT_UNROLL
    for (int j = 0; j < K; ++j) ch.k[j] = prony_step(pr, pr.term_index(t0 + j), dt);
    ch.w = t0 < pr.n_iso ? T(1) : T(0);
    ch.t0 = t0;
    return ch;
}
template <int kMode, int K, class T, class Scratch>
PLIANT_HD void visco_terms(const PronyChunk<K, T>& ch, T* q, int stride, ViscoMode mode, Scratch s) {
    T e[6], S[6];  // e: the blend of prony_term, S_iso or S_vol
    PLIANT_UNROLL
    for (int c = 0; c < 6; ++c) e[c] = ch.w * s[6 + c] + (T(1) - ch.w) * s[12 + c], S[c] = s[c];
    PLIANT_UNROLL
    for (int j = 0; j < K; ++j) {
        T D[6];
        prony_update<kMode>(ch.k[j], e, q + 6 * (ch.t0 + j) * stride, stride, mode, D);
        PLIANT_UNROLL
        for (int c = 0; c < 6; ++c) S[c] = S[c] - D[c];
    }
    PLIANT_UNROLL
    for (int c = 0; c < 6; ++c) s[c] = S[c];
}
template <class T, class Scratch>
PLIANT_HD Mat3<T> visco_pk1(Scratch s) {
    Mat3<T> F;
    PLIANT_UNROLL
    for (int i = 0; i < 9; ++i) F.a[i] = s[18 + i];
    return mul(F, Sym3<T>{s[0], s[1], s[2], s[3], s[4], s[5]});
}

/// Parameters per material (the most any material takes: TransverselyIsotropic's μ, K, η, a).
constexpr int kMaterialParams = 8;

/// Parameters of one element group's material, as passed from the model to the kernels.
template <class T>
struct MaterialParams {
    MaterialKind kind;
    T p[kMaterialParams];
};

/// Whether parameter k of a material kind is a modulus [Pa] (scaled by the viewer's stiffness
/// slider) rather than a stretch or a direction.
PLIANT_HD bool is_modulus(MaterialKind kind, int k) {
    if (kind == MaterialKind::ArrudaBoyce) return k != 1;           // λm
    if (kind == MaterialKind::TransverselyIsotropic) return k < 3;  // a
    return true;
}

/// The functor M (whose kind the caller knows) from its parameters: kernels build it per block
/// from the group's parameters in device memory, so that groups of one kind run in one launch.
template <class M, class T>
PLIANT_HD M make_material(const MaterialParams<T>& m) {
    if constexpr (std::is_same_v<M, MooneyRivlin<T>>) {
        return MooneyRivlin<T>(m.p[0], m.p[1], m.p[2]);
    } else if constexpr (std::is_same_v<M, Polynomial<T>>) {
        return Polynomial<T>{m.p[0], m.p[1], m.p[2], m.p[3], m.p[4], m.p[5]};
    } else if constexpr (std::is_same_v<M, ArrudaBoyce<T>>) {
        return ArrudaBoyce<T>{m.p[0], m.p[1], m.p[2]};
    } else if constexpr (std::is_same_v<M, TransverselyIsotropic<T>>) {
        return TransverselyIsotropic<T>{m.p[0], m.p[1], m.p[2], {m.p[3], m.p[4], m.p[5]}};
    } else {  // two-parameter models: NeoHookean, NeoHookeanCoupled, StVenantKirchhoff, LinearElastic
        return M{m.p[0], m.p[1]};
    }
}

/// Call `f(material)` with the concrete functor for `m` (dispatch once per span of groups).
template <class T, class Fn>
inline auto with_material(const MaterialParams<T>& m, Fn&& f) {
    switch (m.kind) {
        case MaterialKind::NeoHookean:
            return f(make_material<NeoHookean<T>>(m));
        case MaterialKind::MooneyRivlin:
            return f(make_material<MooneyRivlin<T>>(m));
        case MaterialKind::Polynomial:
            return f(make_material<Polynomial<T>>(m));
        case MaterialKind::ArrudaBoyce:
            return f(make_material<ArrudaBoyce<T>>(m));
        case MaterialKind::TransverselyIsotropic:
            return f(make_material<TransverselyIsotropic<T>>(m));
        case MaterialKind::NeoHookeanCoupled:
            return f(make_material<NeoHookeanCoupled<T>>(m));
        case MaterialKind::StVenantKirchhoff:
            return f(make_material<StVenantKirchhoff<T>>(m));
        case MaterialKind::LinearElastic:
        default:
            return f(make_material<LinearElastic<T>>(m));
    }
}

}  // namespace pliant
