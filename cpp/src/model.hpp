// pliant — the static model (Model) and the per-step state (State) of the CPU backend, laid out
// for the kernels of tled.hpp. Built once from arrays that the Python ModelBuilder prepared.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "pliant/contact.hpp"
#include "pliant/smoothing.hpp"
#include "pliant/soft_contact.hpp"

namespace pliant {

/// One element group: consecutive blocks sharing a material.
template <class T>
struct Group {
    index_t block_begin, block_end;
    MaterialParams<T> material;
    Prony<T> visco;  // n_iso = n_vol = 0: elastic
};

/// Raw description of a model handed over by the builder (all in SI units, user-facing node and
/// element numbering already replaced by the builder's locality-friendly order).
struct ModelInput {
    const double* X;  // reference positions [m], (N, 3)
    index_t n_nodes;
    const index_t* tets;    // (M, 4), positively oriented
    const double* density;  // [kg/m³], (M,)
    index_t n_elems;
    std::vector<index_t> group_end;    // element index one past each group, ascending
    std::vector<int> group_kind;       // MaterialKind per group
    std::vector<double> group_params;  // kMaterialParams per group
    std::vector<double> group_visco;   // per group: n_iso, n_vol, then (α, τ) × kPronyMax; or
                                       // empty (no viscoelasticity)
    const double* patterns;            // load patterns [N], (K, N, 3)
    int n_patterns;
    std::vector<index_t> pattern_curve;   // curve per pattern
    double gravity[3] = {0.0, 0.0, 0.0};  // [m/s²], applied as the pattern m_a·g
    index_t gravity_curve = -1;           // −1: no gravity
    std::vector<index_t> cons_node;       // constrained DOFs: node, dim, value [m], curve
    std::vector<int> cons_dim;
    std::vector<double> cons_value;
    std::vector<index_t> cons_curve;
    std::vector<LoadCurve> curves;
    std::vector<double> table_t, table_v;
    std::vector<index_t> contact_nodes;  // surface nodes that take part in contact
    std::vector<index_t> contact_masks;  // per contact node: bit k set if tool k (< kMaskedTools)
                                         // may touch it
    std::vector<double> contact_skin;    // per contact node: [m] kept from the tools' surfaces (a
                                         // sheet's half thickness); empty: 0
    std::vector<RigidTool> tools;
    std::vector<double> tool_keys;       // 8 per keyframe: t, position (3), quaternion (4)
    std::vector<double> tool_grid;       // signed-distance grids [m]
    std::vector<double> tool_grips;      // grasping tools' close/open times [s] (RigidTool::grip_begin)
    std::vector<index_t> press_nodes;    // follower-pressure triangles, 3 nodes each
    std::vector<double> press_value;     // [Pa] per triangle (positive: against its normal)
    std::vector<index_t> press_curve;    // curve per triangle
    std::vector<double> press_traction;  // traction t [Pa] per triangle (3 each; empty: none), on its
                                         // current area: |a| t / 3 per node (pressure_force)
    bool anp = false;                    // average nodal pressure (T4ANP)
    double stiffness_damping = 0.0;      // Rayleigh β [s] (tled.hpp: add_damping_forces)
    double anp_stabilization = 0.0;      // T4ANP: fraction γ of the element's own pressure
    bool anp_shear = false;              // T4ANP: γ = μ/K of each group's material (anp_shear_gamma)
    StrainSmoothing smoothing = StrainSmoothing::Element;  // per element, or edge-smoothed (ES-FEM-T4)
    // Membrane triangles (membrane.hpp): 3 nodes each, MembraneKind each, and per membrane its
    // thickness h [m], density ρ [kg/m³] and two moduli (E [Pa], ν; or μ [Pa], 0).
    std::vector<index_t> mem_nodes;
    std::vector<int> mem_kind;
    std::vector<double> mem_params;  // kMembraneParams per membrane: h, ρ, p1, p2, wrinkles (0/1)
    // Bending (membrane_bending_forces; both empty where no membrane bends): per membrane its
    // kMembraneNbrs patch nodes (membrane.hpp, kMembraneSlots: the node across each edge e, opposite
    // corner e, or kFreeEdge, kClampedEdge; then two across each neighbour's other edges, or −1)
    // and its bending modulus E_b [Pa] and Poisson's ratio ν_b (E_b = 0: it does not bend).
    std::vector<index_t> mem_nbrs;
    std::vector<double> mem_bend;
    // Contact between deformable surfaces (soft_contact.hpp): its surface nodes (engine nodes) with
    // their body labels, its triangles (3 surface-node indices each, outward), the pair table
    // (labels × labels, pair index or −1), μs and μk per pair, the Verlet skin [m].
    std::vector<index_t> soft_nodes, soft_label, soft_tris, soft_pair;
    std::vector<double> soft_mu;
    std::vector<double> soft_sheet_h;  // per label: half a sheet's thickness [m] (two-sided); 0: a solid
    index_t soft_labels = 0;
    double soft_skin = 0.0;
};

template <class T>
struct Model {
    index_t n_nodes = 0, n_pad = 0, n_elems = 0, n_blocks = 0;
    std::vector<index_t> elem_nodes;  // AoSoA K=4 over padded elements
    std::vector<T> elem_grad, elem_vol;
    std::vector<index_t> elem_id;      // padded slot → builder element index (−1 for padding)
    std::vector<index_t> block_group;  // block → group
    std::vector<Group<T>> groups;
    std::vector<index_t> inc_offsets, inc_index;
    std::vector<T> mass, inv_mass, free_mask;  // (P,), (P,), (3P,)
    // Fictitious masses for dynamic relaxation [kg], (P,): element densities scaled so that every
    // element's critical step equals dt_critical (Underwood 1983, "Dynamic relaxation", §4: the
    // static solution does not depend on the mass; large elements no longer wait on small ones).
    std::vector<T> relax_mass, relax_inv_mass;
    std::vector<T> load_patterns;  // (K, 3, P)
    int n_load_patterns = 0;       // K; pattern_curve also holds the pressure slots
    std::vector<index_t> pattern_curve;
    std::vector<index_t> pface_offsets, pface_index, press_nodes, press_slot;
    std::vector<T> press_edges, press_value, press_traction;
    bool anp = false;                // average nodal pressure tetrahedra (T4ANP)
    double stiffness_damping = 0.0;  // Rayleigh β [s]: viscous stress β C0 : Ė in dynamic steps
    double anp_stabilization = 0.0;  // T4ANP: p = p̄ + γ (p(J_e) − p̄) (AveragedPressure)
    bool anp_shear = false;          // T4ANP: γ = μ/K of each group's material instead (anp_shear_gamma)
    int visco_terms = 0;             // max Prony terms of any group: the State's q holds 6 each
    std::vector<T> node_volume;      // Σ V0 of the elements of each node [m³], (P,), T4ANP only
    std::vector<index_t> inc_slot;   // T4ANP only: each incidence's element slot b·kLanes + l
    // Membranes (membrane.hpp): node → force slot CSR (kMembraneSlots m + slot), nodes, kinds,
    // kMembraneValues each; where any bends, their patch nodes (kMembraneNbrs each) and
    // kBendValues each; per membrane its critical step [s] (host, reports); the membrane that limits
    // dt_critical, or −1 (an element does).
    std::vector<index_t> mem_offsets, mem_index, mem_nodes, mem_kind, mem_nbrs;
    std::vector<T> mem_geom, mem_bend;
    std::vector<double> mem_dt;
    index_t dt_critical_membrane = -1;
    // Edge-smoothed strain (smoothing.hpp): per edge its elements (CSR, slots ascending) and weights,
    // its group; per slot its six edges (AoSoA K=6); per group its first edge (G + 1 entries).
    StrainSmoothing smoothing = StrainSmoothing::Element;
    index_t n_edges = 0;
    std::vector<index_t> edge_off, edge_slot, edge_group, elem_edges, group_edge_begin;
    std::vector<T> edge_w;
    std::vector<index_t> cons_dof, cons_curve;  // sorted by node
    std::vector<T> cons_value;
    std::vector<index_t> cons_offsets;  // node n's constraints: [cons_offsets[n], [n+1])
    std::vector<LoadCurve> curves;
    std::vector<double> table_t, table_v;
    std::vector<double> X;  // reference positions [m], AoS (N, 3)
    std::vector<index_t> contact_nodes;
    std::vector<index_t> contact_bits;  // per contact node: bits 0–2 free DOFs, bit 3 + k tool k
    std::vector<double> contact_skin;   // per contact node: [m] kept from the tools' surfaces
    std::vector<RigidTool> tools;
    std::vector<double> tool_keys, tool_grid, tool_grips;
    // Soft contact (ModelInput's, plus each surface node's free-DOF bits, each triangle's mean
    // reference edge [m], the grid's cell size [m] and hash mask, the number of pairs).
    std::vector<index_t> soft_nodes, soft_bits, soft_label, soft_tris, soft_pair;
    std::vector<index_t> soft_vtri_off, soft_vtri;  // surface node → its triangles (CSR)
    std::vector<index_t> soft_edges;     // sharp surface edges: 2 surface nodes each (soft_contact.hpp)
    std::vector<index_t> soft_tri_edge;  // per triangle, its edge k (v_k, v_k+1): sharp edge or −1
    std::vector<double> soft_mu, soft_tri_h;
    std::vector<double> soft_sheet_h;  // per label: half a sheet's thickness [m]; 0: a solid's surface
    index_t soft_labels = 0, soft_pairs = 0, soft_hash_mask = 0;
    double soft_skin = 0.0, soft_cell = 0.0;
    double soft_band = 0.0;    // farthest a contact's closest point lies [m]: band + sheets' half thicknesses
    double dt_critical = 0.0;  // min over elements of h_min / c_d [s]
    index_t dt_critical_elem = -1;
    std::vector<double> elem_dt;  // per builder element: h_min / c_d [s] (host only, for reports)

    explicit Model(const ModelInput& in);

    /// Slots of the viscoelastic state (6 × visco_terms values each): element slots, or with
    /// edge-smoothed strain the edge slots (the edges' stresses carry the viscosity).
    std::size_t visco_slots() const {
        return smoothing == StrainSmoothing::Edge ? static_cast<std::size_t>(n_edges)
                                                  : static_cast<std::size_t>(n_blocks) * kLanes;
    }
    MembraneData<T> membranes() const {
        return {static_cast<index_t>(mem_kind.size()),
                mem_offsets.data(),
                mem_index.data(),
                mem_nodes.data(),
                mem_kind.data(),
                mem_geom.data(),
                nullptr,  // (the engine's corner forces: measures need none)
                mem_nbrs.empty() ? nullptr : mem_nbrs.data(),
                mem_bend.empty() ? nullptr : mem_bend.data()};
    }
    ElementData<T> elements() const { return {elem_nodes.data(), elem_grad.data(), elem_vol.data()}; }
    /// Node data with the physical masses, or with the dynamic-relaxation masses if `relax`.
    NodeData<T> nodes(bool relax = false) const {
        return {inc_offsets.data(),   inc_index.data(),   relax ? relax_inv_mass.data() : inv_mass.data(),
                load_patterns.data(), n_load_patterns,    pface_offsets.data(),
                pface_index.data(),   press_nodes.data(), press_edges.data(),
                press_value.data(),   press_slot.data(),  press_traction.data(),
                membranes()};
    }
    /// Curve factors at time t [s], one per curve.
    void curve_factors(double t, T* out) const {
        for (std::size_t c = 0; c < curves.size(); ++c)
            out[c] = T(curve_value(curves[c], t, table_t.data(), table_v.data()));
    }
    std::size_t bytes() const;

private:
    /// Per-node sums over elements while they are built: lumped mass [kg], stiffness-scaled
    /// relaxation density ρ' V Δt_c⁻² sums, volume [m³]; and per-node incidence counts.
    struct NodeSums {
        std::vector<double> mass, stiff, vol;
        std::vector<index_t> count;
    };
    // The constructor's steps, in order.
    void build_groups(const ModelInput& in);
    NodeSums build_elements(const ModelInput& in);
    void build_membranes(const ModelInput& in, NodeSums& sums);
    double build_bending(const ModelInput& in, index_t m, double area, double alt, NodeSums& sums);
    void build_masses(const ModelInput& in, const NodeSums& sums);
    void build_incidence(std::vector<index_t> count);
    void build_smoothing(const ModelInput& in);
    void build_loads(const ModelInput& in, const std::vector<double>& mass);
    void build_pressure(const ModelInput& in);
    void build_constraints(const ModelInput& in);
    void build_contact_and_tables(const ModelInput& in);
    void build_soft_contact(const ModelInput& in);
    void build_soft_adjacency();
    void build_soft_edges();
};

/// A stamp unique in the process (State::version).
std::uint64_t new_version();

/// Per-step state: displacements now and one step before [m], SoA (3, P); time t [s] and the last
/// step Δt [s] (velocity v_{n−½} = (u − u⁻)/Δt). `version` changes with every change of the
/// values (touch()): a backend whose device holds a copy of this state knows whether it is current.
template <class T>
struct State {
    std::vector<T> u, u_prev;
    // The last step's increment u − u⁻ as the update computed it, before u was rounded to T (plus the
    // correction where a contact moved u; u − u⁻ where a constraint set it): the next step's velocity
    // × Δt (node_update), so that the rounding of u does not enter it. Set to u − u⁻ whenever u or u⁻
    // is set from outside.
    std::vector<T> du;
    std::vector<T> q;  // viscoelastic state: 6 × visco_terms per element (or edge) slot, AoSoA (may be empty)
    // Grasping, per contact node (the model's contact-node order): the tool holding it (−1: none)
    // and its position in that tool's frame [m], (n_contact, 3).
    std::vector<index_t> grip_tool;
    std::vector<double> grip_at;
    double t = 0.0, dt = 0.0;
    long step = 0;
    // The run clock: while Δt stays dt, the time after step k is t_epoch + (k − step_epoch) Δt
    // (clock_time), counted from here whichever runs the steps were split into, so that a run
    // split in two (frames, save and restore) meets its curves and tool poses at the same times,
    // to the bit, as one run. Restarted (restart_clock) where t, Δt or the step count are set
    // from outside, Δt changes, or a relaxation sets the time.
    double t_epoch = 0.0;
    long step_epoch = 0;
    std::uint64_t version = new_version();
    explicit State(index_t n_pad, std::size_t q_size = 0, std::size_t n_contact = 0)
        : u(3 * static_cast<std::size_t>(n_pad), T(0)),
          u_prev(u),
          du(u),
          q(q_size, T(0)),
          grip_tool(n_contact, -1),
          grip_at(3 * n_contact, 0.0) {}
    void touch() { version = new_version(); }
    void restart_clock() { t_epoch = t, step_epoch = step; }
};

/// The time [s] k steps of dt after a clock's epoch t0: one expression wherever a time is counted
/// (the steps' load and pose times, the state's time after a run), so that both round alike.
PLIANT_HD double clock_time(double t0, long k, double dt) { return t0 + static_cast<double>(k) * dt; }

/// u or u⁻ set from outside: the increment is u − u⁻ again.
template <class T>
void reset_increment(State<T>& s) {
    for (std::size_t i = 0; i < s.u.size(); ++i) s.du[i] = s.u[i] - s.u_prev[i];
    s.touch();
}

/// Central differences assume equal steps: when Δt changes from s.dt to dt, rescale u⁻ and the
/// increment du so that the velocity (u − u⁻)/Δt = du/Δt is kept. Returns whether anything changed.
template <class T>
bool keep_velocity(State<T>& s, double dt) {
    if (s.dt <= 0.0 || s.dt == dt) return false;
    const T r = T(dt / s.dt);
    for (std::size_t i = 0; i < s.u.size(); ++i) {
        s.u_prev[i] = s.u[i] - r * (s.u[i] - s.u_prev[i]);
        s.du[i] = r * s.du[i];
    }
    return true;
}

}  // namespace pliant
