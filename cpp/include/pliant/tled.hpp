// pliant — Total Lagrangian Explicit Dynamics on linear tetrahedra: the per-element and per-node
// kernels, header-only, host and device. Backends only launch these functions.
//
// Data layout (structure of arrays, AoSoA for elements): element slot (b, l) is lane l of block b;
// element field k of width K is stored at [(b*K + k)*kLanes + l]. A CUDA thread i takes
// b = i / kLanes, l = i % kLanes; a CPU SIMD loop runs l = 0..kLanes−1 for one b.
//   elem_nodes  int32  K=4   node indices, positively oriented
//   elem_grad   T      K=9   reference shape-function gradients ∇X N_a [1/m] of corners 0..2,
//                            row a*3 + i; corner 3 is −(∇N_0 + ∇N_1 + ∇N_2)
//   elem_vol    T      K=1   reference volume V0 [m³]
//   f_elem      T            element nodal forces [N], 12·kLanes per block: corner by corner, lane by
//                            lane, x y z side by side (corner_force), so that a node gathers each
//                            incidence's three components from one place
// Node fields are SoA over padded node count P: u[d*P + n] is component d of node n [m].
#pragma once

#include <cmath>

#include "materials.hpp"
#include "membrane.hpp"

namespace pliant {

template <class T>
struct ElementData {
    const index_t* nodes;
    const T* grad;
    const T* vol;
};

PLIANT_HD index_t aosoa(index_t b, int l, int field, int width) { return (b * width + field) * kLanes + l; }

/// Displacement gradient H = ∇X u = Σ_a u_a ⊗ ∇X N_a of element slot (b, l), with
/// ∇N_3 = −Σ_{a<3} ∇N_a so that H = Σ_{a<3} (u_a − u_3) ⊗ ∇N_a; F = I + H (Miller et al. 2007,
/// CNME 23:121, eq. 4). Kept apart from I so that small strains keep their digits in float32.
/// u: displacements [m], SoA (3, P).
template <class T>
PLIANT_HD Mat3<T> displacement_gradient(index_t b, int l, const ElementData<T>& el, const T* u, index_t P) {
    index_t n[4];
    PLIANT_UNROLL
    for (int a = 0; a < 4; ++a) n[a] = el.nodes[aosoa(b, l, a, 4)];
    Mat3<T> H = {{T(0), T(0), T(0), T(0), T(0), T(0), T(0), T(0), T(0)}};
    PLIANT_UNROLL
    for (int i = 0; i < 3; ++i) {
        const T* ui = u + i * P;
        const T u3 = ui[n[3]];
        PLIANT_UNROLL
        for (int a = 0; a < 3; ++a) {
            const T du = ui[n[a]] - u3;
            PLIANT_UNROLL
            for (int j = 0; j < 3; ++j) H.a[3 * i + j] += du * el.grad[aosoa(b, l, 3 * a + j, 9)];
        }
    }
    return H;
}

/// Offset in f_elem of corner a's force (x; y and z follow at +1 and +2) of element slot (b, l):
/// block b's 12·kLanes values hold corner 0's 3·kLanes, lane by lane, then corner 1's, and so on.
/// Kernel 2 reads each incidence's three components with one load (gather_forces; in the AoSoA
/// order, component-major, they lay kLanes apart: three loads from three cache lines), and kernel
/// 1's stores stay whole blocks.
PLIANT_HD index_t corner_force(index_t b, int l, int a) { return (b * 4 + a) * 3 * kLanes + 3 * l; }
/// Values of T after the last block of f_elem that the allocation adds: gather_forces reads four
/// values at a corner's offset, one past its three.
constexpr int kForcePad = 4;

/// Element nodal forces of a first Piola–Kirchhoff stress Pk [Pa]: f_a = V0 · Pk ∇X N_a for
/// a < 3 and f_3 = −Σ f_a, stored (Add = false) or added (Add = true) into f_out [N] (corner_force),
/// as its block ob (b; or 0 of a one-block scratch, which the CPU streams to the forces).
template <bool Add, class T>
PLIANT_HD void store_forces(index_t b, int l, const ElementData<T>& el, const Mat3<T>& Pk, index_t ob,
                            T* f_out) {
    const T V0 = el.vol[aosoa(b, l, 0, 1)];
    T g[9];
    PLIANT_UNROLL
    for (int k = 0; k < 9; ++k) g[k] = el.grad[aosoa(b, l, k, 9)];
    PLIANT_UNROLL
    for (int i = 0; i < 3; ++i) {
        T f3 = T(0);
        PLIANT_UNROLL
        for (int a = 0; a < 3; ++a) {
            const T fa = V0 * (Pk.a[3 * i] * g[3 * a] + Pk.a[3 * i + 1] * g[3 * a + 1] +
                               Pk.a[3 * i + 2] * g[3 * a + 2]);
            if constexpr (Add)
                f_out[corner_force(ob, l, a) + i] += fa;
            else
                f_out[corner_force(ob, l, a) + i] = fa;
            f3 -= fa;
        }
        if constexpr (Add)
            f_out[corner_force(ob, l, 3) + i] += f3;
        else
            f_out[corner_force(ob, l, 3) + i] = f3;
    }
}

/// Kernel 1 (element_forces, below) from the kinematics k of slot (b, l), written as block ob of
/// f_out and J_out (store_forces).
template <class T, class Material>
PLIANT_HD void element_forces_at(index_t b, int l, const Material& mat, const ElementData<T>& el,
                                 const Kinematics<T>& k, index_t ob, T* f_out, T* J_out) {
    store_forces<false>(b, l, el, mat.pk1(k), ob, f_out);
    J_out[aosoa(ob, l, 0, 1)] = k.J;
}

/// Kernel 1 (element_forces, below), written as block ob of f_out and J_out (store_forces). The
/// gradient goes in as a temporary: a named copy of it stops the CPU's SIMD loop.
template <class T, class Material>
PLIANT_HD void element_forces_to(index_t b, int l, const Material& mat, const ElementData<T>& el, const T* u,
                                 index_t P, index_t ob, T* f_out, T* J_out) {
    element_forces_at(b, l, mat, el, kinematics(displacement_gradient(b, l, el, u, P)), ob, f_out, J_out);
}

/// Kernel 1, one element per lane: element nodal forces f_a = V0 · F S ∇X N_a
/// (Miller et al. 2007, CNME 23:121, eq. 12; Taylor et al. 2008, IEEE TMI 27(5), eq. 6).
/// Inputs: material, element data, displacements u [m] SoA (3, P).
/// Outputs: f_out [N] AoSoA K=12; J_out (det F, K=1) for the instability check.
template <class T, class Material>
PLIANT_HD void element_forces(index_t b, int l, const Material& mat, const ElementData<T>& el, const T* u,
                              index_t P, T* f_out, T* J_out) {
    element_forces_to(b, l, mat, el, u, P, b, f_out, J_out);
}

/// Kernel 1 of a viscoelastic material as the phases of visco_begin (materials.hpp), over slot
/// (b, l)'s scratch s: (1) visco_forces_begin: kinematics from u [m] SoA (3, P), J_out (det F,
/// K=1), visco_begin; (2) visco_terms for the Prony terms (the caller's); (3) visco_forces_end:
/// f_out [N] AoSoA K=12 from P = F S (store_forces).
template <class T, class Material, class Scratch>
PLIANT_HD void visco_forces_begin(index_t b, int l, const Material& mat, const ElementData<T>& el, const T* u,
                                  index_t P, T* J_out, Scratch s) {
    const Kinematics<T> k = kinematics(displacement_gradient(b, l, el, u, P));
    visco_begin(mat, k, s);
    J_out[aosoa(b, l, 0, 1)] = k.J;
}
template <class T, class Scratch>
PLIANT_HD void visco_forces_end(index_t b, int l, const ElementData<T>& el, T* f_out, Scratch s) {
    store_forces<false>(b, l, el, visco_pk1<T>(s), b, f_out);
}

/// Stiffness-proportional (Rayleigh β) damping as a viscous stress, added to the element forces:
/// S_d = β (λ0 tr(Ė) I + 2μ0 Ė), Ė = sym(Fᵀ Ḟ), Ḟ = ∇X v with the half-step velocity
/// v = du/Δt (du = u − u⁻ before rounding: node_update), and f_a += V0 · F S_d ∇X N_a. At small strain this
/// is C = βK with the material's small-strain moduli (μ0 = shear_modulus(), λ0 = dilatational_modulus() −
/// 2μ0); rigid motion has Ė = 0 and is not damped (Belytschko, Liu & Moran 2000, §6.2.2 and Box 6.1;
/// Abaqus/Explicit's β damping stress σ_d = β D^el : ε̇). Central differences with it are stable
/// for Δt ≤ (2/ω_max)(√(1 + ξ²) − ξ), ξ = β ω_max / 2 (Belytschko et al. 2000, eq. 6.3.18).
/// Inputs: material, element data, u and du [m] SoA (3, P), β/Δt [1]. Output: f_inout [N] (+=).
template <class T, class Material>
PLIANT_HD void add_damping_forces(index_t b, int l, const Material& mat, const ElementData<T>& el, const T* u,
                                  const T* du, index_t P, T beta_over_dt, T* f_inout) {
    const Mat3<T> H = displacement_gradient(b, l, el, u, P);
    const Mat3<T> Hd = displacement_gradient(b, l, el, du, P);  // Ḟ Δt
    Mat3<T> FtFdot;                                             // Fᵀ Ḟ Δt, F = I + H
    PLIANT_UNROLL
    for (int i = 0; i < 3; ++i) {
        PLIANT_UNROLL
        for (int j = 0; j < 3; ++j) {
            T s = Hd.a[3 * i + j];
            PLIANT_UNROLL
            for (int k = 0; k < 3; ++k) s += H.a[3 * k + i] * Hd.a[3 * k + j];
            FtFdot.a[3 * i + j] = s;
        }
    }
    const Sym3<T> Edt = sym(FtFdot);  // Ė Δt
    const T mu = mat.shear_modulus(), lam = mat.dilatational_modulus() - T(2) * mu;
    const Sym3<T> Sd = scale(beta_over_dt, add_identity(lam * trace(Edt), scale(T(2) * mu, Edt)));
    Mat3<T> F = H;
    F.a[0] += T(1), F.a[4] += T(1), F.a[8] += T(1);
    store_forces<true>(b, l, el, mul(F, Sd), b, f_inout);
}

/// Values T4ANP's pass (1) keeps a slot for pass (3) (kKeep): its displacement gradient H (9) and
/// J^(−2/3).
inline constexpr int kAnpKept = 10;

/// Average nodal pressure tetrahedron (T4ANP; Bonet & Burton 1998, Commun. Numer. Meth. Eng.
/// 14:437; Joldes, Wittek & Miller 2009, Commun. Numer. Meth. Eng. 25:827), three passes per step:
/// (1) element_pressure: V0 p(J) per element; (2) nodal_pressure: p̄_a = Σ V0 p / Σ V0 over the
/// elements of node a; (3) element_forces with p̄ = ¼ Σ p̄_a of the element's corners in place of
/// its own pressure. Volumetric locking of nearly incompressible tissue is much reduced.
/// (1) Inputs: decoupled material, element data, u [m] SoA (3, P). Output: ep_out [N·m] (slot).
/// kKeep: H_out (AoSoA K = kAnpKept) also receives the displacement gradient [1] and J^(−2/3),
/// which pass (3) then reads instead of gathering the displacements again and computing J^(−2/3)
/// (Dev::kKeepsAnpGradient).
template <bool kKeep, class T, class Material>
PLIANT_HD void element_pressure(index_t b, int l, const Material& mat, const ElementData<T>& el, const T* u,
                                index_t P, T* ep_out, T* H_out) {
    const Mat3<T> H = displacement_gradient(b, l, el, u, P);
    const Kinematics<T> k = kinematics(H);
    if constexpr (kKeep) {
        PLIANT_UNROLL
        for (int i = 0; i < 9; ++i) H_out[aosoa(b, l, i, kAnpKept)] = H.a[i];
        H_out[aosoa(b, l, 9, kAnpKept)] = k.j23;
    }
    ep_out[aosoa(b, l, 0, 1)] = el.vol[aosoa(b, l, 0, 1)] * mat.pressure(k);
}

/// (2) Node n's averaged pressure p̄ [Pa] from the element values V0 p (slot layout), gathered
/// through the node's incidences' element slots (inc_slot: each incidence's slot b·kLanes + l, in
/// the incidence order), over Σ V0 [m³]; summed in gather_forces' order (four partial sums).
template <class T>
PLIANT_HD T nodal_pressure(index_t n, const index_t* inc_offsets, const index_t* inc_slot, const T* ep,
                           const T* node_volume) {
    const index_t end = inc_offsets[n + 1];
    T s0 = T(0), s1 = T(0), s2 = T(0), s3 = T(0);
    index_t k = inc_offsets[n];
    for (; k + 4 <= end; k += 4)
        s0 += ep[inc_slot[k]], s1 += ep[inc_slot[k + 1]], s2 += ep[inc_slot[k + 2]],
            s3 += ep[inc_slot[k + 3]];
    for (; k < end; ++k) s0 += ep[inc_slot[k]];
    return ((s0 + s1) + (s2 + s3)) / node_volume[n];
}

/// The mean p̄ = ¼ Σ p̄_a [Pa] of slot (b, l)'s corners' nodal pressures (node_p).
template <class T>
PLIANT_HD T corner_pressure(index_t b, int l, const ElementData<T>& el, const T* node_p) {
    T p = T(0);
    PLIANT_UNROLL
    for (int a = 0; a < 4; ++a) p += node_p[el.nodes[aosoa(b, l, a, 4)]];
    return p / T(4);
}

/// (3) Element forces of slot (b, l) with its corners' mean nodal pressure p̄ [Pa] (node_p), with
/// the fraction stab (γ) of its own pressure mixed back in (AveragedPressure).
/// kKept: the displacement gradient is read from H (pass (1)'s H_out), else computed from u [m].
template <bool kKept, class T, class Material>
PLIANT_HD void element_forces_anp(index_t b, int l, const Material& mat, const ElementData<T>& el, const T* u,
                                  index_t P, const T* H, const T* node_p, T stab, T* f_out, T* J_out) {
    const AveragedPressure<Material, T> ap{mat, corner_pressure(b, l, el, node_p), stab};
    if constexpr (kKept) {
        Mat3<T> Hk;
        PLIANT_UNROLL
        for (int i = 0; i < 9; ++i) Hk.a[i] = H[aosoa(b, l, i, kAnpKept)];
        element_forces_at(b, l, ap, el, kinematics(Hk, H[aosoa(b, l, 9, kAnpKept)]), b, f_out, J_out);
    } else {
        element_forces(b, l, ap, el, u, P, f_out, J_out);
    }
}

/// Time-integration coefficients of central differences with mass-proportional damping α [1/s]:
/// u⁺ = γ1 M⁻¹(r − f) + γ2 u + γ3 u⁻, γ1 = 2Δt²/(αΔt + 2), γ2 = 4/(αΔt + 2), γ3 = 1 − γ2
/// (Taylor et al. 2008, IEEE TMI 27(5), eq. 9; Joldes et al. 2009, CMAME 198:3313, eq. 7).
/// Evaluated in the equivalent increment form u⁺ = u + (γ2 − 1)(u − u⁻) + γ1 M⁻¹(r − f): in
/// float32, γ2 and γ3 rounded separately no longer sum to 1, and the leftover (γ2 + γ3 − 1) u acts
/// as a negative spring of ω² ≈ ε/Δt² that made long float32 runs grow unstable (seen on a
/// 12,000-tet Spot at Δt = 3.4e-5 s: e-folding in 0.1 s). The increment form is exact for rest.
template <class T>
struct Integrator {
    T g1, c;  // γ1 [s²], c = γ2 − 1 = (2 − αΔt)/(2 + αΔt)
};
template <class T>
PLIANT_HD Integrator<T> central_difference(double dt, double alpha) {
    const double d = alpha * dt + 2.0;
    return {T(2.0 * dt * dt / d), T((2.0 - alpha * dt) / d)};
}

/// Load-curve kinds; a curve maps time t [s] to a dimensionless factor.
enum class CurveKind : int { Constant = 0, Step = 1, Ramp = 2, SmoothRamp = 3, Table = 4, Hilly = 5 };

struct LoadCurve {
    CurveKind kind;
    double t0, t1;                     // Step: jumps at t0; Ramp/SmoothRamp: 0 at t0 → 1 at t1
    index_t table_begin, table_count;  // Table: piecewise linear in (times, values), held at the ends
};

/// Factor of curve c at time t: Ramp is linear; SmoothRamp is 10τ³ − 15τ⁴ + 6τ⁵ (NiftySim's
/// POLY345, zero velocity and acceleration at both ends); Hilly is τ exp(cos(4πτ) − 1) (NiftySim's
/// HILLY); Table interpolates linearly. τ = (t − t0)/(t1 − t0) clamped to [0, 1].
PLIANT_HD double curve_value(const LoadCurve& c, double t, const double* table_t, const double* table_v) {
    switch (c.kind) {
        case CurveKind::Constant:
            return 1.0;
        case CurveKind::Step:
            return t >= c.t0 ? 1.0 : 0.0;
        case CurveKind::Ramp:
        case CurveKind::SmoothRamp:
        case CurveKind::Hilly: {
            double tau = (t - c.t0) / (c.t1 - c.t0);
            tau = tau < 0.0 ? 0.0 : (tau > 1.0 ? 1.0 : tau);
            if (c.kind == CurveKind::Ramp) return tau;
            if (c.kind == CurveKind::Hilly) return tau * std::exp(std::cos(4.0 * M_PI * tau) - 1.0);
            return tau * tau * tau * (10.0 + tau * (-15.0 + 6.0 * tau));
        }
        default: {
            const double* ts = table_t + c.table_begin;
            const double* vs = table_v + c.table_begin;
            const index_t n = c.table_count;
            if (t <= ts[0]) return vs[0];
            if (t >= ts[n - 1]) return vs[n - 1];
            index_t k = 0;
            while (ts[k + 1] < t) ++k;
            const double w = (t - ts[k]) / (ts[k + 1] - ts[k]);
            return vs[k] + w * (vs[k + 1] - vs[k]);
        }
    }
}

/// Node data for kernel 2: the node → (element, corner) incidence in CSR form. inc_offsets has
/// N + 1 entries; inc_index holds, per incidence, the offset of its x force component in f_elem
/// (corner_force; y and z follow at +1 and +2). Loads: load_patterns[k][d*P + n] [N] scaled by the
/// value of curve k.
template <class T>
struct NodeData {
    const index_t* inc_offsets;
    const index_t* inc_index;
    const T* inv_mass;  // 1/m_a [1/kg], m_a = Σ ρ V0 / 4 over incident elements
    const T* load_patterns;
    int n_patterns;  // rows of load_patterns (pattern factors may have more slots: pressures)
    // Follower pressure on surface triangles: node → faces CSR, 3 nodes per face, reference edges
    // X1 − X0 and X2 − X0 [m] (6 per face), pressure [Pa] and its pattern-factor slot per face.
    const index_t* pface_offsets;
    const index_t* pface_index;
    const index_t* press_nodes;
    const T* press_edges;
    const T* press_value;
    const index_t* press_slot;
    const T* press_traction;  // traction t [Pa] per face (3 each; zero: none), on the current area
    MembraneData<T> mem;      // membrane triangles (membrane.hpp): internal forces gathered per node
};

/// External force [N] of follower pressure and surface traction on node n: Σ over its faces
/// s (−p n + |n| t) / 6, n = (x1 − x0) × (x2 − x0) the current area vector times 2, each
/// triangle's load shared equally by its 3 nodes (Bonet & Wood, Nonlinear Continuum Mechanics for
/// FEA, 2nd ed., §8.4, follower pressure; NiftySim's tledPressureConstraint and
/// tledTractionConstraint, the traction on the current area). Positive p pushes against the face
/// normal n; t [Pa] acts along itself.
/// Inputs: node data, pattern factors s (slot per face), u [m] SoA (3, P). Output: out [N] (3).
template <class T>
PLIANT_HD void pressure_force(index_t n, const NodeData<T>& nd, const T* factors, const T* u, index_t P,
                              T out[3]) {
    out[0] = out[1] = out[2] = T(0);
    const index_t end = nd.pface_offsets[n + 1];
    for (index_t k = nd.pface_offsets[n]; k < end; ++k) {
        const index_t f = nd.pface_index[k];
        const index_t a = nd.press_nodes[3 * f], b = nd.press_nodes[3 * f + 1], c = nd.press_nodes[3 * f + 2];
        T e1[3], e2[3];
        PLIANT_UNROLL
        for (int d = 0; d < 3; ++d) {
            const T ua = u[d * P + a];
            e1[d] = nd.press_edges[6 * f + d] + (u[d * P + b] - ua);
            e2[d] = nd.press_edges[6 * f + 3 + d] + (u[d * P + c] - ua);
        }
        const T n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                        e1[0] * e2[1] - e1[1] * e2[0]};
        const T s = nd.press_value[f] * factors[nd.press_slot[f]] / T(6);
        PLIANT_UNROLL
        for (int d = 0; d < 3; ++d) out[d] -= s * n[d];
        const T* t = nd.press_traction + 3 * f;
        if (t[0] != T(0) || t[1] != T(0) || t[2] != T(0)) {  // a traction face: |n| t s / 6
            const T st =
                factors[nd.press_slot[f]] / T(6) * std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            PLIANT_UNROLL
            for (int d = 0; d < 3; ++d) out[d] += st * t[d];
        }
    }
}

/// External load r [N] (3) on node n at the pattern factors given: follower pressure and surface
/// traction (pressure_force) plus the load patterns (point forces and gravity, each pattern's
/// vector times its factor). What node_update drives the node with, and with the internal force
/// what a support holds at equilibrium (Engine::external_forces: reactions = f − r there).
/// Inputs: node data, pattern factors (slot per face and pattern), u [m] SoA (3, P).
template <class T>
PLIANT_HD void applied_loads(index_t n, const NodeData<T>& nd, const T* pattern_factors, const T* u,
                             index_t P, T r[3]) {
    pressure_force(n, nd, pattern_factors, u, P, r);
    for (int k = 0; k < nd.n_patterns; ++k) {
        const T s = pattern_factors[k];
        const T* lp = nd.load_patterns + static_cast<std::size_t>(k) * 3 * P + n;
        PLIANT_UNROLL
        for (int d = 0; d < 3; ++d) r[d] += s * lp[d * P];
    }
}

/// Node n's internal force f [N] (3): the sum of its incidences' element forces (corner_force), in
/// a fixed order (no atomics: the same bits on every device and thread count): four partial sums,
/// s_j over the incidences begin + 4i + j of the list's whole groups of four, the last 0–3 into s_0,
/// then (s_0 + s_1) + (s_2 + s_3). Four chains of additions, where one chain made each addition
/// wait for the one before (kernel 2 took an add's latency an incidence). Where PLIANT_HOST_VECTORS
/// (config.hpp), it reads each incidence's x, y, z with one load of four values and adds them as one
/// vector, the fourth value (the next slot's x, or past the last slot one of f_elem's kForcePad
/// values) to a lane that is dropped: one load and one add an incidence where three each had cost
/// kernel 2 a fifth of its time (docs/engine.md). Elsewhere the same additions one value at a time.
template <class T>
PLIANT_HD void gather_forces(index_t n, const NodeData<T>& nd, const T* f_elem, T f[3]) {
    const index_t begin = nd.inc_offsets[n], end = nd.inc_offsets[n + 1];
    index_t k = begin;
#if PLIANT_HOST_VECTORS
    typedef T V4 __attribute__((vector_size(4 * sizeof(T))));
    V4 s[4] = {}, x[4];  // (no function returning a V4: without AVX that changes an ABI, a warning)
    for (; k + 4 <= end; k += 4) {
        PLIANT_UNROLL
        for (int j = 0; j < 4; ++j) __builtin_memcpy(&x[j], f_elem + nd.inc_index[k + j], sizeof x[j]);
        PLIANT_UNROLL
        for (int j = 0; j < 4; ++j) s[j] += x[j];
    }
    for (; k < end; ++k) {
        __builtin_memcpy(&x[0], f_elem + nd.inc_index[k], sizeof x[0]);
        s[0] += x[0];
    }
    const V4 sum = (s[0] + s[1]) + (s[2] + s[3]);
    f[0] = sum[0], f[1] = sum[1], f[2] = sum[2];
#else
    T s[4][3] = {};
    for (; k + 4 <= end; k += 4) {
        PLIANT_UNROLL
        for (int j = 0; j < 4; ++j) {
            const index_t o = nd.inc_index[k + j];
            PLIANT_UNROLL
            for (int d = 0; d < 3; ++d) s[j][d] += f_elem[o + d];
        }
    }
    for (; k < end; ++k) {
        const index_t o = nd.inc_index[k];
        PLIANT_UNROLL
        for (int d = 0; d < 3; ++d) s[0][d] += f_elem[o + d];
    }
    PLIANT_UNROLL
    for (int d = 0; d < 3; ++d) f[d] = (s[0][d] + s[1][d]) + (s[2][d] + s[3][d]);
#endif
}

/// Kernel 2, one node per lane: gather the element forces of node n in a fixed order (no atomics,
/// bitwise reproducible), add its membrane corners' forces (membrane_force, computed by the
/// membrane pass before it), then u⁺ = u + du⁺,
/// du⁺ = (γ2 − 1) du + γ1 M⁻¹(r − f) (central differences: u⁺ = γ1 M⁻¹(r − f) + γ2 u + γ3 u⁻ with
/// du = u − u⁻), r = load patterns + follower pressure and surface traction at u. du is the last
/// step's increment as computed, before u was rounded to T (plus the correction where a contact moved
/// u⁺ since: contact_node, soft_pass; u⁺ − u where a constraint set it: apply_constraint), so the
/// rounding of u (half a unit in its last place) does not enter the velocity and grow with every step
/// (docs/engine.md, "Precision of float32 runs with small steps").
/// Inputs: node data, element forces, load-pattern factors, u and du [m] SoA (3, P).
/// Outputs: u_out and du_out [m]; f_node_out [N] (internal force per node, may be null).
template <class T>
PLIANT_HD void node_update(index_t n, const NodeData<T>& nd, const T* f_elem, const T* pattern_factors,
                           const Integrator<T>& it, const T* u, const T* du, index_t P, T* u_out, T* du_out,
                           T* f_node_out) {
    T f[3];
    gather_forces(n, nd, f_elem, f);
    if (nd.mem.count) membrane_force(n, nd.mem, f);
    const T w = it.g1 * nd.inv_mass[n];
    // Every load before the first store: the stores could alias them as far as the compiler knows,
    // and it would load them again after each.
    T r[3];
    applied_loads(n, nd, pattern_factors, u, P, r);
    T un[3], inc[3];
    PLIANT_UNROLL
    for (int d = 0; d < 3; ++d) {
        inc[d] = it.c * du[d * P + n] + w * (r[d] - f[d]);
        un[d] = u[d * P + n] + inc[d];
    }
    PLIANT_UNROLL
    for (int d = 0; d < 3; ++d) {
        u_out[d * P + n] = un[d];
        du_out[d * P + n] = inc[d];
        if (f_node_out) f_node_out[d * P + n] = f[d];
    }
}

/// Prefetches the element-force lines node n's gather reads (gather_forces; one line per incidence,
/// two where the four values it loads straddle a line). Kernel 2 of a model that outgrows the caches
/// waits on these irregular loads; issued kPrefetchAhead nodes ahead they arrive in time (the 1M-tet
/// benchmark: kernel 2 from 62 % of the step to 44–46 %, docs/engine.md). No effect on any result.
constexpr int kPrefetchAhead = 16;
template <class T>
PLIANT_HD void prefetch_incidences(index_t n, const NodeData<T>& nd, const T* f_elem) {
    for (index_t k = nd.inc_offsets[n]; k < nd.inc_offsets[n + 1]; ++k) {
        const index_t o = nd.inc_index[k];
        prefetch(f_elem + o);
        prefetch(f_elem + o + 3);
    }
}

/// Kinematic constraint i: u⁺[dof_i] = value_i · curve factor (fixed nodes have value 0), and its
/// increment du⁺ = u⁺ − u. dof is d*P + n in the SoA node layout.
template <class T>
PLIANT_HD void apply_constraint(index_t i, const index_t* dof, const T* value, const index_t* curve,
                                const T* curve_factors, const T* u, T* u_out, T* du_out) {
    const index_t k = dof[i];
    u_out[k] = value[i] * curve_factors[curve[i]];
    du_out[k] = u_out[k] - u[k];
}

/// Stress and strain measures of one element, for output (not on the stepping path).
template <class T>
struct ElementMeasures {
    T J, energy;          // det F; strain-energy density W [Pa]
    Sym3<T> S, sigma, E;  // 2nd Piola–Kirchhoff [Pa]; Cauchy σ = J⁻¹ F S Fᵀ [Pa]; Green–Lagrange E
};

/// σ = J⁻¹ P Fᵀ, E = ½(C − I), W of element slot (b, l) (Bonet & Wood, 2nd ed., eqs. 5.31, 3.15).
template <class T, class Material>
PLIANT_HD ElementMeasures<T> element_measures(index_t b, int l, const Material& mat, const ElementData<T>& el,
                                              const T* u, index_t P) {
    const Kinematics<T> k = kinematics(displacement_gradient(b, l, el, u, P));
    ElementMeasures<T> m;
    m.J = k.J;
    m.energy = mat.energy(k);
    m.S = mat.pk2(k);
    const Mat3<T> Pk = mat.pk1(k);
    const T iJ = T(1) / m.J;
    const T* p = Pk.a;
    const T* f = k.F.a;
    m.sigma = {
        iJ * (p[0] * f[0] + p[1] * f[1] + p[2] * f[2]), iJ * (p[3] * f[3] + p[4] * f[4] + p[5] * f[5]),
        iJ * (p[6] * f[6] + p[7] * f[7] + p[8] * f[8]), iJ * (p[0] * f[3] + p[1] * f[4] + p[2] * f[5]),
        iJ * (p[3] * f[6] + p[4] * f[7] + p[5] * f[8]), iJ * (p[0] * f[6] + p[1] * f[7] + p[2] * f[8])};
    m.E = k.E;
    return m;
}

/// Reference geometry of a tetrahedron X [m], shape (4, 3): shape-function gradients
/// grad_out (4, 3) [1/m] (rows of the inverse Jacobian), volume V0 [m³] (negative when inverted)
/// and smallest altitude h_min = 3 V0 / max face area [m] (characteristic length for the stable
/// time step, Belytschko, Liu & Moran 2000, §6.3). Computed in double precision.
PLIANT_HD void tet_reference(const double X[4][3], double grad_out[4][3], double& vol_out,
                             double& altitude_out) {
    double A[3][3];
    PLIANT_UNROLL
    for (int r = 0; r < 3; ++r) PLIANT_UNROLL
    for (int c = 0; c < 3; ++c) A[r][c] = X[c + 1][r] - X[0][r];  // columns X_a − X_0
    const double d = A[0][0] * (A[1][1] * A[2][2] - A[1][2] * A[2][1]) -
                     A[0][1] * (A[1][0] * A[2][2] - A[1][2] * A[2][0]) +
                     A[0][2] * (A[1][0] * A[2][1] - A[1][1] * A[2][0]);
    vol_out = d / 6.0;
    // Rows of A⁻¹ are ∇ξ, ∇η, ∇ζ = ∇N_1, ∇N_2, ∇N_3.
    const double inv = d != 0.0 ? 1.0 / d : 0.0;
    double B[3][3];
    PLIANT_UNROLL
    for (int r = 0; r < 3; ++r) PLIANT_UNROLL
    for (int c = 0; c < 3; ++c) {
        const int r1 = (c + 1) % 3, r2 = (c + 2) % 3, c1 = (r + 1) % 3, c2 = (r + 2) % 3;
        B[r][c] = (A[r1][c1] * A[r2][c2] - A[r1][c2] * A[r2][c1]) * inv;
    }
    PLIANT_UNROLL
    for (int j = 0; j < 3; ++j) {
        grad_out[1][j] = B[0][j];
        grad_out[2][j] = B[1][j];
        grad_out[3][j] = B[2][j];
        grad_out[0][j] = -(B[0][j] + B[1][j] + B[2][j]);
    }
    // Face opposite corner a has area 3|V|·|∇N_a|, so the altitude from corner a is 1/|∇N_a|.
    double gmax = 0.0;
    PLIANT_UNROLL
    for (int a = 0; a < 4; ++a) {
        const double g = grad_out[a][0] * grad_out[a][0] + grad_out[a][1] * grad_out[a][1] +
                         grad_out[a][2] * grad_out[a][2];
        gmax = g > gmax ? g : gmax;
    }
    altitude_out = gmax > 0.0 ? 1.0 / std::sqrt(gmax) : 0.0;
}

}  // namespace pliant
