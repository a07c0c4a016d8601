// pliant — the engine: the step sequence of Total Lagrangian Explicit Dynamics and of dynamic
// relaxation, written once, over a device (executor) that provides memory, copies and three
// launch shapes (each item, each element slot of a block range, one serial item), plus graphs.
// Built for ThreadsDevice (CPU: OpenMP + SIMD), CudaDevice, and EmulatedDevice (the CUDA engine
// on the host, for tests). The physics are the header-only kernels of tled.hpp / contact.hpp.
//
// A step (step_once): (1) step scalars: load-curve factors, tool poses, the step counter;
// (2) element forces per material group (T4ANP: element pressures, nodal averages, then forces;
// edge-smoothed strain: element gradients, edge stresses, then forces; viscoelastic: the Prony
// state advances); (3) per node: gather, central difference update,
// kinematic constraints; (4) contact with the rigid tools (and grasping) and the per-tool force sums;
// (5) contact between deformable surfaces (soft_contact.hpp) and the per-pair force sums.
// Stability checks every `check_every` steps (J ≤ 0 or NaN per element; non-finite or blown-up nodes).
// Everything a kernel needs is captured by value (a DeviceView of device pointers): CUDA kernels
// cannot read the host object, and graphs keep the values they were captured with.
#pragma once

#include <algorithm>
#include <climits>
#include <cmath>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "backend.hpp"
#include "buffers.hpp"

namespace pliant {

/// Device-resident scalars of a run: written by the step-scalars, check and measure kernels, read
/// back by the host at checks.
template <class T>
struct Scalars {
    double t0;  // the run clock's epoch [s] (State::t_epoch)
    long base;  // steps from the epoch to this call's first (State::step − State::step_epoch)
    long step;  // steps taken in this call
    long row;   // tool-history row of the current step
    Integrator<T> it;
    double alpha;            // relax: adaptive damping [1/s]
    double rq_now, rq_last;  // relax: the smallest Rayleigh quotient [1/s²] of this window and the last
    long rq_steps;           // relax: steps into this window (kRelaxWindow)
    double residual;         // relax: relative out-of-balance force at the last measure
    int bad_slot, bad_node;  // check: smallest offending element slot / node (INT_MAX: none)
    int status;              // check verdict (RunStatus)
    index_t where;
    double value;
    int soft_due;      // soft contact: rebuild the candidate lists at the next step (set at each run's start)
    int soft_rebuild;  // soft contact: rebuild them this step (due, or a node left its skin)
    int soft_moved;  // soft contact: smallest surface node beyond skin/2 of its last rebuild (INT_MAX: none)
    // soft contact: the largest triangle bounding radius at the last rebuild [m], as its bits (an
    // atomic maximum; non-negative doubles order as their bits do)
    std::int64_t soft_rmax;
    index_t soft_active, soft_touched;  // soft contact: nodes with candidates; nodes of a sweep's contacts
    index_t soft_contacts;              // soft contact: a sweep's contacts (soft_count)
    index_t soft_edges_active;          // soft contact: sharp edges with an end node that has candidates
    index_t soft_items;                 // soft contact: the larger of soft_active and soft_edges_active
    index_t soft_redo;                  // soft contact: soft_items if the last sweep moved a node, else 0
    index_t soft_lanes;       // soft contact: soft_active × kSoftCandidates (Dev::kSplitsDetection's items)
    index_t soft_lanes_redo;  // soft contact: soft_lanes if the last sweep moved a node, else 0
    // soft contact: the largest impulse component of a sweep's contacts [kg·m], as its bits (an atomic
    // maximum), and the unit of that sweep's fixed-point impulse sums [kg·m] (soft_gather)
    std::int64_t soft_pmax;
    double soft_unit;
};

/// Everything the kernels read or write, as device pointers and sizes (trivially copyable).
template <class T>
struct DeviceView {
    index_t n_nodes, P, slots, n_contact, chunks, contact_chunk;  // contact nodes per chunk: chunk_size
    int n_curves, n_factors, n_tools, visco_w;
    const T* anp_gamma;  // T4ANP stabilization γ per group (AveragedPressure)
    ElementData<T> el;
    bool smoothed;              // edge-smoothed strain (smoothing.hpp)
    bool prefetch;              // kernel 2 prefetches its gathers (Dev::kPrefetch, a model beyond the caches)
    bool stream;                // kernel 1 streams its forces past the caches (Dev::kStreams, the same)
    EdgeData<T> ed;             // its edge domains
    const index_t* edge_group;  // edge → material group
    T *H_elem, *Hbar, *P_edge;  // element gradients (9 per slot), edge gradients (AoSoA K=9),
                                // edge stresses [Pa] (9 per edge)
    const index_t* elem_id;
    const index_t* block_group;      // block → material group
    const MaterialParams<T>* mats;   // per group (scaled moduli: scale_materials)
    const Prony<T>* prony;           // per group
    NodeData<T> nodes, relax_nodes;  // physical / dynamic-relaxation inverse masses
    const T *mass, *relax_mass, *free_mask, *node_volume, *cval;
    const index_t* inc_slot;  // T4ANP: each incidence's element slot (Model::inc_slot)
    const index_t *co, *cdof, *ccurve, *pattern_curve, *cnodes, *cbits;
    const LoadCurve* curves;
    const double *tt, *tv, *X, *grid;
    const double* cskin;  // per contact node: [m] kept from the tools' surfaces (Model::contact_skin)
    const RigidTool* tools;
    const double *keys, *grips;  // keyframes, grasping tools' close/open times
    T *u[3], *du[3], *q, *f_elem, *J, *elem_p, *node_p, *f_node[2], *cnext, *pf;
    T* H_anp;  // T4ANP: pass (1)'s gradients and J^(−2/3) for pass (3), AoSoA K=kAnpKept (kKeepsAnpGradient)
    Scalars<T>* sc;
    Pose *pose0, *pose1;
    double *cforce, *chunk, *hist, *fcon, *partial;
    index_t* ctool;
    index_t* closed;  // per tool: grip bits of the step (kGripClosedBefore / After)
    index_t* gtool;   // per contact node: the tool holding it, −1 (State::grip_tool)
    double* gat;      // per contact node: its position in that tool's frame [m] (State::grip_at)
    // Tool and pair forces per step: hist_width = 6 per tool + 3 per soft-contact pair.
    index_t hist_width, n_pairs;
    // Soft contact (engine_soft.hpp): the surface, positions at the last rebuild (3 per surface node),
    // each chunk's largest move², the grid (bucket heads, cursors, each triangle's bucket, centroid,
    // radius; triangles by bucket), candidates (kSoftCandidates per node), each node's contact
    // (triangle, weights, impulse), forces [N] (3 per node); a sweep's sums in fixed point
    // (soft_gather): shares (units of 2^-32) and impulses (units of Scalars::soft_unit) per node, and
    // impulses per pair (3 each).
    SoftSurface soft;
    double *sb, *stc, *str, *srec_w, *srec_p, *sforce, *erec_w, *erec_p;
    std::int64_t *sshare, *sacc, *spair;
    double* sx;  // the surface positions at u⁺ [m] (3 per node: soft_current), kept through the pass
    index_t *shead, *scursor, *sbucket, *scell, *scand, *snear, *srec, *sactive, *stouched, *erec, *eactive;
    std::int64_t* spart;  // the chunk sums of the rebuild's prefix sums (Engine::scan)
    // Dev::kSplitsDetection: each active node's candidates' closest points (kSoftCandidates slots per
    // entry of sactive): feature, squared distance [m²], weights (3 per slot).
    int* slane_f;
    double *slane_d2, *slane_w;
};

/// Which element function a material group runs (dispatch happens once, in Engine::dispatch).
enum class Variant { Plain, Visco, Anp };

/// Consecutive blocks whose groups share a material kind and variant (and Prony term counts,
/// isochoric and volumetric: the phases of a viscoelastic launch): one launch. The kernels
/// read each block's material parameters from the device, so groups that differ only in their
/// values (the copies of a batch, a model's element sets of one kind) cost a single launch.
struct Span {
    index_t block_begin, block_end;
    index_t group;                 // the first group (its kind decides the element function)
    index_t edge_begin, edge_end;  // its groups' edge domains (edge-smoothed strain)
};

/// Items per chunk of a fixed-order sum over n items (the tool forces over the contact nodes, the
/// rebuild's prefix sums: Engine::scan): the power of two from 64 up that is at least √n, so that
/// each chunk's thread and the one thread over the chunks both walk about √n items (on a GPU, one
/// thread walking thousands is what a step waits for).
inline index_t chunk_size(index_t n) {
    index_t c = 64;
    while (static_cast<long long>(c) * c < n) c *= 2;
    return c;
}
/// Chunks of chunk_size(n) items over n items (not monotone in n: where the chunk size doubles,
/// the count halves).
inline index_t chunk_count(index_t n) { return (n + chunk_size(n) - 1) / chunk_size(n); }
/// Nodes per chunk of the relaxation's residual sums (fixed: the same bits for any thread count).
constexpr index_t kMeasureChunk = 1024;
/// Relaxation: steps per window of the damping's eigenvalue estimate (relax_measure takes the
/// smallest Rayleigh quotient of this window and the last). The fictitious masses give every
/// element the same critical step, so a step count spans a fixed number of the highest modes'
/// periods (about 80 at 0.8 of that step): enough to see past the jitter that contact's corrections
/// add to one step's quotient, short enough to follow a structure that stiffens as it deforms.
/// Measured (docs/engine.md): of windows of 100, 250, 300, 500 and 1,000 steps, 300 the best
/// compromise between a pressed organ and a sheet draped on a ball (1,000: the organ faster, the
/// sheet 3x slower).
constexpr long kRelaxWindow = 300;
/// Steps per replayed launch sequence (a CUDA graph) between two checks: a multiple of 6, the
/// period of the buffer rotation (3) and of relax's force-buffer toggle (2), so that one captured
/// graph serves every unit of a run. Longer runs between checks launch it repeatedly instead of
/// capturing (and instantiating) a graph of check_every steps for each rotation phase.
constexpr long kGraphSteps = 48;

template <class T, class Dev>
class Engine final : public Backend<T> {
public:
    template <class... A>
    explicit Engine(const Model<T>& m, A&&... dev_args);

    RunReport run(State<T>& s, long n, double dt, double alpha, int check_every, double size) override;
    RunReport step(const State<T>& in, State<T>& out, double dt, double alpha) override;
    RunReport relax(State<T>& s, double t_eval, double dt, double tol, long max_steps, int check_every,
                    double size) override;
    ElementResults<T> measures(const State<T>& s) override;
    std::vector<T> internal_forces(const State<T>& s, bool damped) override;
    std::vector<T> external_forces(const State<T>& s, double t) override;
    std::vector<double> tool_history() override;
    std::vector<double> pair_history() override;
    ContactReport contact_report() override;
    void set_tool_keys(const std::vector<std::vector<double>>& keys,
                       const std::vector<std::vector<double>>& grips,
                       const std::vector<double>& reach) override;
    void scale_materials(double factor) override;
    std::string name() const override { return Dev::kName; }
    int threads() const override { return dev_.threads(); }

    // --- kernels: public, as CUDA extended lambdas may not live in private member functions ----
    /// The three displacement buffers: u at t (cur), at t − Δt (prev), and the step's output.
    struct Phase {
        int prev = 0, cur = 1, next = 2;
        void rotate() {
            const int p = prev;
            prev = cur;
            cur = next;
            next = p;
        }
    };
    void step_once(const Phase& ph, double dt, double time_dt, bool relaxing, T* f_node_out, RunReport& rep);
    void step_scalars(double time_dt, bool fixed_row);
    void forces(const T* u, ViscoMode visco_mode, double dt);
    void edge_stresses(const T* u, ViscoMode visco_mode, double dt);
    void nodal_pressures();
    template <class M, Variant V>
    void launch_gradient(const Span& sp, const T* u);
    template <class F>
    void with_visco_mode(ViscoMode visco_mode, F&& f);
    template <class M, Variant V>
    void launch_edge_stress(const Span& sp);
    template <class M, int kMode>
    void launch_visco_edge_stress(const Span& sp, ViscoMode visco_mode, double dt);
    void node_pass(const Phase& ph, bool relaxing, T* f_node_out);
    void load_pass(double t, const T* u, T* f_out);
    void contact_pass(const Phase& ph, bool relaxing);
    void soft_pass(const Phase& ph, bool relaxing);
    void soft_lists(const T* u);
    template <class Count, class Total, class Emit>
    void scan(index_t n, const int* flag, const Count& count, const Total& total, const Emit& emit);
    Scalars<T> check(const T* u_new, const T* u_old, double t_elem, double t_node, double size,
                     RunReport& rep);
    void relax_measure(const T* u_cur, const T* u_prev, const T* f_cur, const T* f_prev, double dt,
                       long steps);
    void copy(T* dst, const T* src, std::size_t n);
    void fill(T* dst, T value, std::size_t n);
    template <class M, Variant V, bool kKeep>
    void launch_pressure(const Span& sp, const T* u);
    template <class M, Variant V>
    void launch_forces(const Span& sp, const T* u, ViscoMode visco_mode, double dt);
    template <class M, int kMode>
    void launch_visco_forces(const Span& sp, const T* u, ViscoMode visco_mode, double dt);
    template <class M, Variant V>
    void launch_measures(const Span& sp, const T* u, double dt, T* out);
    void damping(const Phase& ph, double dt);
    template <class M, Variant V>
    void launch_damping(const Span& sp, const T* u, const T* du, T beta_over_dt);

private:
    /// k steps between two checks, as launch sequences of at most kGraphSteps steps each replayed
    /// by the device (dev_.repeat), key naming the host bookkeeping the launches bake in (the
    /// buffer phase): the same at each sequence's start, kGraphSteps being a multiple of its period.
    template <class Step>
    void replay_steps(long k, long key, Step&& step) {
        for (long done = 0; done < k; done += kGraphSteps)
            dev_.repeat(std::min(kGraphSteps, k - done), key, step);
    }
    template <class Visitor>
    void dispatch(Visitor&& visit);
    void load(const State<T>& s);
    void store(State<T>& s);
    void set_scalars(double t0, long base, double dt, double alpha);
    void ensure_history(long rows);
    void allocate_soft(std::size_t ns, std::size_t nst);
    std::vector<double> history_columns(std::size_t begin, std::size_t width);
    void refresh_view();
    void upload_materials();

    const Model<T>& m_;
    Dev dev_;
    std::vector<Group<T>> groups_;  // the model's, with scaled moduli (scale_materials)
    std::vector<Span> spans_;       // launches of the element kernels
    std::vector<RigidTool> tools_;  // the model's, with replaced keyframes (set_tool_keys)
    ModelBuffers<T, Dev> mb_;
    DeviceBuffer<RigidTool, Dev> d_tools_;
    DeviceBuffer<double, Dev> d_keys_, d_grips_, cforce_, chunk_, hist_, fcon_, partial_, gat_;
    DeviceBuffer<T, Dev> u_[3], du_[3], q_, f_elem_, J_, elem_p_, node_p_, H_anp_, f_node_[2], cnext_, pf_,
        H_elem_, Hbar_, P_edge_;
    DeviceBuffer<Scalars<T>, Dev> sc_;
    DeviceBuffer<Pose, Dev> pose0_, pose1_;
    DeviceBuffer<index_t, Dev> ctool_, closed_, gtool_;
    DeviceBuffer<double, Dev> sb_, stc_, str_, srec_w_, srec_p_, sforce_, erec_w_, erec_p_, d_soft_mu_, sx_,
        slane_d2_, slane_w_;
    DeviceBuffer<int, Dev> slane_f_;
    DeviceBuffer<index_t, Dev> shead_, scursor_, sbucket_, scell_, scand_, snear_, srec_, sactive_, stouched_,
        erec_, eactive_;
    DeviceBuffer<std::int64_t, Dev> spart_, sshare_, sacc_, spair_;
    DeviceBuffer<MaterialParams<T>, Dev> d_mats_;
    DeviceBuffer<T, Dev> d_mem_geom_;  // the membranes' values, their moduli scaled (scale_materials)
    DeviceBuffer<T, Dev> d_mem_bend_;  // the membranes' bending values, their moduli scaled
    DeviceBuffer<T, Dev> mem_f_;       // the membranes' slot forces [N] (membrane_corner_forces)
    double material_scale_ = 1.0;
    DeviceBuffer<Prony<T>, Dev> d_prony_;
    DeviceBuffer<T, Dev> anp_gamma_;
    DeviceView<T> v_{};
    Phase phase_;
    const State<T>* resident_ = nullptr;  // the state whose values the device holds
    std::uint64_t resident_version_ = 0;
    long history_rows_ = 0;  // rows of the last run's tool history
};

}  // namespace pliant

#include "engine_steps.hpp"
#include "engine_soft.hpp"
#include "engine_calls.hpp"
