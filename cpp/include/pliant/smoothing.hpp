// pliant — edge-based smoothed strain on linear tetrahedra (ES-FEM-T4), header-only, host and device.
//
// Each edge k of the mesh owns a smoothing domain made of one sixth of every tetrahedron around it
// (V_k = Σ_{e∋k} V_e/6); the domain's deformation gradient is the volume-weighted mean of its
// elements' gradients, F̄_k = I + Σ_{e∋k} w_ek H_e, w_ek = (V_e/6)/V_k, and its stress P̄_k = P(F̄_k)
// (Liu, Nguyen-Thoi & Lam 2009, J. Sound Vib. 320:1100, eqs. 14-18; for tetrahedra and large strain
// Nguyen-Thoi, Liu, Vu-Do & Nguyen-Xuan 2009, CMAME 198:3479, §3). The nodal forces
// f_a = Σ_k V_k P̄_k ∇N̄_ka with ∇N̄_ka = Σ_{e∋k} w_ek ∇N_ea regroup, element by element, into
// f_a = Σ_e V_e P̃_e ∇N_ea with P̃_e = (1/6) Σ_{k ∈ edges(e)} P̄_k: each element applies the mean of
// its six edges' stresses through its own gradients (kernel 1's store), and the node pass is
// unchanged. Passes a step: element gradients H_e; edge gradients H̄_k (a gather); edge stresses
// P̄_k (SIMD across edges); element forces.
//
// With T4ANP the edges carry the isochoric stress only and each element adds the volumetric part
// J p C⁻¹ of its own F with the averaged nodal pressure: the selective edge/node-smoothed tetrahedron
// (ES/NS-FEM-T4; Jiang, Zhang, Liu, Han & Zeng 2015, Eng. Anal. Bound. Elem. 59:62, §3.3), free of
// both shear and volumetric locking.
//
// Data: edges are numbered group by group (an edge of two materials is two domains); edge k's
// elements are edge_slot[edge_off[k] .. edge_off[k+1]) (element slots, ascending: a fixed summation
// order) with weights edge_w; elem_edges AoSoA K=6 holds each slot's edges (local edges 01 02 03 12
// 13 23); H_elem the element gradients (9 per slot, slot-major); P_edge (9 per edge, row-major) the edge
// stresses.
#pragma once

#include "tled.hpp"

namespace pliant {

/// Where the strain is constant: per element (plain linear tetrahedra), or per edge domain.
enum class StrainSmoothing : int { Element = 0, Edge = 1 };

template <class T>
struct EdgeData {
    const index_t* off;         // (n_edges + 1,) CSR offsets
    const index_t* slot;        // element slots of each edge
    const T* w;                 // w_ek = (V_e/6)/V_k [1]
    const index_t* elem_edges;  // AoSoA K=6: the slot's six edges
};

/// Pass 1: the displacement gradient H_e [1] of element slot s = b·kLanes + l into H_out[9s .. 9s+8]
/// (slot-major: each edge gathers its elements' nine values from one cache line or two); returns
/// it too. Inputs: element data, displacements u [m] SoA (3, P).
template <class T>
PLIANT_HD Mat3<T> element_gradient(index_t b, int l, const ElementData<T>& el, const T* u, index_t P,
                                   T* H_out) {
    const Mat3<T> H = displacement_gradient(b, l, el, u, P);
    T* h = H_out + 9 * (static_cast<std::size_t>(b) * kLanes + l);
    PLIANT_UNROLL
    for (int c = 0; c < 9; ++c) h[c] = H.a[c];
    return H;
}

/// Slot (b, l)'s gradient [1] as pass 1 stored it in H_elem (element_gradient).
template <class T>
PLIANT_HD Mat3<T> stored_gradient(index_t b, int l, const T* H_elem) {
    const T* h = H_elem + 9 * (static_cast<std::size_t>(b) * kLanes + l);
    Mat3<T> H;
    PLIANT_UNROLL
    for (int c = 0; c < 9; ++c) H.a[c] = h[c];
    return H;
}

/// Pass 1 under T4ANP: element_gradient, and T4ANP's pass (1) from the same gradient, ep_out = V0
/// p(J) [N·m] (slot; element_pressure), so that the displacements are gathered once.
template <class T, class Material>
PLIANT_HD void element_gradient_pressure(index_t b, int l, const Material& mat, const ElementData<T>& el,
                                         const T* u, index_t P, T* H_out, T* ep_out) {
    const Mat3<T> H = element_gradient(b, l, el, u, P, H_out);
    ep_out[aosoa(b, l, 0, 1)] = el.vol[aosoa(b, l, 0, 1)] * mat.pressure(kinematics(H));
}

/// Pass 2a: edge k's smoothed gradient H̄_k = Σ w_ek H_e [1] into Hbar_out (AoSoA K=9 over edge
/// blocks) (Nguyen-Thoi et al. 2009, CMAME 198:3479, eq. 20). Inputs: edge data, element
/// gradients (9 per slot). Where PLIANT_HOST_VECTORS (config.hpp), it adds each element's first
/// eight values as one vector (one load, one multiply-add) and the ninth alone: each value's
/// additions are the same, in the same order (gather_forces, tled.hpp, does the same).
template <class T>
PLIANT_HD void edge_gradient(index_t k, const EdgeData<T>& ed, const T* H_elem, T* Hbar_out) {
    T H[9] = {T(0), T(0), T(0), T(0), T(0), T(0), T(0), T(0), T(0)};
#if PLIANT_HOST_VECTORS
    typedef T V8 __attribute__((vector_size(8 * sizeof(T))));
    V8 H8 = {T(0), T(0), T(0), T(0), T(0), T(0), T(0), T(0)};
    for (index_t i = ed.off[k]; i < ed.off[k + 1]; ++i) {
        const T* h = H_elem + 9 * static_cast<std::size_t>(ed.slot[i]);
        const T w = ed.w[i];
        V8 x;
        __builtin_memcpy(&x, h, sizeof x);
        H8 += w * x;
        H[8] += w * h[8];
    }
    PLIANT_UNROLL
    for (int c = 0; c < 8; ++c) H[c] = H8[c];
#else
    for (index_t i = ed.off[k]; i < ed.off[k + 1]; ++i) {
        const T* h = H_elem + 9 * static_cast<std::size_t>(ed.slot[i]);
        const T w = ed.w[i];
        PLIANT_UNROLL
        for (int c = 0; c < 9; ++c) H[c] += w * h[c];
    }
#endif
    PLIANT_UNROLL
    for (int c = 0; c < 9; ++c) Hbar_out[aosoa(k / kLanes, k % kLanes, c, 9)] = H[c];
}

/// Edge slot (b, l)'s smoothed gradient H̄ [1] (AoSoA K=9).
template <class T>
PLIANT_HD Mat3<T> edge_gradient_at(index_t b, int l, const T* Hbar) {
    Mat3<T> H;
    PLIANT_UNROLL
    for (int c = 0; c < 9; ++c) H.a[c] = Hbar[aosoa(b, l, c, 9)];
    return H;
}

/// Edge slot (b, l)'s stress Pk [Pa] into P_out[9k .. 9k+8], k = b·kLanes + l (row-major: pass 3
/// gathers an edge's nine values together).
template <class T>
PLIANT_HD void store_edge_stress(index_t b, int l, const Mat3<T>& Pk, T* P_out) {
    T* p = P_out + 9 * (static_cast<std::size_t>(b) * kLanes + l);
    PLIANT_UNROLL
    for (int c = 0; c < 9; ++c) p[c] = Pk.a[c];
}

/// Pass 2b, one edge per lane of edge block b: the smoothed stress P̄_k = P(I + H̄_k) [Pa] into
/// P_out (store_edge_stress). Inputs: material (isochoric only under T4ANP), smoothed gradients
/// (AoSoA K=9). A viscoelastic material's runs as the phases of visco_begin (materials.hpp) with
/// kinematics(edge_gradient_at) and store_edge_stress(visco_pk1).
template <class T, class Material>
PLIANT_HD void edge_stress(index_t b, int l, const Material& mat, const T* Hbar, T* P_out) {
    store_edge_stress(b, l, mat.pk1(kinematics(edge_gradient_at(b, l, Hbar))), P_out);
}

/// P̃_e = (1/6) Σ P̄_k [Pa] over the six edges of slot (b, l).
template <class T>
PLIANT_HD Mat3<T> mean_edge_stress(index_t b, int l, const index_t* elem_edges, const T* P_edge) {
    Mat3<T> Pm = {{T(0), T(0), T(0), T(0), T(0), T(0), T(0), T(0), T(0)}};
    PLIANT_UNROLL
    for (int j = 0; j < 6; ++j) {
        const T* p = P_edge + 9 * elem_edges[aosoa(b, l, j, 6)];  // 32-bit offsets: SIMD gathers
        PLIANT_UNROLL
        for (int c = 0; c < 9; ++c) Pm.a[c] += p[c];
    }
    PLIANT_UNROLL
    for (int c = 0; c < 9; ++c) Pm.a[c] *= T(1) / T(6);
    return Pm;
}

/// Pass 3's material: the element's stress is its edges' mean P̃ (given), plus with T4ANP (kAnp)
/// the volumetric J p C⁻¹ of its own F, p = p̄ + γ (p(J_e) − p̄) as in AveragedPressure. pk2 (for
/// the outputs) is S = C⁻¹ Fᵀ P symmetrized; energy is the element's own W(F_e).
template <class M, class T, bool kAnp>
struct SmoothedStress {
    const M& m;
    Mat3<T> Pm;  // P̃ [Pa]
    T p;         // T4ANP: p̄ [Pa]
    T stab;      // T4ANP: γ [1]
    PLIANT_HD Mat3<T> pk1(const Kinematics<T>& k) const {
        if constexpr (kAnp) {
            const Sym3<T> Ci = inverse_cauchy_green(k);
            const Mat3<T> Pv = mul(k.F, scale(k.J * (p + stab * (m.pressure(k) - p)), Ci));
            Mat3<T> out;
            PLIANT_UNROLL
            for (int c = 0; c < 9; ++c) out.a[c] = Pm.a[c] + Pv.a[c];
            return out;
        } else {
            return Pm;
        }
    }
    PLIANT_HD Sym3<T> pk2(const Kinematics<T>& k) const {
        const Mat3<T> Pk = pk1(k);
        Mat3<T> FtP;  // Fᵀ P
        PLIANT_UNROLL
        for (int i = 0; i < 3; ++i) {
            PLIANT_UNROLL
            for (int j = 0; j < 3; ++j)
                FtP.a[3 * i + j] =
                    k.F.a[i] * Pk.a[j] + k.F.a[3 + i] * Pk.a[3 + j] + k.F.a[6 + i] * Pk.a[6 + j];
        }
        const Sym3<T> Ci = inverse_cauchy_green(k);
        return sym(mul_sym_left(Ci, FtP));
    }
    PLIANT_HD T energy(const Kinematics<T>& k) const { return m.energy(k); }
};

/// Pass 3: element forces of slot (b, l) from the mean stress of its edges (and, kAnp, its
/// volumetric part from the corners' nodal pressures node_p). The element's own F (its J, and
/// under T4ANP its volumetric stress) comes from pass 1's gradient H_elem (9 per slot), the same
/// values, not gathered from the displacements again. Outputs as element_forces.
template <bool kAnp, class T, class Material>
PLIANT_HD void element_forces_smoothed(index_t b, int l, const Material& mat, const ElementData<T>& el,
                                       const EdgeData<T>& ed, const T* P_edge, const T* H_elem,
                                       const T* node_p, T stab, T* f_out, T* J_out) {
    const T p = kAnp ? corner_pressure(b, l, el, node_p) : T(0);
    const SmoothedStress<Material, T, kAnp> sm{mat, mean_edge_stress(b, l, ed.elem_edges, P_edge), p, stab};
    element_forces_at(b, l, sm, el, kinematics(stored_gradient(b, l, H_elem)), b, f_out, J_out);
}

}  // namespace pliant
