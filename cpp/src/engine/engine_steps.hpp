// pliant — the engine's kernels and the step they make (included by engine.hpp). Each function
// launches one kernel (or one per material group) through the device; the kernel bodies call the
// physics of tled.hpp and contact.hpp.
#pragma once

namespace pliant {

/// One step of central differences (relaxing: the dynamic-relaxation masses, loads held at t0).
/// time_dt: how far the load time advances per step (Δt in a run, 0 in a relaxation).
template <class T, class Dev>
void Engine<T, Dev>::step_once(const Phase& ph, double dt, double time_dt, bool relaxing, T* f_node_out,
                               RunReport& rep) {
    step_scalars(time_dt, relaxing);
    const double w0 = dev_.wtime();
    forces(v_.u[ph.cur], relaxing ? ViscoMode::Relaxed : ViscoMode::Advance, dt);
    if (m_.stiffness_damping > 0.0 && !relaxing) damping(ph, dt);
    const double w1 = dev_.wtime();
    node_pass(ph, relaxing, f_node_out);
    const double w2 = dev_.wtime();
    if (v_.n_tools) contact_pass(ph, relaxing);
    if (v_.soft.n_nodes) soft_pass(ph, relaxing);
    if (dev_.lead()) {
        rep.elem_seconds += w1 - w0;
        rep.node_seconds += w2 - w1;
        rep.contact_seconds += dev_.wtime() - w2;
    }
}

/// The load-pattern factors at t [s] (load patterns and pressure slots) into v.pf; one thread.
template <class T>
PLIANT_HD void pattern_factors_at(const DeviceView<T>& v, double t) {
    for (int p = 0; p < v.n_factors; ++p)
        v.pf[p] = T(curve_value(v.curves[v.pattern_curve[p]], t, v.tt, v.tv));
}

/// Load-curve factors at t (load patterns, pressure) and t⁺ (prescribed displacements), tool poses
/// at t and t⁺: t = t0 + (base + step) · time_dt and t⁺ the next step's t, on the run clock
/// (State::t_epoch, clock_time); then the step counter advances.
template <class T, class Dev>
void Engine<T, Dev>::step_scalars(double time_dt, bool fixed_row) {
    const DeviceView<T> v = v_;
    dev_.serial([=] PLIANT_KERNEL() {
        Scalars<T>& s = *v.sc;
        const double t = clock_time(s.t0, s.base + s.step, time_dt);
        const double t_next = clock_time(s.t0, s.base + s.step + 1, time_dt);
        for (int c = 0; c < v.n_curves; ++c) v.cnext[c] = T(curve_value(v.curves[c], t_next, v.tt, v.tv));
        pattern_factors_at(v, t);
        for (int k = 0; k < v.n_tools; ++k) {
            v.pose0[k] = tool_pose(v.tools[k], t, v.keys);
            v.pose1[k] = tool_pose(v.tools[k], t_next, v.keys);
            v.closed[k] = (tool_closed(v.tools[k], t, v.grips) ? kGripClosedBefore : 0) |
                          (tool_closed(v.tools[k], t_next, v.grips) ? kGripClosedAfter : 0);
        }
        s.row = fixed_row ? 0 : s.step;
        s.step += 1;
    });
}

/// Calls visit.template operator()<M, Variant>(span) for every span of groups: the one place where
/// material kinds, viscoelasticity and T4ANP choose the element function.
template <class T, class Dev>
template <class Visitor>
void Engine<T, Dev>::dispatch(Visitor&& visit) {
    for (const Span& sp : spans_) {
        const Group<T>& g = groups_[sp.group];
        with_material(g.material, [&](const auto& mat) {
            using M = std::decay_t<decltype(mat)>;
            if constexpr (M::decoupled) {
                if (g.visco.terms() > 0) return visit.template operator()<M, Variant::Visco>(sp);
                if (m_.anp) return visit.template operator()<M, Variant::Anp>(sp);
            }
            return visit.template operator()<M, Variant::Plain>(sp);
        });
    }
}

/// T4ANP's pass (1) of span sp; kKeep: it also keeps the displacement gradients for pass (3).
template <class T, class Dev>
template <class M, Variant V, bool kKeep>
void Engine<T, Dev>::launch_pressure(const Span& sp, const T* u) {
    if constexpr (V == Variant::Anp) {
        const DeviceView<T> v = v_;
        dev_.blocks(sp.block_begin, sp.block_end, [=] PLIANT_KERNEL(index_t b, int l) {
            const M mat = make_material<M>(v.mats[v.block_group[b]]);
            element_pressure<kKeep>(b, l, mat, v.el, u, v.P, v.elem_p, v.H_anp);
        });
    }
}

/// Calls f.template operator()<kMode>() with the ViscoMode a viscoelastic kernel fixes at compile
/// time: in a time step (Advance) the mode, so that its loops carry one mode's arithmetic; -1 (the
/// mode decided at run time) for the rest (outputs, relaxation).
template <class T, class Dev>
template <class F>
void Engine<T, Dev>::with_visco_mode(ViscoMode visco_mode, F&& f) {
    if (visco_mode == ViscoMode::Advance)
        return f.template operator()<static_cast<int>(ViscoMode::Advance)>();
    f.template operator()<-1>();
}

/// The middle phases of a viscoelastic launch (Dev::blocks_phased, Phases): the Prony terms t0 ..
/// t0 + K − 1 (visco_terms) of the series of block b's group, group[b · group_stride] (per element
/// block, or per edge block: stride kLanes), and slot (b, l)'s state in q (AoSoA, visco_w values a
/// slot). A named class rather than a lambda: its phase's term count K is a template parameter.
template <class T, class S, int kMode>
struct ViscoTermsPhase {
    const Prony<T>* prony;
    const index_t* group;
    index_t group_stride;
    T* q;
    int visco_w;
    T dt;
    ViscoMode mode;
    template <int K>
    PLIANT_HD PronyChunk<K, T> uniform(index_t b, int t0) const {
        return prony_chunk<K>(prony[group[b * group_stride]], t0, dt);
    }
    template <int K>
    PLIANT_HD void operator()(const PronyChunk<K, T>& ch, index_t b, int l, S s) const {
        visco_terms<kMode, K>(ch, q + aosoa(b, l, 0, visco_w), kLanes, mode, s);
    }
};

/// Viscoelastic element forces (visco_forces_begin, tled.hpp): the element, the span's Prony terms
/// (isochoric, then volumetric) and the forces as phases of one launch (Dev::blocks_phased), so that
/// on the CPU every term count vectorizes; kMode >= 0: the ViscoMode fixed at compile time.
template <class T, class Dev>
template <class M, int kMode>
void Engine<T, Dev>::launch_visco_forces(const Span& sp, const T* u, ViscoMode visco_mode, double dt) {
    using S = typename Dev::template Scratch<T>;
    const DeviceView<T> v = v_;
    dev_.template blocks_phased<T, kViscoScratch>(
        sp.block_begin, sp.block_end, groups_[sp.group].visco.phases(),  // the same for the span's groups
        [=] PLIANT_KERNEL(index_t b, int l, S s) {
            visco_forces_begin(b, l, make_material<M>(v.mats[v.block_group[b]]), v.el, u, v.P, v.J, s);
        },
        ViscoTermsPhase<T, S, kMode>{v.prony, v.block_group, 1, v.q, v.visco_w, T(dt), visco_mode},
        [=] PLIANT_KERNEL(index_t b, int l, S s) { visco_forces_end(b, l, v.el, v.f_elem, s); });
}

template <class T, class Dev>
template <class M, Variant V>
void Engine<T, Dev>::launch_forces(const Span& sp, const T* u, ViscoMode visco_mode, double dt) {
    if (v_.smoothed) {  // pass 3 of the edge-smoothed strain (smoothing.hpp; viscosity is in the edges)
        const DeviceView<T> v = v_;
        dev_.blocks(sp.block_begin, sp.block_end, [=] PLIANT_KERNEL(index_t b, int l) {
            const M mat = make_material<M>(v.mats[v.block_group[b]]);
            element_forces_smoothed<V == Variant::Anp>(b, l, mat, v.el, v.ed, v.P_edge, v.H_elem, v.node_p,
                                                       v.anp_gamma[v.block_group[b]], v.f_elem, v.J);
        });
    } else if constexpr (V == Variant::Visco) {  // the time step's mode compiled on its own; terms as phases
        with_visco_mode(visco_mode,
                        [&]<int kMode>() { launch_visco_forces<M, kMode>(sp, u, visco_mode, dt); });
    } else if (Dev::kStreams && V == Variant::Plain && v_.stream) {
        if constexpr (Dev::kStreams && V == Variant::Plain) {  // a model beyond the caches (CPU)
            const DeviceView<T> v = v_;
            dev_.template blocks_streamed<12, 1>(sp.block_begin, sp.block_end, v.f_elem, v.J,
                                                 [=] PLIANT_KERNEL(index_t b, int l, T* f_out, T* J_out) {
                                                     const M mat = make_material<M>(v.mats[v.block_group[b]]);
                                                     element_forces_to(b, l, mat, v.el, u, v.P, 0, f_out,
                                                                       J_out);
                                                 });
        }
    } else {
        const DeviceView<T> v = v_;
        dev_.blocks(sp.block_begin, sp.block_end, [=] PLIANT_KERNEL(index_t b, int l) {
            (void)v, (void)u;  // captured before any `if constexpr` (nvcc)
            const M mat = make_material<M>(v.mats[v.block_group[b]]);
            if constexpr (V == Variant::Anp) {
                element_forces_anp<Dev::kKeepsAnpGradient>(b, l, mat, v.el, u, v.P, v.H_anp, v.node_p,
                                                           v.anp_gamma[v.block_group[b]], v.f_elem, v.J);
            } else {
                element_forces(b, l, mat, v.el, u, v.P, v.f_elem, v.J);
            }
        });
    }
}

/// Kernel 1 (element forces f_elem and J), or with T4ANP its three passes; visco_mode: what the
/// viscoelastic groups do with their Prony state (ViscoMode).
template <class T, class Dev>
void Engine<T, Dev>::forces(const T* u, ViscoMode visco_mode, double dt) {
    if (v_.smoothed) {
        edge_stresses(u, visco_mode, dt);  // with T4ANP, its passes (1) and (2) too
    } else if (m_.anp) {
        // Pass (3) reads pass (1)'s gradients where the device keeps them (Dev::kKeepsAnpGradient).
        if (Dev::kKeepsAnpGradient)
            dispatch([&]<class M, Variant V>(const Span& sp) { launch_pressure<M, V, true>(sp, u); });
        else
            dispatch([&]<class M, Variant V>(const Span& sp) { launch_pressure<M, V, false>(sp, u); });
        dev_.barrier();
        nodal_pressures();
    }
    dispatch([&]<class M, Variant V>(const Span& sp) { launch_forces<M, V>(sp, u, visco_mode, dt); });
    dev_.barrier();
}

/// T4ANP's pass (2): every node's averaged pressure from the elements' V0 p(J).
template <class T, class Dev>
void Engine<T, Dev>::nodal_pressures() {
    const DeviceView<T> v = v_;
    dev_.each(v.n_nodes, [=] PLIANT_KERNEL(index_t n) {
        v.node_p[n] = nodal_pressure(n, v.nodes.inc_offsets, v.inc_slot, v.elem_p, v.node_volume);
    });
}

/// Passes 1 and 2 of the edge-smoothed strain (smoothing.hpp): every element's displacement
/// gradient, every edge domain's mean gradient, then its stress per material group. With T4ANP
/// pass 1 also gives the elements' V0 p(J) (element_gradient_pressure: the displacements gathered
/// once), and the nodal pressures follow it.
template <class T, class Dev>
void Engine<T, Dev>::edge_stresses(const T* u, ViscoMode visco_mode, double dt) {
    const DeviceView<T> v = v_;
    dispatch([&]<class M, Variant V>(const Span& sp) { launch_gradient<M, V>(sp, u); });
    dev_.barrier();
    if (m_.anp) nodal_pressures();
    dev_.each(m_.n_edges, [=] PLIANT_KERNEL(index_t k) { edge_gradient(k, v.ed, v.H_elem, v.Hbar); });
    dispatch([&]<class M, Variant V>(const Span& sp) {
        if constexpr (V == Variant::Visco)
            with_visco_mode(visco_mode,
                            [&]<int kMode>() { launch_visco_edge_stress<M, kMode>(sp, visco_mode, dt); });
        else
            launch_edge_stress<M, V>(sp);
    });
    dev_.barrier();
}

/// Pass 1 of the edge-smoothed strain for span sp: the element gradients, and for T4ANP's groups
/// their V0 p(J) too (element_gradient_pressure).
template <class T, class Dev>
template <class M, Variant V>
void Engine<T, Dev>::launch_gradient(const Span& sp, const T* u) {
    const DeviceView<T> v = v_;
    if constexpr (V == Variant::Anp)
        dev_.blocks(sp.block_begin, sp.block_end, [=] PLIANT_KERNEL(index_t b, int l) {
            element_gradient_pressure(b, l, make_material<M>(v.mats[v.block_group[b]]), v.el, u, v.P,
                                      v.H_elem, v.elem_p);
        });
    else
        dev_.blocks(sp.block_begin, sp.block_end,
                    [=] PLIANT_KERNEL(index_t b, int l) { element_gradient(b, l, v.el, u, v.P, v.H_elem); });
}

/// Edge stresses of a span's edge blocks; under T4ANP the isochoric part only (p̄ = 0, γ = 0):
/// each element adds its volumetric part (SmoothedStress).
template <class T, class Dev>
template <class M, Variant V>
void Engine<T, Dev>::launch_edge_stress(const Span& sp) {
    const DeviceView<T> v = v_;
    dev_.blocks(sp.edge_begin / kLanes, sp.edge_end / kLanes, [=] PLIANT_KERNEL(index_t b, int l) {
        const M mat = make_material<M>(v.mats[v.edge_group[b * kLanes]]);
        if constexpr (V == Variant::Anp)
            edge_stress(b, l, AveragedPressure<M, T>{mat, T(0), T(0)}, v.Hbar, v.P_edge);
        else
            edge_stress(b, l, mat, v.Hbar, v.P_edge);
    });
}

/// Edge stresses of a viscoelastic span: its Prony state per edge (the state's slots are edge
/// slots), the terms as phases as in launch_visco_forces.
template <class T, class Dev>
template <class M, int kMode>
void Engine<T, Dev>::launch_visco_edge_stress(const Span& sp, ViscoMode visco_mode, double dt) {
    using S = typename Dev::template Scratch<T>;
    const DeviceView<T> v = v_;
    dev_.template blocks_phased<T, kViscoScratch>(
        sp.edge_begin / kLanes, sp.edge_end / kLanes, groups_[sp.group].visco.phases(),
        [=] PLIANT_KERNEL(index_t b, int l, S s) {
            visco_begin(make_material<M>(v.mats[v.edge_group[b * kLanes]]),
                        kinematics(edge_gradient_at(b, l, v.Hbar)), s);
        },
        ViscoTermsPhase<T, S, kMode>{v.prony, v.edge_group, kLanes, v.q, v.visco_w, T(dt), visco_mode},
        [=] PLIANT_KERNEL(index_t b, int l, S s) { store_edge_stress(b, l, visco_pk1<T>(s), v.P_edge); });
}

/// Stiffness-proportional damping (β [s]): each element's viscous forces from its half-step
/// velocity du/Δt, added to its element forces (tled.hpp: add_damping_forces).
template <class T, class Dev>
void Engine<T, Dev>::damping(const Phase& ph, double dt) {
    const T* u = v_.u[ph.cur];
    const T* du = v_.du[ph.cur];
    const T beta_over_dt = T(m_.stiffness_damping / dt);
    dispatch([&]<class M, Variant V>(const Span& sp) { launch_damping<M, V>(sp, u, du, beta_over_dt); });
    dev_.barrier();
}

template <class T, class Dev>
template <class M, Variant V>
void Engine<T, Dev>::launch_damping(const Span& sp, const T* u, const T* du, T beta_over_dt) {
    const DeviceView<T> v = v_;
    dev_.blocks(sp.block_begin, sp.block_end, [=] PLIANT_KERNEL(index_t b, int l) {
        const M mat = make_material<M>(v.mats[v.block_group[b]]);
        add_damping_forces(b, l, mat, v.el, u, du, v.P, beta_over_dt, v.f_elem);
    });
}

/// Kernel 2: per node, gather the element forces (and the membranes' corner forces, computed first
/// per membrane), central-difference update (u_next), then the node's kinematic constraints;
/// f_node_out (may be null) receives the internal forces.
template <class T, class Dev>
void Engine<T, Dev>::node_pass(const Phase& ph, bool relaxing, T* f_node_out) {
    const DeviceView<T> v = v_;
    const NodeData<T> nd = relaxing ? v.relax_nodes : v.nodes;
    const T* uc = v.u[ph.cur];
    const T* duc = v.du[ph.cur];
    T* un = v.u[ph.next];
    T* dun = v.du[ph.next];
    if (nd.mem.count)  // each membrane's corner forces, once (not once per corner)
        dev_.each(nd.mem.count, [=] PLIANT_KERNEL(index_t m) { membrane_corner_forces(m, nd.mem, uc, v.P); });
    dev_.each(v.n_nodes, [=] PLIANT_KERNEL(index_t n) {
        if (v.prefetch && n + kPrefetchAhead < v.n_nodes)
            prefetch_incidences(n + kPrefetchAhead, nd, v.f_elem);
        node_update(n, nd, v.f_elem, v.pf, v.sc->it, uc, duc, v.P, un, dun, f_node_out);
        for (index_t i = v.co[n]; i < v.co[n + 1]; ++i)
            apply_constraint(i, v.cdof, v.cval, v.ccurve, v.cnext, uc, un, dun);
    });
}

/// External loads: the load-pattern factors at t [s], then each node's applied_loads at u into
/// f_out [N] SoA (3, P).
template <class T, class Dev>
void Engine<T, Dev>::load_pass(double t, const T* u, T* f_out) {
    const DeviceView<T> v = v_;
    dev_.serial([=] PLIANT_KERNEL() { pattern_factors_at(v, t); });
    dev_.each(v.n_nodes, [=] PLIANT_KERNEL(index_t n) {
        T r[3];
        applied_loads(n, v.nodes, v.pf, u, v.P, r);
        for (int d = 0; d < 3; ++d) f_out[d * v.P + n] = r[d];
    });
}

/// Contact of the surface nodes with the rigid tools (and grasping), one thread per node; then
/// chunks of nodes (chunk_size) each sum their per-tool force and torque, node by node, and one
/// thread adds the chunks in order into the step's history row (the same bits for any thread count).
template <class T, class Dev>
void Engine<T, Dev>::contact_pass(const Phase& ph, bool relaxing) {
    const DeviceView<T> v = v_;
    const T* mass = relaxing ? v.relax_mass : v.mass;
    const T* uc = v.u[ph.cur];
    T* un = v.u[ph.next];
    T* dun = v.du[ph.next];
    dev_.each(v.n_contact, [=] PLIANT_KERNEL(index_t i) {
        contact_node(i, v.cnodes, v.cbits, v.cskin, v.X, mass, uc, v.P, v.tools, v.n_tools, v.pose0, v.pose1,
                     v.closed, v.grid, double(v.sc->it.g1), un, dun, v.cforce, v.ctool, v.gtool, v.gat);
    });
    dev_.each(v.chunks, [=] PLIANT_KERNEL(index_t c) {
        const int w = 6 * v.n_tools;
        double* h = v.chunk + static_cast<std::size_t>(c) * w;
        for (int k = 0; k < w; ++k) h[k] = 0.0;
        const index_t end = (c + 1) * v.contact_chunk < v.n_contact ? (c + 1) * v.contact_chunk : v.n_contact;
        for (index_t i = c * v.contact_chunk; i < end; ++i)
            add_tool_reaction(i, v.cnodes, v.X, un, v.P, v.pose1, v.cforce, v.ctool, h);
    });
    dev_.serial([=] PLIANT_KERNEL() {
        const int w = 6 * v.n_tools;
        double* row = v.hist + v.sc->row * v.hist_width;
        for (int k = 0; k < w; ++k) {
            double s = 0.0;
            for (index_t c = 0; c < v.chunks; ++c) s += v.chunk[static_cast<std::size_t>(c) * w + k];
            row[k] = s;
        }
    });
}

/// Engine::check's verdict on component d of node i: non-finite, beyond far [m], or (u_old given)
/// moved more than size [m] in the step; Ok otherwise.
template <class T>
PLIANT_HD RunStatus node_verdict(const T* u_new, const T* u_old, index_t P, index_t i, int d, double far,
                                 double size) {
    const double x = double(u_new[d * P + i]);
    if (!std::isfinite(x)) return RunStatus::NonFinite;
    if (std::fabs(x) > far) return RunStatus::BlowUp;
    if (u_old != nullptr && !(std::fabs(x - double(u_old[d * P + i])) <= size)) return RunStatus::Jump;
    return RunStatus::Ok;
}

/// Stability check of the last step: an element slot with J ≤ 0 or NaN (J of the step's input, at
/// t_elem), else a node (at t_node) whose new displacement is non-finite, beyond kBlowUpSizes ×
/// size [m] (the body's size: an energy blow-up), or, where u_old (the step's input) is given, that
/// moved more than size in the step (a jump): faster than size/Δt, far above every wave speed the
/// step resolves (Δt ≲ h/c, h ≪ size), the sawtooth of an unstable step, which may stay bounded (a
/// sheet's corner beating at 10 km/s within a metre of its place). The smallest such index, so the
/// verdict does not depend on the order of the search. Returns the device scalars as read back
/// (status 0: fine), so that callers need no second round trip.
template <class T, class Dev>
Scalars<T> Engine<T, Dev>::check(const T* u_new, const T* u_old, double t_elem, double t_node, double size,
                                 RunReport& rep) {
    const DeviceView<T> v = v_;
    const double far = kBlowUpSizes * size;
    dev_.serial([=] PLIANT_KERNEL() { v.sc->bad_slot = v.sc->bad_node = INT_MAX; });
    const index_t n = v.slots > v.n_nodes ? v.slots : v.n_nodes;
    dev_.each(n, [=] PLIANT_KERNEL(index_t i) {
        if (i < v.slots && v.elem_id[i] >= 0 && !(v.J[i] > T(0))) atomic_min(&v.sc->bad_slot, i);
        if (i < v.n_nodes)
            for (int d = 0; d < 3; ++d)
                if (node_verdict(u_new, u_old, v.P, i, d, far, size) != RunStatus::Ok)
                    atomic_min(&v.sc->bad_node, i);
    });
    dev_.serial([=] PLIANT_KERNEL() {
        Scalars<T>& s = *v.sc;
        s.status = 0;
        if (s.bad_slot != INT_MAX) {
            s.status = static_cast<int>(RunStatus::Inverted);
            s.where = v.elem_id[s.bad_slot];
            s.value = double(v.J[s.bad_slot]);
        } else if (s.bad_node != INT_MAX) {
            for (int d = 2; d >= 0; --d) {  // the first offending component
                const RunStatus r = node_verdict(u_new, u_old, v.P, s.bad_node, d, far, size);
                if (r == RunStatus::Ok) continue;
                const double x = double(u_new[d * v.P + s.bad_node]);
                s.status = static_cast<int>(r);
                s.value = r == RunStatus::Jump ? x - double(u_old[d * v.P + s.bad_node]) : x;
            }
            s.where = s.bad_node;
        }
    });
    const Scalars<T> s = dev_.read(v.sc);
    if (s.status != 0 && dev_.lead()) {
        rep.status = static_cast<RunStatus>(s.status);
        rep.where = s.where;
        rep.value = s.value;
        rep.t = rep.status == RunStatus::Inverted ? t_elem : t_node;
    }
    return s;
}

/// Dynamic relaxation's measures (Joldes, Wittek & Miller 2009, CMAME 198:3313, §3): the relative
/// out-of-balance force on the free DOFs (external loads: patterns, follower pressure and contact,
/// against the internal forces) and the adaptive damping α = 2 √λ, λ the estimate of the lowest
/// eigenvalue of M⁻¹K: the Rayleigh quotient of the stiffness change Δuᵀ Δf / Δuᵀ M Δu from u and
/// f at the step and the one before, over the free DOFs that no contact holds. Each quotient is an
/// upper bound on that eigenvalue, and the one step's increment that Joldes et al. take swings far
/// above it where contact corrects nodes (a liver pressed by a kidney: 700–9,600 s⁻¹ for α from one
/// check to the next; the relaxation stalled at a residual of 2e-3): with contact (tools or soft),
/// λ is the smallest quotient of the last one to two windows of kRelaxWindow steps, and a quotient
/// ≤ 0 (softening) leaves α as it was; without, λ is the step's quotient (≤ 0: α = 0), which
/// damps the runaway of a mechanism (a sheet that only bends) into a stall that names it, where
/// the smallest quotient, near 0, let it blow up. steps: the steps since the last measure. α sets
/// the integrator.
template <class T, class Dev>
void Engine<T, Dev>::relax_measure(const T* u_cur, const T* u_prev, const T* f_cur, const T* f_prev,
                                   double dt, long steps) {
    const DeviceView<T> v = v_;
    const bool contact = v.n_tools || v.soft.n_nodes;
    if (contact) {  // contact forces are external loads at equilibrium
        dev_.each(3 * v.P, [=] PLIANT_KERNEL(index_t i) { v.fcon[i] = 0.0; });
        dev_.each(v.n_contact, [=] PLIANT_KERNEL(index_t c) {
            if (v.ctool[c] < 0) return;
            for (int d = 0; d < 3; ++d) v.fcon[d * v.P + v.cnodes[c]] = v.cforce[3 * c + d];
        });
        dev_.each(v.soft.n_nodes, [=] PLIANT_KERNEL(index_t i) {  // after the tools: a node may have both
            for (int d = 0; d < 3; ++d) {  // on free DOFs: a held DOF's contact force is its support's
                const std::size_t k = static_cast<std::size_t>(d) * v.P + v.soft.node[i];
                v.fcon[k] += v.free_mask[k] * v.sforce[3 * i + d];
            }
        });
    }
    const index_t chunks = (v.n_nodes + kMeasureChunk - 1) / kMeasureChunk;
    dev_.each(chunks, [=] PLIANT_KERNEL(index_t c) {
        double sum[4] = {0.0, 0.0, 0.0, 0.0};  // residual², scale², Rayleigh numerator, denominator
        const index_t end = (c + 1) * kMeasureChunk < v.n_nodes ? (c + 1) * kMeasureChunk : v.n_nodes;
        for (index_t n = c * kMeasureChunk; n < end; ++n) {
            T q[3];
            pressure_force(n, v.relax_nodes, v.pf, u_cur, v.P, q);
            for (int d = 0; d < 3; ++d) {
                const std::size_t i = static_cast<std::size_t>(d) * v.P + n;
                double r = double(q[d]) + (contact ? v.fcon[i] : 0.0);
                for (int p = 0; p < v.nodes.n_patterns; ++p)
                    r += double(v.pf[p]) * v.nodes.load_patterns[p * 3 * static_cast<std::size_t>(v.P) + i];
                const double fm = v.free_mask[i], fc = f_cur[i];
                const double du = double(u_cur[i]) - u_prev[i];
                sum[0] += fm * (r - fc) * (r - fc);
                sum[1] += r * r + (1.0 - fm) * fc * fc;
                // A DOF that contact moved this step is held by it, as a fixed DOF by its support:
                // its jump in and out of contact is no stiffness of the structure's.
                const double fr = contact && v.fcon[i] != 0.0 ? 0.0 : fm;
                sum[2] += fr * du * (fc - f_prev[i]);
                sum[3] += fr * double(v.relax_mass[n]) * du * du;
            }
        }
        for (int k = 0; k < 4; ++k) v.partial[4 * c + k] = sum[k];
    });
    dev_.serial([=] PLIANT_KERNEL() {
        double s[4] = {0.0, 0.0, 0.0, 0.0};
        for (index_t c = 0; c < chunks; ++c)
            for (int k = 0; k < 4; ++k) s[k] += v.partial[4 * c + k];
        Scalars<T>& sc = *v.sc;
        sc.residual = s[1] > 0.0 ? std::sqrt(s[0] / s[1]) : 0.0;
        if (s[3] > 0.0 && !contact) {  // Joldes et al.: this step's quotient
            sc.alpha = 2.0 * std::sqrt(s[2] / s[3] > 0.0 ? s[2] / s[3] : 0.0);
            sc.it = central_difference<T>(dt, sc.alpha);
        } else if (s[3] > 0.0 && s[2] > 0.0) {  // with contact: the smallest of the windows'
            const double q = s[2] / s[3];
            if (sc.rq_last == 0.0) sc.rq_now = sc.rq_last = q;  // the relaxation's first estimate
            sc.rq_now = q < sc.rq_now ? q : sc.rq_now;
            const double lowest = sc.rq_now < sc.rq_last ? sc.rq_now : sc.rq_last;
            sc.rq_steps += steps;
            if (sc.rq_steps >= kRelaxWindow) {  // a new window, from this quotient
                sc.rq_last = sc.rq_now;
                sc.rq_now = q;
                sc.rq_steps = 0;
            }
            sc.alpha = 2.0 * std::sqrt(lowest);
            sc.it = central_difference<T>(dt, sc.alpha);
        }
    });
}

template <class T, class Dev>
void Engine<T, Dev>::copy(T* dst, const T* src, std::size_t n) {
    dev_.each(static_cast<index_t>(n), [=] PLIANT_KERNEL(index_t i) { dst[i] = src[i]; });
}

template <class T, class Dev>
void Engine<T, Dev>::fill(T* dst, T value, std::size_t n) {
    dev_.each(static_cast<index_t>(n), [=] PLIANT_KERNEL(index_t i) { dst[i] = value; });
}

/// Per element slot: J, W, S, σ, E into out (20 values per builder element: J, W, S (6), σ (6),
/// E (6)); viscoelastic groups use their stored state, T4ANP the averaged pressure.
template <class T, class Dev>
template <class M, Variant V>
void Engine<T, Dev>::launch_measures(const Span& sp, const T* u, double dt, T* out) {
    const DeviceView<T> v = v_;
    const T tdt = T(dt);
    dev_.blocks(sp.block_begin, sp.block_end, [=] PLIANT_KERNEL(index_t b, int l) {
        (void)tdt, (void)u, (void)out;  // captured before any `if constexpr` (nvcc)
        const index_t e = v.elem_id[b * kLanes + l];
        if (e < 0) return;
        const M mat = make_material<M>(v.mats[v.block_group[b]]);
        ElementMeasures<T> r;
        if (v.smoothed) {  // the edges' stresses (forces() ran: viscous edges used their state)
            const Mat3<T> Pm = mean_edge_stress(b, l, v.ed.elem_edges, v.P_edge);
            if constexpr (V == Variant::Anp) {
                const T p = corner_pressure(b, l, v.el, v.node_p);
                r = element_measures(b, l,
                                     SmoothedStress<M, T, true>{mat, Pm, p, v.anp_gamma[v.block_group[b]]},
                                     v.el, u, v.P);
            } else {
                r = element_measures(b, l, SmoothedStress<M, T, false>{mat, Pm, T(0), T(0)}, v.el, u, v.P);
            }
        } else if constexpr (V == Variant::Visco) {
            const Prony<T>& pr = v.prony[v.block_group[b]];
            const ViscoMaterial<M, T> vm{
                mat, pr, tdt, v.q + aosoa(b, l, 0, v.visco_w), kLanes, ViscoMode::Stored};
            r = element_measures(b, l, vm, v.el, u, v.P);
        } else if constexpr (V == Variant::Anp) {
            const T p = corner_pressure(b, l, v.el, v.node_p);
            r = element_measures(b, l, AveragedPressure<M, T>{mat, p, v.anp_gamma[v.block_group[b]]}, v.el, u,
                                 v.P);
        } else {
            r = element_measures(b, l, mat, v.el, u, v.P);
        }
        T* o = out + 20 * static_cast<std::size_t>(e);
        o[0] = r.J;
        o[1] = r.energy;
        const Sym3<T>* src[3] = {&r.S, &r.sigma, &r.E};
        for (int k = 0; k < 3; ++k) {
            const Sym3<T>& m = *src[k];
            const T vals[6] = {m.xx, m.yy, m.zz, m.xy, m.yz, m.xz};
            for (int c = 0; c < 6; ++c) o[2 + 6 * k + c] = vals[c];
        }
    });
}

}  // namespace pliant
