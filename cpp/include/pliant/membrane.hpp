// pliant — membrane triangles: Total Lagrangian constant-strain triangles that carry in-plane
// stress (and, where they bend, Kirchhoff moments: rotation-free shell triangles), laid on a
// solid's surface (an organ's capsule, a vessel's wall), between its nodes or as sheets of their
// own. Header-only, host and device. Each membrane's forces on its slots are computed once per
// step (membrane_corner_forces) and each node gathers its slots' in a fixed order in the node pass
// (membrane_force): no scatter, the same bits on every device and thread count.
//
// Convected coordinates (Bonet & Wood, Nonlinear Continuum Mechanics for FEA, 2nd ed., §5.6 for
// the membrane kinematics; Bonet, Wood, Mahaney & Heywood 2000, CMAME 190:579, for the
// incompressible Neo-Hookean membrane): a triangle X = X0 + ξ1 (X1 − X0) + ξ2 (X2 − X0) has
// tangent vectors G_i = ∂X/∂ξi (reference) and g_i = G_i + ∂u/∂ξi (current), metrics G_ij = G_i·G_j
// and g_ij = g_i·g_j, Green strain E_ij = (g_ij − G_ij)/2 and contravariant 2nd Piola–Kirchhoff
// stress resultants S^ij [N/m] (stress times the reference thickness). Corner a's internal force
// is f_a = A0 S^ij g_i ∂N_a/∂ξj with ∂N/∂ξ = (−1, −1), (1, 0), (0, 1) for corners 0, 1, 2 and A0
// the reference area (the energy A0 h W(E) differentiated by x_a).
#pragma once

#include <cmath>

#include "config.hpp"

namespace pliant {

/// Membrane constitutive models (the kinds bound to Python as MembraneKind).
enum class MembraneKind : int {
    /// Plane-stress St Venant–Kirchhoff: S = h (λ' tr(E) I + 2 μ E), λ' = E ν / (1 − ν²) (the
    /// plane-stress Lamé constant), μ = E / (2 (1 + ν)). Linear elasticity at small strain, objective
    /// under any rotation (NiftySim's "Linear" membrane at small displacement).
    StVenantKirchhoff = 0,
    /// Incompressible Neo-Hookean (Bonet et al. 2000, eq. 18; NiftySim's "NeoHookean" membrane):
    /// S^ij = μ h (G^ij − (det G / det g) g^ij), the thickness stretch λ3² = det G / det g.
    NeoHookean = 1,
};

/// Values per membrane in MembraneData::geom: reference tangents G_1, G_2 [m] (6), the inverse
/// reference metric G^11, G^22, G^12 [1/m²] (3), two coefficients (A0 h λ', A0 h μ) [N·m] for
/// StVenantKirchhoff, (A0 h μ, 0) for NeoHookean, and the wrinkled state's (membrane_wrinkle):
/// A0 h E (Young's modulus) for StVenantKirchhoff, A0 h μ for NeoHookean, 0 where the membrane
/// does not wrinkle (it carries compression).
constexpr int kMembraneValues = 12;
/// The first of the three values that carry the material's moduli (scaled by scale_materials).
constexpr int kMembraneModuli = 9;
/// Parameters per membrane in a model's input: thickness h [m], density ρ [kg/m³], the material's
/// two (E, ν or μ, 0) and whether it wrinkles (0 or 1).
constexpr int kMembraneParams = 5;

/// Force slots per membrane in MembraneData::corner_f: its three corners, then (a bending
/// membrane's patch, membrane_bending_forces) the node across each edge e (3 + e) and the two
/// nodes across the other edges of that neighbour (6 + 2 e: across its edge opposite corner
/// (e + 1) % 3, 7 + 2 e: opposite corner (e + 2) % 3).
constexpr int kMembraneSlots = 12;
/// Patch nodes per membrane in MembraneData::nbrs (the slots after its corners).
constexpr int kMembraneNbrs = kMembraneSlots - 3;

/// Values per membrane in MembraneData::bend (membrane_bending_forces): the patch coefficients
/// B[c][p] [1] (at c kMembraneSlots + p) of its curvature vectors H_c = H0_c + Σ_p B[c][p] u_p (c =
/// 11, 22, 12 in convected components; p its slots), H0_c [m] (3 each, at kBendH0: the reference
/// positions' and clamped edges' part), the reference curvature κ0_c = N·H0_c [m] (at
/// kBendKappa0) and the bending moduli A0 D ν, A0 D (1 − ν)/2 [N·m³] (at kBendModuli; both 0:
/// the membrane does not bend).
constexpr int kBendH0 = 3 * kMembraneSlots;
constexpr int kBendKappa0 = kBendH0 + 9;
constexpr int kBendModuli = kBendKappa0 + 3;
constexpr int kBendValues = kBendModuli + 2;
/// A node across a membrane's edge: none (a free edge) or a clamped edge (MembraneData::nbrs).
constexpr index_t kFreeEdge = -1, kClampedEdge = -2;

/// Node → membrane force slots (CSR over nodes: offsets N + 1, index holds kMembraneSlots m +
/// slot), and per membrane its nodes (3), kind and kMembraneValues values; corner_f: each slot's
/// internal force [N] (3 kMembraneSlots per membrane, slot s's at 3 (kMembraneSlots m + s):
/// membrane_corner_forces, gathered by membrane_force); nbrs and bend (null where no membrane
/// bends): per membrane its kMembraneNbrs patch nodes (kMembraneSlots; the nodes across its
/// edges kFreeEdge or kClampedEdge where there are none, the others −1) and kBendValues values. count == 0:
/// no membranes.
template <class T>
struct MembraneData {
    index_t count;
    const index_t* offsets;
    const index_t* index;
    const index_t* nodes;
    const index_t* kind;
    const T* geom;
    T* corner_f;
    const index_t* nbrs;
    const T* bend;
};

/// Plane-stress St Venant–Kirchhoff resultant in convected components, S^ij = λ (G^kl E_kl) G^ij +
/// 2 μ G^ik E_kl G^lj, from the inverse metric G^11, G^22, G^12 and a symmetric strain E (11, 22,
/// 12); the membrane's stress (λ = A0 h λ', μ = A0 h μ) and the shell's moments (E the curvature
/// change, λ = A0 D ν, μ = A0 D (1 − ν)/2: Kirchhoff plate bending, Timoshenko & Woinowsky-Krieger,
/// Theory of Plates and Shells, 2nd ed., §10). Output: S (11, 22, 12).
template <class T>
PLIANT_HD void svk_resultant(T Gi11, T Gi22, T Gi12, T lam, T mu, const T E[3], T S[3]) {
    const T E11 = E[0], E22 = E[1], E12 = E[2];
    const T trE = Gi11 * E11 + Gi22 * E22 + T(2) * Gi12 * E12;
    // M = G⁻¹ E (mixed), then M G⁻¹.
    const T m11 = Gi11 * E11 + Gi12 * E12, m12 = Gi11 * E12 + Gi12 * E22;
    const T m21 = Gi12 * E11 + Gi22 * E12, m22 = Gi12 * E12 + Gi22 * E22;
    const T two_mu = T(2) * mu;
    S[0] = lam * trE * Gi11 + two_mu * (m11 * Gi11 + m12 * Gi12);
    S[1] = lam * trE * Gi22 + two_mu * (m21 * Gi12 + m22 * Gi22);
    S[2] = lam * trE * Gi12 + two_mu * (m11 * Gi12 + m12 * Gi22);
}

/// The energy whose derivative svk_resultant is: λ/2 tr(M)² + μ tr(M²), M = G⁻¹E the mixed strain.
template <class T>
PLIANT_HD T svk_energy(T Gi11, T Gi22, T Gi12, T lam, T mu, const T E[3]) {
    const T E11 = E[0], E22 = E[1], E12 = E[2];
    const T m11 = Gi11 * E11 + Gi12 * E12, m12 = Gi11 * E12 + Gi12 * E22;
    const T m21 = Gi12 * E11 + Gi22 * E12, m22 = Gi12 * E12 + Gi22 * E22;
    const T tr = m11 + m22;
    return T(0.5) * lam * tr * tr + mu * (m11 * m11 + m22 * m22 + T(2) * m12 * m21);
}

/// Green strain E_ij [1] (11, 22, 12) from reference tangents G1, G2 and displacement differences
/// d1, d2 [m], formed from the differences so that small strains keep their digits in float32.
template <class T>
PLIANT_HD void membrane_strain(const T* G1, const T* G2, const T d1[3], const T d2[3], T E[3]) {
    E[0] = E[1] = E[2] = T(0);
    PLIANT_UNROLL
    for (int d = 0; d < 3; ++d) {
        E[0] += G1[d] * d1[d] + T(0.5) * d1[d] * d1[d];
        E[1] += G2[d] * d2[d] + T(0.5) * d2[d] * d2[d];
        E[2] += T(0.5) * (G1[d] * d2[d] + d1[d] * G2[d] + d1[d] * d2[d]);
    }
}

/// Wrinkling by tension-field theory (Roddeman, Drukker, Oomens & Janssen 1987, J. Appl. Mech.
/// 54:884; the relaxed energy of Pipkin 1986, IMA J. Appl. Math. 36:85): a membrane without bending
/// stiffness buckles under any compression, so it carries none. From the principal Green strains
/// e1 ≥ e2 (the eigenvalues of the mixed strain G⁻¹E): taut where the material's smaller principal
/// stress is ≥ 0 (St Venant–Kirchhoff: λ'(e1 + e2) + 2 μ e2 ≥ 0; Neo-Hookean: c1 c2² ≥ 1, c = 1 + 2e)
/// and the stress is the material's; slack where e1 ≤ 0 (no stress); wrinkled otherwise: uniaxial
/// tension S1 N⊗N along the major direction N, at the stretch the free width would take (St Venant–
/// Kirchhoff: S1 = E e1; Neo-Hookean: S1 = μ (1 − c1^(−3/2)), its free width c2 = c1^(−1/2)).
/// Returns 0 (taut), 1 (slack) or 2 (wrinkled) with, when wrinkled, A0 S1 [N·m] in s1 and the
/// reference-unit major direction's contravariant components v (G_ij v^i v^j = 1).
template <class T>
PLIANT_HD int membrane_wrinkle(MembraneKind kind, const T* q, const T E[3], T& s1, T v[2]) {
    const T Gi11 = q[6], Gi22 = q[7], Gi12 = q[8];
    const T m11 = Gi11 * E[0] + Gi12 * E[2], m12 = Gi11 * E[2] + Gi12 * E[1];  // M = G⁻¹E (mixed)
    const T m21 = Gi12 * E[0] + Gi22 * E[2], m22 = Gi12 * E[2] + Gi22 * E[1];
    const T half = T(0.5) * (m11 + m22), dev = T(0.5) * (m11 - m22);
    const T disc = std::sqrt(std::fmax(dev * dev + m12 * m21, T(0)));
    const T e1 = half + disc, e2 = half - disc;
    if (e1 <= T(0)) return 1;
    const bool nh = kind == MembraneKind::NeoHookean;
    const T c1 = T(1) + T(2) * e1, c2 = T(1) + T(2) * e2;
    if (nh ? c1 * c2 * c2 >= T(1) : q[9] * (e1 + e2) + T(2) * q[10] * e2 >= T(0)) return 0;
    if (nh) {
        const T r = std::sqrt(c1), rm1 = T(2) * e1 / (r + T(1));  // √c1 − 1 without cancellation
        s1 = q[11] * rm1 * (r * r + r + T(1)) / (r * r * r);      // 1 − c1^(−3/2)
    } else {
        s1 = q[11] * e1;
    }
    // An eigenvector of M for e1 from the row of M − e1 I that is not (nearly) zero: e1 > e2 here.
    T a1 = m12, a2 = e1 - m11;
    const T b1 = e1 - m22, b2 = m21;
    if (b1 * b1 + b2 * b2 > a1 * a1 + a2 * a2) a1 = b1, a2 = b2;
    T G11 = T(0), G22 = T(0), G12 = T(0);
    PLIANT_UNROLL
    for (int d = 0; d < 3; ++d) G11 += q[d] * q[d], G22 += q[3 + d] * q[3 + d], G12 += q[d] * q[3 + d];
    const T w = T(1) / std::sqrt(G11 * a1 * a1 + T(2) * G12 * a1 * a2 + G22 * a2 * a2);
    v[0] = a1 * w, v[1] = a2 * w;
    return 2;
}

/// Contravariant stress resultants times A0, S^11, S^22, S^12 [N·m], of membrane m at current
/// tangents g1, g2 with displacement differences d1 = u1 − u0, d2 = u2 − u0 [m]: the Green strain
/// is formed from the differences, E_ij = (G_i·d_j + d_i·G_j + d_i·d_j)/2, so that small strains keep
/// their digits in float32 (as displacement_gradient keeps H apart from I).
template <class T>
PLIANT_HD void membrane_stress(MembraneKind kind, const T* q, const T g1[3], const T g2[3], const T d1[3],
                               const T d2[3], T S[3]) {
    const T *G1 = q, *G2 = q + 3;
    const T Gi11 = q[6], Gi22 = q[7], Gi12 = q[8];
    T E[3];
    membrane_strain(G1, G2, d1, d2, E);
    if (q[11] != T(0)) {  // a membrane that wrinkles: slack or wrinkled states first
        T s1 = T(0), v[2] = {T(0), T(0)};
        const int state = membrane_wrinkle(kind, q, E, s1, v);
        if (state != 0) {  // slack: s1 = 0 and v = 0
            S[0] = s1 * v[0] * v[0], S[1] = s1 * v[1] * v[1], S[2] = s1 * v[0] * v[1];
            return;
        }
    }
    if (kind == MembraneKind::NeoHookean) {
        // det g / det G from the metrics; g^ij = cofactor / det g.
        T G11 = T(0), G22 = T(0), G12 = T(0), g11 = T(0), g22 = T(0), g12 = T(0);
        PLIANT_UNROLL
        for (int d = 0; d < 3; ++d) {
            G11 += G1[d] * G1[d], G22 += G2[d] * G2[d], G12 += G1[d] * G2[d];
            g11 += g1[d] * g1[d], g22 += g2[d] * g2[d], g12 += g1[d] * g2[d];
        }
        const T detG = G11 * G22 - G12 * G12, detg = g11 * g22 - g12 * g12;
        const T r = detG / (detg * detg);  // (det G / det g) · (1 / det g) for the cofactors
        S[0] = q[9] * (Gi11 - r * g22);
        S[1] = q[9] * (Gi22 - r * g11);
        S[2] = q[9] * (Gi12 + r * g12);
        return;
    }
    svk_resultant(Gi11, Gi22, Gi12, q[9], q[10], E, S);  // plane-stress St Venant–Kirchhoff
}

/// Membrane m's displacement differences d1 = u1 − u0, d2 = u2 − u0 [m] and current tangents
/// g_i = G_i + d_i [m] (3 each), from u [m] SoA (3, P).
template <class T>
PLIANT_HD void membrane_tangents(index_t m, const MembraneData<T>& md, const T* u, index_t P, T d1[3],
                                 T d2[3], T g1[3], T g2[3]) {
    const index_t a = md.nodes[3 * m], b = md.nodes[3 * m + 1], c = md.nodes[3 * m + 2];
    const T* q = md.geom + static_cast<std::size_t>(kMembraneValues) * m;
    PLIANT_UNROLL
    for (int d = 0; d < 3; ++d) {
        const T ua = u[d * P + a];
        d1[d] = u[d * P + b] - ua;
        d2[d] = u[d * P + c] - ua;
        g1[d] = q[d] + d1[d];
        g2[d] = q[3 + d] + d2[d];
    }
}

/// Strain energy A0 h W [J] of a membrane with values q (kMembraneValues) and displacement
/// differences d1, d2 [m] — the potential whose derivative membrane_stress is (S^ij = 2 ∂W/∂g_ij),
/// in the mixed strain M = G⁻¹E (tr M = G^ij E_ij, det M = det E / det G): StVenantKirchhoff
/// W h = λ'/2 tr(M)² + μ tr(M²) (Bonet & Wood §5.6); NeoHookean W h = μ/2 (G^ij g_ij + det G /
/// det g − 3) (Bonet et al. 2000, the energy of eq. 18's stress, λ3² = det G / det g), which with
/// det g / det G = 1 + 2 tr M + 4 det M is 2 μ (tr(M)² − det M + 2 tr M det M) / (1 + 2 tr M +
/// 4 det M): second order in the strain term by term, so small strains keep their digits in float32.
/// A membrane that wrinkles has the relaxed energy of its state (membrane_wrinkle): 0 slack; the
/// uniaxial state's wrinkled.
template <class T>
PLIANT_HD T membrane_energy(MembraneKind kind, const T* q, const T d1[3], const T d2[3]) {
    const T Gi11 = q[6], Gi22 = q[7], Gi12 = q[8];
    T E[3];
    membrane_strain(q, q + 3, d1, d2, E);
    if (q[11] != T(0)) {  // wrinkling: the relaxed energy, 0 slack, of the uniaxial state wrinkled
        T s1 = T(0), v[2] = {T(0), T(0)};
        const int state = membrane_wrinkle(kind, q, E, s1, v);
        if (state == 1) return T(0);
        if (state == 2) {
            // e1 = E_ij v^i v^j: St Venant–Kirchhoff E/2 e1²; Neo-Hookean μ/2 (c1 + 2/√c1 − 3)
            // = μ/2 (√c1 − 1)² (√c1 + 2)/√c1.
            const T e1 = E[0] * v[0] * v[0] + E[1] * v[1] * v[1] + T(2) * E[2] * v[0] * v[1];
            if (kind != MembraneKind::NeoHookean) return T(0.5) * q[11] * e1 * e1;
            const T r = std::sqrt(T(1) + T(2) * e1), rm1 = T(2) * e1 / (r + T(1));
            return T(0.5) * q[11] * rm1 * rm1 * (r + T(2)) / r;
        }
    }
    if (kind != MembraneKind::NeoHookean) return svk_energy(Gi11, Gi22, Gi12, q[9], q[10], E);
    const T E11 = E[0], E22 = E[1], E12 = E[2];
    const T m11 = Gi11 * E11 + Gi12 * E12, m12 = Gi11 * E12 + Gi12 * E22;
    const T m21 = Gi12 * E11 + Gi22 * E12, m22 = Gi12 * E12 + Gi22 * E22;
    const T tr = m11 + m22, det = m11 * m22 - m12 * m21;
    return T(2) * q[9] * (tr * tr - det + T(2) * tr * det) / (T(1) + T(2) * tr + T(4) * det);
}

/// Membrane m's patch nodes (kMembraneSlots: its corners, then MembraneData::nbrs, −1 where none),
/// curvature vectors H_c = H0_c + Σ_p B[c][p] (u_p − u_0) [m] (3 × 3: c = 11, 22, 12; read relative
/// to corner 0, Σ_p B[c][p] = 0, so that a translation moves nothing and a sheet carried far keeps
/// its curvature's digits), its current unit normal t = g1 × g2 / |g1 × g2|, 1 / |g1 × g2| [1/m²]
/// and its curvature change K_c = t·H_c − κ0_c [m] (membrane_bending_forces). Inputs: the membrane's
/// data, u [m] SoA (3, P), its tangents g1, g2 [m].
template <class T>
PLIANT_HD void membrane_curvature(index_t m, const MembraneData<T>& md, const T* u, index_t P, const T g1[3],
                                  const T g2[3], index_t node[kMembraneSlots], T H[3][3], T t[3], T& inv_n,
                                  T K[3]) {
    const T* b = md.bend + static_cast<std::size_t>(kBendValues) * m;
    for (int k = 0; k < kMembraneSlots; ++k)
        node[k] = k < 3 ? md.nodes[3 * m + k] : md.nbrs[static_cast<std::size_t>(kMembraneNbrs) * m + k - 3];
    PLIANT_UNROLL
    for (int c = 0; c < 3; ++c)
        for (int d = 0; d < 3; ++d) H[c][d] = b[kBendH0 + 3 * c + d];
    for (int p = 1; p < kMembraneSlots; ++p) {
        if (node[p] < 0) continue;  // no node in that slot (a free or clamped edge)
        PLIANT_UNROLL
        for (int d = 0; d < 3; ++d) {
            const T up = u[d * P + node[p]] - u[d * P + node[0]];
            PLIANT_UNROLL
            for (int c = 0; c < 3; ++c) H[c][d] += b[kMembraneSlots * c + p] * up;
        }
    }
    const T n[3] = {g1[1] * g2[2] - g1[2] * g2[1], g1[2] * g2[0] - g1[0] * g2[2],
                    g1[0] * g2[1] - g1[1] * g2[0]};
    inv_n = T(1) / std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    PLIANT_UNROLL
    for (int d = 0; d < 3; ++d) t[d] = n[d] * inv_n;
    PLIANT_UNROLL
    for (int c = 0; c < 3; ++c) K[c] = t[0] * H[c][0] + t[1] * H[c][1] + t[2] * H[c][2] - b[kBendKappa0 + c];
}

/// Rotation-free bending (the Basic Shell Triangle: Oñate & Zárate 2000, IJNME 47:557; NiftySim's
/// LinearShell element takes Flores & Oñate 2005's form of it). The curvature of a triangle is its
/// mean second derivative, by the divergence theorem over the triangle in its convected
/// coordinates: H_αβ = ⟨∂²x/∂ξα∂ξβ⟩ = −2 Σ_e ∂N_e/∂ξβ (∂x/∂ξα|_e − ∂x/∂ξα|_own), edge e opposite
/// corner e, with one gradient at each edge shared by its two triangles (so that a constant moment
/// gives no force inside the sheet: the patch test) and exact for quadratic shapes on any mesh (a
/// least-squares quadratic over the edge's stencil; the triangle's own at a free edge, the reference
/// one at a clamped edge: cpp/src/model_bending.cpp). The model stores it as H_c = H0_c + Σ_p
/// B[c][p] u_p (kBendValues). κ_c = t·H_c with t = g1 × g2 / |g1 × g2| the current normal; the
/// moments are Kirchhoff's, M^ij = ∂W/∂κ_ij of W = A0 (D ν/2 tr(K)² + D (1 − ν)/2 tr(K²)), K = κ −
/// κ0 mixed with G⁻¹ (svk_resultant), so a curved reference shape is unstressed. The forces are the
/// exact gradient of that energy: the patch's nodes receive Σ_c w_c B[c][p] t (w = M^11, M^22,
/// 2 M^12) and the corners the normal's variation, ∂N_a/∂ξ1 g2 × v + ∂N_a/∂ξ2 v × g1 with v = (I −
/// t t) Σ_c w_c H_c / |g1 × g2|. Inputs: the membrane's data, its tangents g1, g2 [m], u [m] SoA
/// (3, P). Output: out [N], its kMembraneSlots slots (3 each), added to (corners) and written (the
/// patch's other nodes).
template <class T>
PLIANT_HD void membrane_bending_forces(index_t m, const MembraneData<T>& md, const T* u, index_t P,
                                       const T g1[3], const T g2[3], T* out) {
    const T* b = md.bend + static_cast<std::size_t>(kBendValues) * m;
    index_t node[kMembraneSlots];
    T H[3][3], t[3], inv_n, K[3];
    membrane_curvature(m, md, u, P, g1, g2, node, H, t, inv_n, K);
    const T* q = md.geom + static_cast<std::size_t>(kMembraneValues) * m;
    T M[3];
    svk_resultant(q[6], q[7], q[8], b[kBendModuli], b[kBendModuli + 1], K, M);
    const T w[3] = {M[0], M[1], T(2) * M[2]};
    T s0 = T(0);  // corner 0 takes the others' sum, negated (H reads u_p − u_0)
    for (int p = 1; p < kMembraneSlots; ++p) {
        const T s = node[p] < 0
                        ? T(0)
                        : w[0] * b[p] + w[1] * b[kMembraneSlots + p] + w[2] * b[2 * kMembraneSlots + p];
        s0 -= s;
        PLIANT_UNROLL
        for (int d = 0; d < 3; ++d) {
            if (p < 3)
                out[3 * p + d] += s * t[d];
            else
                out[3 * p + d] = s * t[d];
        }
    }
    PLIANT_UNROLL
    for (int d = 0; d < 3; ++d) out[d] += s0 * t[d];
    T h[3], v[3];
    PLIANT_UNROLL
    for (int d = 0; d < 3; ++d) h[d] = w[0] * H[0][d] + w[1] * H[1][d] + w[2] * H[2][d];
    const T th = t[0] * h[0] + t[1] * h[1] + t[2] * h[2];
    PLIANT_UNROLL
    for (int d = 0; d < 3; ++d) v[d] = (h[d] - th * t[d]) * inv_n;
    const T a1[3] = {g2[1] * v[2] - g2[2] * v[1], g2[2] * v[0] - g2[0] * v[2], g2[0] * v[1] - g2[1] * v[0]};
    const T a2[3] = {v[1] * g1[2] - v[2] * g1[1], v[2] * g1[0] - v[0] * g1[2], v[0] * g1[1] - v[1] * g1[0]};
    PLIANT_UNROLL
    for (int d = 0; d < 3; ++d) {  // ∂N/∂ξ: corner 0 (−1, −1), 1 (1, 0), 2 (0, 1)
        out[d] -= a1[d] + a2[d];
        out[3 + d] += a1[d];
        out[6 + d] += a2[d];
    }
}

/// Whether membrane m bends (its bending moduli are not both 0).
template <class T>
PLIANT_HD bool membrane_bends(index_t m, const MembraneData<T>& md) {
    if (md.bend == nullptr) return false;
    const T* b = md.bend + static_cast<std::size_t>(kBendValues) * m + kBendModuli;
    return b[0] != T(0) || b[1] != T(0);
}

/// Bending energy A0 W [J] of membrane m (membrane_bending_forces' W; 0 where it does not bend).
/// u [m] SoA (3, P).
template <class T>
PLIANT_HD T membrane_bending_energy(index_t m, const MembraneData<T>& md, const T* u, index_t P) {
    if (!membrane_bends(m, md)) return T(0);
    T d1[3], d2[3], g1[3], g2[3];
    membrane_tangents(m, md, u, P, d1, d2, g1, g2);
    const T* b = md.bend + static_cast<std::size_t>(kBendValues) * m;
    index_t node[kMembraneSlots];
    T H[3][3], t[3], inv_n, K[3];
    membrane_curvature(m, md, u, P, g1, g2, node, H, t, inv_n, K);
    const T* q = md.geom + static_cast<std::size_t>(kMembraneValues) * m;
    return svk_energy(q[6], q[7], q[8], b[kBendModuli], b[kBendModuli + 1], K);
}

/// Membrane m's internal force [N] at each of its corners a, A0 S^ij g_i ∂N_a/∂ξj (see the header),
/// its stress computed once for the three, and where it bends its bending forces on its corners
/// and the nodes across its edges (membrane_bending_forces). Inputs: membrane data, u [m] SoA (3,
/// P). Output: md.corner_f[3 (kMembraneSlots m + slot) + d].
template <class T>
PLIANT_HD void membrane_corner_forces(index_t m, const MembraneData<T>& md, const T* u, index_t P) {
    const T* q = md.geom + static_cast<std::size_t>(kMembraneValues) * m;
    T d1[3], d2[3], g1[3], g2[3];
    membrane_tangents(m, md, u, P, d1, d2, g1, g2);
    T S[3];
    membrane_stress(static_cast<MembraneKind>(md.kind[m]), q, g1, g2, d1, d2, S);
    // w_i = S^ij ∂N_a/∂ξj: corner 0 (−1, −1), 1 (1, 0), 2 (0, 1).
    const T w[3][2] = {{-(S[0] + S[2]), -(S[2] + S[1])}, {S[0], S[2]}, {S[2], S[1]}};
    T* out = md.corner_f + 3 * kMembraneSlots * static_cast<std::size_t>(m);
    PLIANT_UNROLL
    for (int a = 0; a < 3; ++a)
        for (int d = 0; d < 3; ++d) out[3 * a + d] = w[a][0] * g1[d] + w[a][1] * g2[d];
    if (membrane_bends(m, md)) membrane_bending_forces(m, md, u, P, g1, g2, out);
}

/// Internal force [N] of node n's membrane corners (membrane_corner_forces, computed before this
/// pass), added to f (3) in the order the model lists them (a fixed order: the same bits on every
/// device and thread count). Output: f [N] (3), added to.
template <class T>
PLIANT_HD void membrane_force(index_t n, const MembraneData<T>& md, T f[3]) {
    const index_t end = md.offsets[n + 1];
    for (index_t k = md.offsets[n]; k < end; ++k) {
        const T* c = md.corner_f + 3 * static_cast<std::size_t>(md.index[k]);  // 3 (6 m + slot)
        PLIANT_UNROLL
        for (int d = 0; d < 3; ++d) f[d] += c[d];
    }
}

/// Values membrane_measures gives per membrane.
constexpr int kMembraneMeasures = 8;

/// Output measures of membrane m (not on the stepping path): its area stretch J_s = √(det g / det G),
/// its Cauchy stress resultant t = J_s⁻¹ S^ij g_i ⊗ g_j [N/m] (the force per current length of a
/// cut through it) and its strain energy A0 h W [J] (membrane_energy, and its bending energy): out[0] = J_s,
/// out[1..6] = t as xx, yy, zz, xy, yz, xz, out[7] the energy. u [m] SoA (3, P).
template <class T>
PLIANT_HD void membrane_measures(index_t m, const MembraneData<T>& md, const T* u, index_t P,
                                 T out[kMembraneMeasures]) {
    const T* q = md.geom + static_cast<std::size_t>(kMembraneValues) * m;
    T d1[3], d2[3], g1[3], g2[3];
    membrane_tangents(m, md, u, P, d1, d2, g1, g2);
    T S[3];  // times A0 (the coefficients hold it): divided out below
    membrane_stress(static_cast<MembraneKind>(md.kind[m]), q, g1, g2, d1, d2, S);
    T G11 = T(0), G22 = T(0), G12 = T(0), g11 = T(0), g22 = T(0), g12 = T(0);
    for (int d = 0; d < 3; ++d) {
        G11 += q[d] * q[d], G22 += q[3 + d] * q[3 + d], G12 += q[d] * q[3 + d];
        g11 += g1[d] * g1[d], g22 += g2[d] * g2[d], g12 += g1[d] * g2[d];
    }
    const T detG = G11 * G22 - G12 * G12;
    const T Js = std::sqrt((g11 * g22 - g12 * g12) / detG);
    const T w = T(1) / (Js * T(0.5) * std::sqrt(detG));  // 1 / (J_s A0)
    const int ij[6][2] = {{0, 0}, {1, 1}, {2, 2}, {0, 1}, {1, 2}, {0, 2}};
    out[0] = Js;
    for (int k = 0; k < 6; ++k) {
        const int i = ij[k][0], j = ij[k][1];
        out[1 + k] =
            w * (S[0] * g1[i] * g1[j] + S[1] * g2[i] * g2[j] + S[2] * (g1[i] * g2[j] + g2[i] * g1[j]));
    }
    out[7] = membrane_energy(static_cast<MembraneKind>(md.kind[m]), q, d1, d2) +
             membrane_bending_energy(m, md, u, P);
}

}  // namespace pliant
