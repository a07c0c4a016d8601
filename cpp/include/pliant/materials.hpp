// pliant — hyperelastic materials, header-only, host and device.
//
// Each material is a small functor with three methods over the deformation gradient F:
//   pk2(F)    second Piola–Kirchhoff stress S [Pa]
//   pk1(F)    first Piola–Kirchhoff stress P = F S [Pa] (what TLED's nodal forces need)
//   energy(F) strain-energy density W [J/m³ = Pa]
// and the parameter-only `dilatational_modulus()` = λ + 2μ [Pa] for the critical time step.
// Conventions: C = FᵀF, J = det F, I1 = tr C, I2 = ½(I1² − tr C²), Ī1 = J^(−2/3) I1, Ī2 = J^(−4/3) I2.
#pragma once

#include <cmath>

#include "mat3.hpp"

namespace pliant {

/// Material type codes, shared with Python (pliant.materials) and the model description.
enum class MaterialKind : int {
    NeoHookean = 0,         // decoupled, params (mu, K)
    MooneyRivlin = 1,       // decoupled, params (C10, C01, K)
    NeoHookeanCoupled = 2,  // Bonet & Wood, params (mu, lambda)
    StVenantKirchhoff = 3,  // params (mu, lambda)
    LinearElastic = 4,      // small strain, params (mu, lambda)
};

/// Decoupled Neo-Hookean, W = μ/2 (Ī1 − 3) + K/2 (J − 1)²;
/// S = μ J^(−2/3) (I − I1/3 C⁻¹) + K J (J − 1) C⁻¹ (Taylor et al. 2008, IEEE TMI 27(5), eq. 10;
/// NiftySim's "NH").
template <class T>
struct NeoHookean {
    T mu, K;
    PLIANT_HD T dilatational_modulus() const { return K + T(4) / T(3) * mu; }
    PLIANT_HD Sym3<T> pk2(const Mat3<T>& F) const {
        const Sym3<T> C = right_cauchy_green(F);
        const T J = det(F);
        const Sym3<T> Ci = inverse(C, J * J);
        const T j23 = inv_cbrt(J * J);  // J^(-2/3)
        const T a = mu * j23;
        return add_identity(a, scale(K * J * (J - T(1)) - a * trace(C) / T(3), Ci));
    }
    PLIANT_HD Mat3<T> pk1(const Mat3<T>& F) const { return mul(F, pk2(F)); }
    PLIANT_HD T energy(const Mat3<T>& F) const {
        const T J = det(F);
        const T I1 = trace(right_cauchy_green(F));
        return mu / T(2) * (inv_cbrt(J * J) * I1 - T(3)) + K / T(2) * (J - T(1)) * (J - T(1));
    }
};

/// Decoupled Mooney–Rivlin, W = C10 (Ī1 − 3) + C01 (Ī2 − 3) + K/2 (J − 1)²;
/// S = 2C10 J^(−2/3)(I − I1/3 C⁻¹) + 2C01 J^(−4/3)(I1 I − C − 2/3 I2 C⁻¹) + K J (J − 1) C⁻¹
/// (Holzapfel, Nonlinear Solid Mechanics 2000, §6.5, eqs. 6.142–6.147).
template <class T>
struct MooneyRivlin {
    T C10, C01, K;
    PLIANT_HD T dilatational_modulus() const { return K + T(8) / T(3) * (C10 + C01); }
    PLIANT_HD Sym3<T> pk2(const Mat3<T>& F) const {
        const Sym3<T> C = right_cauchy_green(F);
        const T J = det(F);
        const Sym3<T> Ci = inverse(C, J * J);
        const T I1 = trace(C);
        const T I2 = T(0.5) * (I1 * I1 - ddot(C));
        const T j23 = inv_cbrt(J * J);
        const T a = T(2) * C10 * j23;
        const T b = T(2) * C01 * j23 * j23;
        const T ci = K * J * (J - T(1)) - a * I1 / T(3) - b * T(2) / T(3) * I2;
        return add_identity(a + b * I1, axpby(ci, Ci, -b, C));
    }
    PLIANT_HD Mat3<T> pk1(const Mat3<T>& F) const { return mul(F, pk2(F)); }
    PLIANT_HD T energy(const Mat3<T>& F) const {
        const Sym3<T> C = right_cauchy_green(F);
        const T J = det(F);
        const T I1 = trace(C);
        const T I2 = T(0.5) * (I1 * I1 - ddot(C));
        const T j23 = inv_cbrt(J * J);
        return C10 * (j23 * I1 - T(3)) + C01 * (j23 * j23 * I2 - T(3)) +
               K / T(2) * (J - T(1)) * (J - T(1));
    }
};

/// Coupled compressible Neo-Hookean, W = μ/2 (I1 − 3) − μ ln J + λ/2 (ln J)²;
/// S = μ (I − C⁻¹) + λ ln J C⁻¹ (Bonet & Wood, Nonlinear Continuum Mechanics for FEA, 2nd ed.,
/// §6.4.3, eq. 6.28; FEBio's "neo-Hookean").
template <class T>
struct NeoHookeanCoupled {
    T mu, lambda;
    PLIANT_HD T dilatational_modulus() const { return lambda + T(2) * mu; }
    PLIANT_HD Sym3<T> pk2(const Mat3<T>& F) const {
        const Sym3<T> C = right_cauchy_green(F);
        const T J = det(F);
        const Sym3<T> Ci = inverse(C, J * J);
        return add_identity(mu, scale(lambda * std::log(J) - mu, Ci));
    }
    PLIANT_HD Mat3<T> pk1(const Mat3<T>& F) const { return mul(F, pk2(F)); }
    PLIANT_HD T energy(const Mat3<T>& F) const {
        const T lnJ = std::log(det(F));
        return mu / T(2) * (trace(right_cauchy_green(F)) - T(3)) - mu * lnJ +
               lambda / T(2) * lnJ * lnJ;
    }
};

/// St Venant–Kirchhoff, W = λ/2 (tr E)² + μ E:E with E = ½(C − I); S = λ tr(E) I + 2μ E
/// (Bonet & Wood, 2nd ed., §6.4.2, eq. 6.19).
template <class T>
struct StVenantKirchhoff {
    T mu, lambda;
    PLIANT_HD T dilatational_modulus() const { return lambda + T(2) * mu; }
    PLIANT_HD Sym3<T> pk2(const Mat3<T>& F) const {
        const Sym3<T> E = add_identity(T(-0.5), scale(T(0.5), right_cauchy_green(F)));
        return add_identity(lambda * trace(E), scale(T(2) * mu, E));
    }
    PLIANT_HD Mat3<T> pk1(const Mat3<T>& F) const { return mul(F, pk2(F)); }
    PLIANT_HD T energy(const Mat3<T>& F) const {
        const Sym3<T> C = right_cauchy_green(F);
        const Sym3<T> E = add_identity(T(-0.5), scale(T(0.5), C));
        const T trE = trace(E);
        return lambda / T(2) * trE * trE + mu * ddot(E);
    }
};

/// Small-strain linear elasticity, σ = λ tr(ε) I + 2μ ε with ε = sym(F − I); the nodal forces
/// use P = σ (geometrically linear; Zienkiewicz & Taylor, The FEM vol. 1, §6.2). Not objective:
/// a baseline for small displacements only.
template <class T>
struct LinearElastic {
    T mu, lambda;
    PLIANT_HD T dilatational_modulus() const { return lambda + T(2) * mu; }
    PLIANT_HD Sym3<T> strain(const Mat3<T>& F) const { return add_identity(T(-1), sym(F)); }
    PLIANT_HD Sym3<T> pk2(const Mat3<T>& F) const {
        const Sym3<T> e = strain(F);
        return add_identity(lambda * trace(e), scale(T(2) * mu, e));
    }
    PLIANT_HD Mat3<T> pk1(const Mat3<T>& F) const {
        const Sym3<T> s = pk2(F);
        return {{s.xx, s.xy, s.xz, s.xy, s.yy, s.yz, s.xz, s.yz, s.zz}};
    }
    PLIANT_HD T energy(const Mat3<T>& F) const {
        const Sym3<T> e = strain(F);
        const T tr = trace(e);
        return lambda / T(2) * tr * tr + mu * ddot(e);
    }
};

/// Parameters of one element group's material, as passed from the model to the kernels.
template <class T>
struct MaterialParams {
    MaterialKind kind;
    T p[4];
};

/// Call `f(material)` with the concrete functor for `m` (dispatch once per element group).
template <class T, class Fn>
inline auto with_material(const MaterialParams<T>& m, Fn&& f) {
    switch (m.kind) {
        case MaterialKind::NeoHookean: return f(NeoHookean<T>{m.p[0], m.p[1]});
        case MaterialKind::MooneyRivlin: return f(MooneyRivlin<T>{m.p[0], m.p[1], m.p[2]});
        case MaterialKind::NeoHookeanCoupled: return f(NeoHookeanCoupled<T>{m.p[0], m.p[1]});
        case MaterialKind::StVenantKirchhoff: return f(StVenantKirchhoff<T>{m.p[0], m.p[1]});
        case MaterialKind::LinearElastic: default: return f(LinearElastic<T>{m.p[0], m.p[1]});
    }
}

}  // namespace pliant
