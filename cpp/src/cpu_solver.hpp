// pliant — CPU backend: launches the kernels of tled.hpp with OpenMP threads across element
// blocks and SIMD across the lanes of a block. Every thread count gives the same bits: each
// element and node is computed by the same code whatever thread runs it, and sums run in a fixed order.
#pragma once

#include <vector>

#include "model.hpp"

namespace pliant {
// Most CPU threads a solver accepts: 4 per processor, at least 64.
int thread_limit();
}  // namespace pliant

namespace pliant {

/// Outcome of a run: status 0 ok, 1 non-finite value, 2 inverted element (J ≤ 0), 3 blow-up
/// (|u| above the limit). `where` is the builder's element (status 2) or node (1, 3) index,
/// `value` the offending quantity, `t` the time [s] at which it was found.
struct RunReport {
    long steps = 0;
    double t = 0.0;
    int status = 0;
    index_t where = -1;
    double value = 0.0;
    double residual = 0.0;  // relax: relative out-of-balance force at the end
    double damping = 0.0;   // relax: last adaptive damping coefficient α [1/s]
    double elem_seconds = 0.0, node_seconds = 0.0;  // run: wall time in kernel 1 and kernel 2
    double contact_seconds = 0.0;                   // run: wall time in the contact kernel
};

template <class T>
class CpuSolver {
public:
    // threads: 1 .. thread_limit(), or <= 0 for OpenMP's default. More threads than that cannot
    // help and, far beyond, make OpenMP fail to create them (a crash): refused with an exception.
    CpuSolver(const Model<T>& model, int threads);

    /// One central-difference step from `in` to `out` (distinct states), Δt [s], damping α [1/s].
    RunReport step(const State<T>& in, State<T>& out, double dt, double alpha);
    /// n steps in place, checking stability every `check_every` steps and at the end.
    RunReport run(State<T>& s, long n, double dt, double alpha, int check_every, double blowup);
    /// Dynamic relaxation to the static equilibrium of the loads at time t_eval [s], with adaptive
    /// mass-proportional damping (Joldes, Wittek & Miller 2009, CMAME 198:3313, §3).
    RunReport relax(State<T>& s, double t_eval, double dt, double tol, long max_steps,
                    int check_every, double blowup);
    /// Per element (builder order): J, W [Pa], S, σ [Pa] and E as (xx, yy, zz, xy, yz, xz).
    void measures(const State<T>& s, T* J_out, T* W_out, T* S_out, T* sigma_out, T* E_out) const;
    /// Internal nodal forces f(u) [N], SoA (3, P), of the state's current displacements.
    std::vector<T> internal_forces(const State<T>& s);

    int threads() const { return threads_; }
    /// Per step of the last run/relax: for each tool, the force [N] and torque [N·m] it received
    /// (6 values, torque about the tool's position), shape (steps, tools, 6).
    const std::vector<double>& tool_history() const { return tool_history_; }
    /// Per contact node of the last step: tool index (−1: none) and contact force on the node [N].
    const std::vector<index_t>& contact_tool() const { return contact_tool_; }
    const std::vector<double>& contact_force() const { return contact_force_; }

private:
    struct Buffers {
        const T* prev;
        const T* cur;
        T* next;
    };
    // Kernel 1; q: the state's viscoelastic values, visco_mode: 0 advance by dt, 1 stored, 2 relaxed.
    void element_pass(const T* u, T* q, double dt, int visco_mode);
    void forces_pass(const T* u, T* q, double dt, int visco_mode);  // or the three T4ANP passes
    void anp_nodal_pressures(const T* u, T* ep, T* np) const;       // T4ANP passes 1 and 2
    void node_pass(const Buffers& b, const T* pattern_factors, const T* cons_factors,
                   const Integrator<T>& it, T* f_node);
    bool check(const T* u_cur, double t, double blowup, RunReport& rep) const;
    /// Dynamic relaxation's measures at a check: the relative out-of-balance force on the free DOFs
    /// (external loads: patterns, follower pressure and contact, against the internal forces) and
    /// the adaptive damping α = 2 √(Rayleigh quotient of the stiffness change) (Joldes, Wittek &
    /// Miller 2009, CMAME 198:3313: the minimum-eigenvalue estimate of its adaptive damping), from u
    /// and f at this step and the one before.
    struct RelaxMeasure {
        double residual = 0.0;
        double alpha = -1.0;  // < 0: no estimate (no motion)
    };
    RelaxMeasure relax_measure(const T* u_cur, const T* u_prev, const T* f_cur, const T* f_prev,
                               const T* pattern_factors) const;
    void contact_pass(const T* u_cur, T* u_next, double t0, double t1, double g1, double* hist);

    const Model<T>& m_;
    int threads_;
    bool relaxing_ = false;  // inside relax(): the dynamic-relaxation masses replace the physical
    std::vector<T> f_elem_, J_, scratch_, f_node_[2], elem_p_, node_p_;
    std::vector<double> contact_force_, tool_history_, chunk_hist_;
    std::vector<index_t> contact_tool_;
};

}  // namespace pliant
