// pliant — CPU backend implementation (see cpu_solver.hpp).
#include "cpu_solver.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>

namespace pliant {

int thread_limit() { return std::max(64, 4 * omp_get_num_procs()); }

template <class T>
CpuSolver<T>::CpuSolver(const Model<T>& model, int threads)
    : m_(model), threads_(threads > 0 ? threads : omp_get_max_threads()) {
    if (threads_ > thread_limit())
        throw std::invalid_argument("threads = " + std::to_string(threads_) + ": expected 1 to " +
                                    std::to_string(thread_limit()));
    const std::size_t S = static_cast<std::size_t>(m_.n_blocks) * kLanes;
    f_elem_.assign(12 * S, T(0));
    J_.assign(S, T(1));
    if (m_.anp) {
        elem_p_.assign(S, T(0));
        node_p_.assign(static_cast<std::size_t>(m_.n_pad), T(0));
    }
    scratch_.assign(3 * static_cast<std::size_t>(m_.n_pad), T(0));
    f_node_[0] = scratch_;
    f_node_[1] = scratch_;
    contact_force_.assign(3 * m_.contact_nodes.size(), 0.0);
    contact_tool_.assign(m_.contact_nodes.size(), -1);
    chunk_hist_.assign((m_.contact_nodes.size() / 512 + 1) * 6 * m_.tools.size(), 0.0);
}

// Contact kernel over the contact nodes in fixed chunks of kContactChunk nodes, each chunk
// summing its per-tool force and torque; the chunk sums are added in chunk order by one thread.
// Fixed chunks (not per-thread partials) keep the result independent of the thread count.
// Inside a parallel region; hist receives 6 values per tool. One barrier.
template <class T>
void CpuSolver<T>::contact_pass(const T* u_cur, T* u_next, double t0, double t1, double g1,
                                double* hist) {
    constexpr index_t kContactChunk = 512;
    const int nt = static_cast<int>(m_.tools.size());
    Pose p0[8], p1[8];  // every thread evaluates the (few) poses itself: no barrier
    std::vector<Pose> q0, q1;
    Pose* P0 = p0;
    Pose* P1 = p1;
    if (nt > 8) {
        q0.resize(nt);
        q1.resize(nt);
        P0 = q0.data();
        P1 = q1.data();
    }
    for (int k = 0; k < nt; ++k) {
        P0[k] = tool_pose(m_.tools[k], t0, m_.tool_keys.data());
        P1[k] = tool_pose(m_.tools[k], t1, m_.tool_keys.data());
    }
    const index_t nc = static_cast<index_t>(m_.contact_nodes.size());
    const index_t chunks = (nc + kContactChunk - 1) / kContactChunk;
    const index_t P = m_.n_pad;
    const T* mass = relaxing_ ? m_.relax_mass.data() : m_.mass.data();
#pragma omp for schedule(static)
    for (index_t c = 0; c < chunks; ++c) {
        double* h = &chunk_hist_[static_cast<std::size_t>(c) * 6 * nt];
        for (int k = 0; k < 6 * nt; ++k) h[k] = 0.0;
        const index_t end = std::min(nc, (c + 1) * kContactChunk);
        for (index_t i = c * kContactChunk; i < end; ++i) {
            contact_node(i, m_.contact_nodes.data(), m_.contact_bits.data(), m_.X.data(), mass, u_cur, P,
                         m_.tools.data(), nt, P0, P1, m_.tool_grid.data(), g1, u_next,
                         contact_force_.data(), contact_tool_.data());
            add_tool_reaction(i, m_.contact_nodes.data(), m_.X.data(), u_next, P, P1,
                              contact_force_.data(), contact_tool_.data(), h);
        }
    }
#pragma omp single nowait
    {
        for (int k = 0; k < 6 * nt; ++k) hist[k] = 0.0;
        for (index_t c = 0; c < chunks; ++c)
            for (int k = 0; k < 6 * nt; ++k) hist[k] += chunk_hist_[static_cast<std::size_t>(c) * 6 * nt + k];
    }
}

// Kernel 1 over all blocks; called inside a parallel region (implicit barrier at the end).
template <class T>
void CpuSolver<T>::element_pass(const T* __restrict u, T* q, double dt, int visco_mode) {
    const ElementData<T> el = m_.elements();
    T* __restrict f = f_elem_.data();
    T* __restrict J = J_.data();
    const index_t P = m_.n_pad;
    const int W = 6 * m_.visco_terms;  // viscoelastic state width per slot
#pragma omp for schedule(static)
    for (index_t b = 0; b < m_.n_blocks; ++b) {
        const Group<T>& g = m_.groups[m_.block_group[b]];
        with_material(g.material, [&](const auto& mat) {
            using M = std::decay_t<decltype(mat)>;
            if constexpr (M::decoupled) {
                if (g.visco.terms() > 0) {
                    for (int l = 0; l < kLanes; ++l)
                        element_forces(b, l,
                                       ViscoMaterial<M, T>{mat, g.visco, T(dt), q + aosoa(b, l, 0, W),
                                                           kLanes, visco_mode},
                                       el, u, P, f, J);
                    return;
                }
            }
#pragma omp simd
            for (int l = 0; l < kLanes; ++l) element_forces(b, l, mat, el, u, P, f, J);
        });
    }
}

// T4ANP passes 1 and 2: V0 p(J) per element slot into ep, then the nodes' volume averages into
// np; inside a parallel region (two implicit barriers).
template <class T>
void CpuSolver<T>::anp_nodal_pressures(const T* __restrict u, T* ep, T* np) const {
    const ElementData<T> el = m_.elements();
    const index_t P = m_.n_pad;
#pragma omp for schedule(static)
    for (index_t b = 0; b < m_.n_blocks; ++b) {
        with_material(m_.groups[m_.block_group[b]].material, [&](const auto& mat) {
            if constexpr (std::decay_t<decltype(mat)>::decoupled) {
#pragma omp simd
                for (int l = 0; l < kLanes; ++l) element_pressure(b, l, mat, el, u, P, ep);
            }
        });
    }
#pragma omp for schedule(static)
    for (index_t n = 0; n < m_.n_nodes; ++n)
        np[n] = nodal_pressure(n, m_.inc_offsets.data(), m_.inc_index.data(), ep,
                               m_.node_volume.data());
}

// Kernel 1, or with T4ANP its three passes (element pressures, nodal averages, forces); inside a
// parallel region, each pass ending with the implicit barrier of its loop.
template <class T>
void CpuSolver<T>::forces_pass(const T* __restrict u, T* q, double dt, int visco_mode) {
    if (!m_.anp) {
        element_pass(u, q, dt, visco_mode);
        return;
    }
    const ElementData<T> el = m_.elements();
    const index_t P = m_.n_pad;
    T* __restrict np = node_p_.data();
    T* __restrict f = f_elem_.data();
    T* __restrict J = J_.data();
    anp_nodal_pressures(u, elem_p_.data(), np);
#pragma omp for schedule(static)
    for (index_t b = 0; b < m_.n_blocks; ++b) {
        with_material(m_.groups[m_.block_group[b]].material, [&](const auto& mat) {
            if constexpr (std::decay_t<decltype(mat)>::decoupled) {
#pragma omp simd
                for (int l = 0; l < kLanes; ++l) element_forces_anp(b, l, mat, el, u, P, np, f, J);
            }
        });
    }
}

// Kernel 2 over all nodes, then the kinematic constraints; inside a parallel region.
template <class T>
void CpuSolver<T>::node_pass(const Buffers& bu, const T* pattern_factors, const T* cons_factors,
                             const Integrator<T>& it, T* f_node) {
    const NodeData<T> nd = m_.nodes(relaxing_);
    const T* f = f_elem_.data();
    const index_t P = m_.n_pad;
    const index_t* co = m_.cons_offsets.data();
    // A node's constraints are applied right after its update, by the same thread: one barrier.
#pragma omp for schedule(static)
    for (index_t n = 0; n < m_.n_nodes; ++n) {
        node_update(n, nd, f, pattern_factors, it, bu.cur, bu.prev, P, bu.next, f_node);
        for (index_t i = co[n]; i < co[n + 1]; ++i)
            apply_constraint(i, m_.cons_dof.data(), m_.cons_value.data(), m_.cons_curve.data(),
                             cons_factors, bu.next);
    }
}

template <class T>
bool CpuSolver<T>::check(const T* u, double t, double blowup, RunReport& rep) const {
    const std::size_t S = J_.size();
    for (std::size_t s = 0; s < S; ++s) {
        const index_t e = m_.elem_id[s];
        if (e < 0 || J_[s] > T(0)) continue;
        rep.status = 2;  // an element: J ≤ 0, or NaN (as the CUDA check reports it)
        rep.where = e;
        rep.value = J_[s];
        rep.t = t;
        return false;
    }
    const index_t P = m_.n_pad;
    for (index_t n = 0; n < m_.n_nodes; ++n) {
        for (int d = 0; d < 3; ++d) {
            const double v = u[d * P + n];
            if (std::isfinite(v) && std::abs(v) <= blowup) continue;
            rep.status = std::isfinite(v) ? 3 : 1;
            rep.where = n;
            rep.value = v;
            rep.t = t;
            return false;
        }
    }
    return true;
}

template <class T>
RunReport CpuSolver<T>::step(const State<T>& in, State<T>& out, double dt, double alpha) {
    State<T> tmp = in;
    keep_velocity(tmp, dt);
    RunReport rep = run(tmp, 1, dt, alpha, 1, INFINITY);
    out = std::move(tmp);
    return rep;
}

template <class T>
RunReport CpuSolver<T>::run(State<T>& s, long n, double dt, double alpha, int check_every,
                            double blowup) {
    keep_velocity(s, dt);
    std::vector<T>* v[3] = {&s.u_prev, &s.u, &scratch_};
    RunReport rep;
    const Integrator<T> it = central_difference<T>(dt, alpha);
    const std::size_t nc = m_.curves.size(), np = m_.pattern_curve.size();
    const double t0 = s.t;
    long done = 0;
    bool ok = true;
    const std::size_t nt = m_.tools.size();
    tool_history_.assign(static_cast<std::size_t>(n) * 6 * nt, 0.0);
#pragma omp parallel num_threads(threads_)
    {
        std::vector<T> cnow(nc), cnext(nc), pf(np + 1);
        int ip = 0, ic = 1, in = 2;
        for (long k = 0; k < n; ++k) {
            const double t = t0 + k * dt;
            m_.curve_factors(t, cnow.data());
            m_.curve_factors(t + dt, cnext.data());
            for (std::size_t p = 0; p < np; ++p) pf[p] = cnow[m_.pattern_curve[p]];
            const bool master = omp_get_thread_num() == 0;
            const double w0 = master ? omp_get_wtime() : 0.0;
            forces_pass(v[ic]->data(), s.q.data(), dt, 0);
            const double w1 = master ? omp_get_wtime() : 0.0;
            node_pass({v[ip]->data(), v[ic]->data(), v[in]->data()}, pf.data(), cnext.data(), it,
                      nullptr);
            const double w2 = master ? omp_get_wtime() : 0.0;
            if (nt) contact_pass(v[ic]->data(), v[in]->data(), t, t + dt, double(it.g1),
                                 tool_history_.data() + static_cast<std::size_t>(k) * 6 * nt);
            if (master) {
                rep.elem_seconds += w1 - w0;
                rep.node_seconds += w2 - w1;
                rep.contact_seconds += omp_get_wtime() - w2;
            }
            ip = std::exchange(ic, std::exchange(in, ip));
            if ((k + 1) % check_every == 0 || k + 1 == n) {
#pragma omp single
                {
                    // J_ belongs to u at t (the step's input), u at t + Δt is now current.
                    done = k + 1;
                    ok = check(v[ip]->data(), t, blowup, rep) &&
                         check(v[ic]->data(), t + dt, blowup, rep);
                }
                if (!ok) break;
            }
        }
#pragma omp single
        {
            std::vector<T> a = std::move(*v[ip]), b = std::move(*v[ic]), c = std::move(*v[in]);
            s.u_prev = std::move(a);
            s.u = std::move(b);
            scratch_ = std::move(c);
        }
    }
    s.t = t0 + done * dt;
    s.dt = dt;
    s.step += done;
    rep.steps = done;
    if (rep.status == 0) rep.t = s.t;
    return rep;
}

template <class T>
typename CpuSolver<T>::RelaxMeasure CpuSolver<T>::relax_measure(const T* u_cur, const T* u_prev,
                                                                const T* f_cur, const T* f_prev,
                                                                const T* pattern_factors) const {
    const index_t P = m_.n_pad;
    const std::size_t N3 = 3 * static_cast<std::size_t>(P);
    const T* lp = m_.load_patterns.data();
    double res = 0.0, scale = 0.0, num = 0.0, den = 0.0;
    // Follower pressure at the current displacements: an external load too.
    std::vector<T> rpress(m_.pface_index.empty() ? 0 : N3, T(0));
    if (!rpress.empty()) {
        const NodeData<T> nd = m_.nodes(true);
        for (index_t n = 0; n < m_.n_nodes; ++n) {
            T q[3];
            pressure_force(n, nd, pattern_factors, u_cur, P, q);
            for (int d = 0; d < 3; ++d) rpress[d * P + n] = q[d];
        }
    }
    // Contact forces from the rigid tools are external loads at equilibrium.
    std::vector<double> fcon(m_.tools.empty() ? 0 : N3, 0.0);
    for (std::size_t c = 0; c < fcon.size() / N3 * contact_tool_.size(); ++c)
        if (contact_tool_[c] >= 0)
            for (int d = 0; d < 3; ++d)
                fcon[d * P + m_.contact_nodes[c]] += contact_force_[3 * c + d];
    for (std::size_t i = 0; i < N3; ++i) {
        double r = (fcon.empty() ? 0.0 : fcon[i]) + (rpress.empty() ? 0.0 : rpress[i]);
        for (int p = 0; p < m_.n_load_patterns; ++p) r += double(pattern_factors[p]) * lp[p * N3 + i];
        const double fm = m_.free_mask[i];
        res += fm * (r - f_cur[i]) * (r - f_cur[i]);
        scale += r * r + (1.0 - fm) * double(f_cur[i]) * f_cur[i];
        const double du = double(u_cur[i]) - u_prev[i];
        num += fm * du * (double(f_cur[i]) - f_prev[i]);
        den += fm * double(m_.relax_mass[i % P]) * du * du;
    }
    RelaxMeasure out;
    out.residual = scale > 0.0 ? std::sqrt(res / scale) : 0.0;
    if (den > 0.0) out.alpha = 2.0 * std::sqrt(std::max(num / den, 0.0));
    return out;
}

template <class T>
RunReport CpuSolver<T>::relax(State<T>& s, double t_eval, double dt, double tol, long max_steps,
                              int check_every, double blowup) {
    s.u_prev = s.u;  // start at rest
    relaxing_ = true;  // fictitious masses (Model::relax_mass) in kernel 2, contact and damping
    std::vector<T>* v[3] = {&s.u_prev, &s.u, &scratch_};
    RunReport rep;
    const std::size_t nc = m_.curves.size(), np = m_.pattern_curve.size();
    std::vector<T> cf(nc), pf(np + 1);
    m_.curve_factors(t_eval, cf.data());
    for (std::size_t p = 0; p < np; ++p) pf[p] = cf[m_.pattern_curve[p]];
    double alpha = 0.0;
    long done = 0;
    bool stop = false;
    tool_history_.assign(6 * m_.tools.size(), 0.0);  // relax keeps the last step's forces
    // Stall: the best residual has not improved by 1 % over the last 1,000 checks (round-off floor).
    double best = INFINITY;
    long best_check = 0, checks = 0;
#pragma omp parallel num_threads(threads_)
    {
        int ip = 0, ic = 1, in = 2, fc = 0;
        for (long k = 0; k < max_steps && !stop; ++k) {
            const Integrator<T> it = central_difference<T>(dt, alpha);
            forces_pass(v[ic]->data(), s.q.data(), dt, 2);
            node_pass({v[ip]->data(), v[ic]->data(), v[in]->data()}, pf.data(), cf.data(), it,
                      f_node_[fc].data());
            if (!m_.tools.empty())
                contact_pass(v[ic]->data(), v[in]->data(), t_eval, t_eval, double(it.g1),
                             tool_history_.data());
            // f_node_[fc] = f(u_cur), f_node_[1 − fc] = f(u_prev)
            if ((k + 1) % check_every == 0 && k > 0) {
#pragma omp single
                {
                    done = k + 1;
                    const T* uc = v[ic]->data();
                    const RelaxMeasure rm = relax_measure(uc, v[ip]->data(), f_node_[fc].data(),
                                                          f_node_[1 - fc].data(), pf.data());
                    rep.residual = rm.residual;
                    if (rm.alpha >= 0.0) alpha = rm.alpha;
                    const bool ok = check(uc, t_eval, blowup, rep);
                    ++checks;
                    if (rep.residual < 0.99 * best) {
                        best = rep.residual;
                        best_check = checks;
                    }
                    stop = !ok || rep.residual < tol || checks - best_check > 1000;
                }
            }
            ip = std::exchange(ic, std::exchange(in, ip));
            fc = 1 - fc;
        }
#pragma omp single
        {
            // After the loop, v[ic] holds the newest displacements.
            std::vector<T> a = std::move(*v[ip]), b = std::move(*v[ic]), c = std::move(*v[in]);
            s.u_prev = std::move(a);
            s.u = std::move(b);
            scratch_ = std::move(c);
            if (!stop) done = max_steps;
        }
    }
    relaxing_ = false;
    if (m_.visco_terms > 0) {  // the viscous state of the equilibrium: fully relaxed
#pragma omp parallel num_threads(threads_)
        forces_pass(s.u.data(), s.q.data(), dt, 3);
    }
    s.u_prev = s.u;  // equilibrium: at rest
    s.t = t_eval;
    s.dt = dt;
    rep.steps = done;
    rep.damping = alpha;
    if (rep.status == 0) rep.t = t_eval;
    return rep;
}

template <class T>
void CpuSolver<T>::measures(const State<T>& s, T* J_out, T* W_out, T* S_out, T* sigma_out,
                            T* E_out) const {
    const ElementData<T> el = m_.elements();
    const index_t P = m_.n_pad;
    const T* u = s.u.data();
    // T4ANP: the stresses the forces see, with the averaged pressure (passes 1 and 2 first).
    std::vector<T> ep(m_.anp ? J_.size() : 0), np(m_.anp ? P : 0);
    if (m_.anp) {
#pragma omp parallel num_threads(threads_)
        anp_nodal_pressures(u, ep.data(), np.data());
    }
#pragma omp parallel for schedule(static) num_threads(threads_)
    for (index_t b = 0; b < m_.n_blocks; ++b) {
        with_material(m_.groups[m_.block_group[b]].material, [&](const auto& mat) {
            for (int l = 0; l < kLanes; ++l) {
                const index_t e = m_.elem_id[b * kLanes + l];
                if (e < 0) continue;
                ElementMeasures<T> q;
                using M = std::decay_t<decltype(mat)>;
                const Group<T>& g = m_.groups[m_.block_group[b]];
                if constexpr (M::decoupled) {
                    if (g.visco.terms() > 0) {
                        T* qs = const_cast<T*>(s.q.data()) + aosoa(b, l, 0, 6 * m_.visco_terms);
                        q = element_measures(b, l, ViscoMaterial<M, T>{mat, g.visco, T(s.dt), qs,
                                                                       kLanes, 1}, el, u, P);
                    } else if (m_.anp) {
                        T p = T(0);
                        for (int a = 0; a < 4; ++a) p += np[el.nodes[aosoa(b, l, a, 4)]];
                        q = element_measures(b, l, AveragedPressure<M, T>{mat, p / T(4)}, el, u, P);
                    } else {
                        q = element_measures(b, l, mat, el, u, P);
                    }
                } else {
                    q = element_measures(b, l, mat, el, u, P);
                }
                J_out[e] = q.J;
                W_out[e] = q.energy;
                const Sym3<T>* src[3] = {&q.S, &q.sigma, &q.E};
                T* dst[3] = {S_out, sigma_out, E_out};
                for (int k = 0; k < 3; ++k) {
                    const T vals[6] = {src[k]->xx, src[k]->yy, src[k]->zz,
                                       src[k]->xy, src[k]->yz, src[k]->xz};
                    for (int c = 0; c < 6; ++c) dst[k][6 * e + c] = vals[c];
                }
            }
        });
    }
}

template <class T>
std::vector<T> CpuSolver<T>::internal_forces(const State<T>& s) {
    std::vector<T> f(3 * static_cast<std::size_t>(m_.n_pad), T(0));
    const NodeData<T> nd = m_.nodes();
    const Integrator<T> it{T(0), T(0)};
    const std::vector<T> zeros(m_.pattern_curve.size() + 1, T(0));
#pragma omp parallel num_threads(threads_)
    {
        forces_pass(s.u.data(), const_cast<T*>(s.q.data()), s.dt, 1);
#pragma omp for schedule(static)
        for (index_t n = 0; n < m_.n_nodes; ++n)
            node_update(n, nd, f_elem_.data(), zeros.data(), it, s.u.data(), s.u.data(),
                        m_.n_pad, scratch_.data(), f.data());
    }
    return f;
}

template class CpuSolver<float>;
template class CpuSolver<double>;

}  // namespace pliant
