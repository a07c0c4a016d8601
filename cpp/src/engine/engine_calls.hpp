// pliant — the engine's calls (included by engine.hpp): set-up, state transfer, run, relax and
// the results, the same for every device.
#pragma once

namespace pliant {

template <class T, class Dev>
template <class... A>
Engine<T, Dev>::Engine(const Model<T>& m, A&&... dev_args)
    : m_(m), dev_(std::forward<A>(dev_args)...), groups_(m.groups), tools_(m.tools), mb_(dev_, m) {
    const std::size_t S = static_cast<std::size_t>(m.n_blocks) * kLanes;
    const std::size_t P3 = 3 * static_cast<std::size_t>(m.n_pad);
    const std::size_t nt = m.tools.size(), nc = m.contact_nodes.size();
    for (auto& u : u_) u = DeviceBuffer<T, Dev>(dev_, P3);
    for (auto& d : du_) d = DeviceBuffer<T, Dev>(dev_, P3);
    for (auto& f : f_node_) f = DeviceBuffer<T, Dev>(dev_, P3);
    q_ = DeviceBuffer<T, Dev>(dev_, m.visco_slots() * 6 * static_cast<std::size_t>(m.visco_terms));
    f_elem_ = DeviceBuffer<T, Dev>(dev_, 12 * S + kForcePad);
    mem_f_ = DeviceBuffer<T, Dev>(dev_, 3 * kMembraneSlots * m.mem_kind.size());
    J_ = DeviceBuffer<T, Dev>(dev_, S);
    elem_p_ = DeviceBuffer<T, Dev>(dev_, m.anp ? S : 0);
    node_p_ = DeviceBuffer<T, Dev>(dev_, m.anp ? static_cast<std::size_t>(m.n_pad) : 0);
    const bool smoothed = m.smoothing == StrainSmoothing::Edge;
    H_anp_ = DeviceBuffer<T, Dev>(dev_, Dev::kKeepsAnpGradient && m.anp && !smoothed ? kAnpKept * S : 0);
    H_elem_ = DeviceBuffer<T, Dev>(dev_, smoothed ? 9 * S : 0);
    Hbar_ = DeviceBuffer<T, Dev>(dev_, 9 * static_cast<std::size_t>(m.n_edges));
    P_edge_ = DeviceBuffer<T, Dev>(dev_, 9 * static_cast<std::size_t>(m.n_edges));
    cnext_ = DeviceBuffer<T, Dev>(dev_, m.curves.size());
    pf_ = DeviceBuffer<T, Dev>(dev_, m.pattern_curve.size());
    sc_ = DeviceBuffer<Scalars<T>, Dev>(dev_, 1);
    pose0_ = DeviceBuffer<Pose, Dev>(dev_, nt);
    pose1_ = DeviceBuffer<Pose, Dev>(dev_, nt);
    const std::size_t chunks = chunk_count(static_cast<index_t>(nc));
    cforce_ = DeviceBuffer<double, Dev>(dev_, 3 * nc);
    ctool_ = DeviceBuffer<index_t, Dev>(dev_, nc);
    gtool_ = DeviceBuffer<index_t, Dev>(dev_, nc);
    gat_ = DeviceBuffer<double, Dev>(dev_, 3 * nc);
    closed_ = DeviceBuffer<index_t, Dev>(dev_, nt);
    chunk_ = DeviceBuffer<double, Dev>(dev_, chunks * 6 * nt);
    const std::size_t ns = m.soft_nodes.size(), nst = m.soft_tris.size() / 3;
    fcon_ = DeviceBuffer<double, Dev>(dev_, nt || ns ? P3 : 0);
    allocate_soft(ns, nst);
    partial_ = DeviceBuffer<double, Dev>(
        dev_, 4 * ((static_cast<std::size_t>(m.n_nodes) + kMeasureChunk - 1) / kMeasureChunk));
    d_tools_ = DeviceBuffer<RigidTool, Dev>(dev_, nt);
    d_tools_.upload(tools_.data(), nt);
    d_keys_ = DeviceBuffer<double, Dev>(dev_, m.tool_keys.size());
    d_keys_.upload(m.tool_keys.data(), m.tool_keys.size());
    d_grips_ = DeviceBuffer<double, Dev>(dev_, m.tool_grips.size());
    d_grips_.upload(m.tool_grips.data(), m.tool_grips.size());
    const std::vector<index_t> none(nc, -1);
    ctool_.upload(none.data(), nc);
    gtool_.upload(none.data(), nc);
    const std::size_t ng = groups_.size();
    std::vector<Prony<T>> prony(ng);
    for (std::size_t g = 0; g < ng; ++g) {  // spans: runs of groups of one kind and Prony term counts
        const Group<T>& a = groups_[g];
        prony[g] = a.visco;
        const Group<T>* last = spans_.empty() ? nullptr : &groups_[spans_.back().group];
        const index_t e0 = smoothed ? m.group_edge_begin[g] : 0,
                      e1 = smoothed ? m.group_edge_begin[g + 1] : 0;
        if (last && a.material.kind == last->material.kind && a.visco.n_iso == last->visco.n_iso &&
            a.visco.n_vol == last->visco.n_vol) {
            spans_.back().block_end = a.block_end;
            spans_.back().edge_end = e1;
        } else {
            spans_.push_back({groups_[g].block_begin, groups_[g].block_end, static_cast<index_t>(g), e0, e1});
        }
    }
    d_prony_ = DeviceBuffer<Prony<T>, Dev>(dev_, ng);
    d_prony_.upload(prony.data(), ng);
    std::vector<T> gamma(ng, T(m.anp_stabilization));  // T4ANP stabilization per group
    if (m.anp_shear)
        for (std::size_t g = 0; g < ng; ++g)
            with_material(groups_[g].material, [&](const auto& mat) {
                if constexpr (std::decay_t<decltype(mat)>::decoupled) gamma[g] = anp_shear_gamma(mat);
            });
    anp_gamma_ = DeviceBuffer<T, Dev>(dev_, ng);
    anp_gamma_.upload(gamma.data(), ng);
    d_mats_ = DeviceBuffer<MaterialParams<T>, Dev>(dev_, ng);
    d_mem_geom_ = DeviceBuffer<T, Dev>(dev_, m.mem_geom.size());
    d_mem_bend_ = DeviceBuffer<T, Dev>(dev_, m.mem_bend.size());
    upload_materials();
    ensure_history(1);
    refresh_view();
    const std::vector<T> ones(S, T(1));  // J before any step: every element fine
    J_.upload(ones.data(), S);
}

/// The soft-contact buffers (engine_soft.hpp) for ns surface nodes and nst triangles.
template <class T, class Dev>
void Engine<T, Dev>::allocate_soft(std::size_t ns, std::size_t nst) {
    const std::size_t H = ns ? static_cast<std::size_t>(m_.soft_hash_mask) + 1 : 0;
    sb_ = DeviceBuffer<double, Dev>(dev_, 3 * ns);
    sx_ = DeviceBuffer<double, Dev>(dev_, 3 * ns);
    stc_ = DeviceBuffer<double, Dev>(dev_, 3 * nst);
    str_ = DeviceBuffer<double, Dev>(dev_, nst);
    srec_w_ = DeviceBuffer<double, Dev>(dev_, 3 * ns);
    srec_p_ = DeviceBuffer<double, Dev>(dev_, 3 * ns);
    sacc_ = DeviceBuffer<std::int64_t, Dev>(dev_, 3 * ns);
    sforce_ = DeviceBuffer<double, Dev>(dev_, 3 * ns);
    shead_ = DeviceBuffer<index_t, Dev>(dev_, H + 1);
    scursor_ = DeviceBuffer<index_t, Dev>(dev_, H);
    sbucket_ = DeviceBuffer<index_t, Dev>(dev_, nst);
    scell_ = DeviceBuffer<index_t, Dev>(dev_, nst);
    scand_ = DeviceBuffer<index_t, Dev>(dev_, ns * kSoftCandidates);
    snear_ = DeviceBuffer<index_t, Dev>(dev_, ns);
    srec_ = DeviceBuffer<index_t, Dev>(dev_, ns);
    sshare_ = DeviceBuffer<std::int64_t, Dev>(dev_, ns);
    spair_ = DeviceBuffer<std::int64_t, Dev>(dev_, 3 * static_cast<std::size_t>(m_.soft_pairs));
    const std::size_t ne = m_.soft_edges.size() / 2;
    erec_ = DeviceBuffer<index_t, Dev>(dev_, ne);
    eactive_ = DeviceBuffer<index_t, Dev>(dev_, ne);
    erec_w_ = DeviceBuffer<double, Dev>(dev_, 2 * ne);
    erec_p_ = DeviceBuffer<double, Dev>(dev_, 3 * ne);
    sactive_ = DeviceBuffer<index_t, Dev>(dev_, ns);
    if constexpr (Dev::kSplitsDetection) {  // the candidates' closest points, computed a launch ahead
        const std::size_t lanes = ns * kSoftCandidates;
        slane_f_ = DeviceBuffer<int, Dev>(dev_, lanes);
        slane_d2_ = DeviceBuffer<double, Dev>(dev_, lanes);
        slane_w_ = DeviceBuffer<double, Dev>(dev_, 3 * lanes);
    }
    stouched_ = DeviceBuffer<index_t, Dev>(dev_, ns);
    // Chunk sums of the rebuild's two prefix sums (Engine::scan): over the buckets, and over the
    // surface nodes and sharp edges.
    const index_t parts =
        std::max(chunk_count(static_cast<index_t>(H)), chunk_count(static_cast<index_t>(ns + ne)));
    spart_ = DeviceBuffer<std::int64_t, Dev>(dev_, static_cast<std::size_t>(parts));
    d_soft_mu_ = DeviceBuffer<double, Dev>::mirror(dev_, m_.soft_mu);
}

/// The kernels' view of every device array (after any of them was reallocated).
template <class T, class Dev>
void Engine<T, Dev>::refresh_view() {
    DeviceView<T>& v = v_;
    const Model<T>& m = m_;
    v.n_nodes = m.n_nodes, v.P = m.n_pad;
    v.slots = m.n_blocks * kLanes;
    v.n_contact = static_cast<index_t>(m.contact_nodes.size());
    v.contact_chunk = chunk_size(v.n_contact);
    v.chunks = chunk_count(v.n_contact);
    v.n_curves = static_cast<int>(m.curves.size());
    v.n_factors = static_cast<int>(m.pattern_curve.size());
    v.n_tools = static_cast<int>(tools_.size());
    v.visco_w = 6 * m.visco_terms;
    v.anp_gamma = anp_gamma_.data();
    v.el = {mb_.elem_nodes.data(), mb_.elem_grad.data(), mb_.elem_vol.data()};
    v.smoothed = m.smoothing == StrainSmoothing::Edge;
    v.prefetch = Dev::kPrefetch && m.bytes() > kLargeModelBytes;
    v.stream = Dev::kStreams && m.bytes() > kLargeModelBytes;
    v.ed = {mb_.edge_off.data(), mb_.edge_slot.data(), mb_.edge_w.data(), mb_.elem_edges.data()};
    v.edge_group = mb_.edge_group.data();
    v.H_elem = H_elem_.data(), v.Hbar = Hbar_.data(), v.P_edge = P_edge_.data();
    v.elem_id = mb_.elem_id.data();
    v.block_group = mb_.block_group.data();
    v.mats = d_mats_.data();
    v.prony = d_prony_.data();
    v.nodes = {mb_.inc_off.data(),
               mb_.inc_idx.data(),
               mb_.inv_mass.data(),
               mb_.patterns.data(),
               m.n_load_patterns,
               mb_.pf_off.data(),
               mb_.pf_idx.data(),
               mb_.pnodes.data(),
               mb_.pedges.data(),
               mb_.pvalue.data(),
               mb_.pslot.data(),
               mb_.ptraction.data(),
               {static_cast<index_t>(m.mem_kind.size()), mb_.mem_off.data(), mb_.mem_idx.data(),
                mb_.mem_nodes.data(), mb_.mem_kind.data(), d_mem_geom_.data(), mem_f_.data(),
                m.mem_nbrs.empty() ? nullptr : mb_.mem_nbrs.data(),
                m.mem_bend.empty() ? nullptr : d_mem_bend_.data()}};
    v.relax_nodes = v.nodes;
    v.relax_nodes.inv_mass = mb_.relax_inv_mass.data();
    v.mass = mb_.mass.data(), v.relax_mass = mb_.relax_mass.data(), v.free_mask = mb_.free_mask.data();
    v.node_volume = mb_.node_vol.data(), v.cval = mb_.cval.data(), v.inc_slot = mb_.inc_slot.data();
    v.co = mb_.co.data(), v.cdof = mb_.cdof.data(), v.ccurve = mb_.ccurve.data();
    v.pattern_curve = mb_.pcurve.data(), v.cnodes = mb_.cnodes.data(), v.cbits = mb_.cbits.data();
    v.cskin = mb_.cskin.data();
    v.curves = mb_.curves.data(), v.tt = mb_.tt.data(), v.tv = mb_.tv.data(), v.X = mb_.X.data();
    v.grid = mb_.grid.data(), v.tools = d_tools_.data(), v.keys = d_keys_.data(), v.grips = d_grips_.data();
    for (int k = 0; k < 3; ++k) v.u[k] = u_[k].data(), v.du[k] = du_[k].data();
    v.q = q_.data(), v.f_elem = f_elem_.data(), v.J = J_.data();
    v.elem_p = elem_p_.data(), v.node_p = node_p_.data(), v.H_anp = H_anp_.data();
    v.f_node[0] = f_node_[0].data(), v.f_node[1] = f_node_[1].data();
    v.cnext = cnext_.data(), v.pf = pf_.data(), v.sc = sc_.data();
    v.pose0 = pose0_.data(), v.pose1 = pose1_.data();
    v.cforce = cforce_.data(), v.chunk = chunk_.data(), v.hist = hist_.data();
    v.fcon = fcon_.data(), v.partial = partial_.data(), v.ctool = ctool_.data();
    v.closed = closed_.data(), v.gtool = gtool_.data(), v.gat = gat_.data();
    v.n_pairs = m.soft_pairs;
    v.hist_width = 6 * v.n_tools + 3 * v.n_pairs;
    SoftSurface& sf = v.soft;
    sf.n_nodes = static_cast<index_t>(m.soft_nodes.size());
    sf.n_tris = static_cast<index_t>(m.soft_tris.size() / 3);
    sf.labels = m.soft_labels, sf.hash_mask = m.soft_hash_mask;
    sf.node = mb_.snodes.data(), sf.bits = mb_.sbits.data(), sf.label = mb_.slabel.data();
    sf.tri = mb_.stris.data(), sf.tri_h = mb_.stri_h.data(), sf.pair = mb_.spair.data();
    sf.vtri_off = mb_.svtri_off.data(), sf.vtri = mb_.svtri.data();
    sf.n_edges = static_cast<index_t>(m.soft_edges.size() / 2);
    sf.edge = mb_.sedges.data(), sf.tri_edge = mb_.stri_edge.data();
    sf.mu = d_soft_mu_.data(), sf.skin = m.soft_skin, sf.cell = m.soft_cell;
    sf.sheet_h = mb_.ssheet_h.data();
    sf.band_max = m.soft_band;
    v.sb = sb_.data(), v.sx = sx_.data(), v.stc = stc_.data(), v.str = str_.data();
    v.srec_w = srec_w_.data(), v.srec_p = srec_p_.data(), v.sacc = sacc_.data(), v.sforce = sforce_.data();
    v.shead = shead_.data(), v.scursor = scursor_.data(), v.sbucket = sbucket_.data();
    v.scell = scell_.data(), v.scand = scand_.data(), v.snear = snear_.data(), v.srec = srec_.data(),
    v.sshare = sshare_.data(), v.spair = spair_.data();
    v.erec = erec_.data(), v.erec_w = erec_w_.data(), v.erec_p = erec_p_.data();
    v.sactive = sactive_.data(), v.stouched = stouched_.data(), v.eactive = eactive_.data();
    v.spart = spart_.data();
    v.slane_f = slane_f_.data(), v.slane_d2 = slane_d2_.data(), v.slane_w = slane_w_.data();
}

/// Copies a state to the device unless the device holds it already (same object, same version).
template <class T, class Dev>
void Engine<T, Dev>::load(const State<T>& s) {
    if (resident_ == &s && resident_version_ == s.version) return;
    u_[phase_.cur].upload(s.u.data(), s.u.size());
    u_[phase_.prev].upload(s.u_prev.data(), s.u_prev.size());
    du_[phase_.cur].upload(s.du.data(), s.du.size());
    q_.upload(s.q.data(), s.q.size());
    gtool_.upload(s.grip_tool.data(), s.grip_tool.size());
    gat_.upload(s.grip_at.data(), s.grip_at.size());
    resident_ = &s;
    resident_version_ = s.version;
}

/// Copies the device's state back into s, which becomes the resident state.
template <class T, class Dev>
void Engine<T, Dev>::store(State<T>& s) {
    u_[phase_.cur].download(s.u.data(), s.u.size());
    u_[phase_.prev].download(s.u_prev.data(), s.u_prev.size());
    du_[phase_.cur].download(s.du.data(), s.du.size());
    q_.download(s.q.data(), s.q.size());
    gtool_.download(s.grip_tool.data(), s.grip_tool.size());
    gat_.download(s.grip_at.data(), s.grip_at.size());
    s.touch();
    resident_ = &s;
    resident_version_ = s.version;
}

template <class T, class Dev>
void Engine<T, Dev>::set_scalars(double t0, long base, double dt, double alpha) {
    Scalars<T> s{};
    s.t0 = t0;
    s.base = base;
    s.it = central_difference<T>(dt, alpha);
    s.alpha = alpha;
    s.soft_due = 1;  // the state may have changed since the last run: new candidate lists
    s.soft_moved = INT_MAX;
    sc_.upload(&s, 1);
}

template <class T, class Dev>
void Engine<T, Dev>::ensure_history(long rows) {
    const std::size_t width = 6 * tools_.size() + 3 * static_cast<std::size_t>(m_.soft_pairs);
    const std::size_t need = static_cast<std::size_t>(rows < 1 ? 1 : rows) * width;
    if (need > hist_.size() || hist_.data() == nullptr) {
        hist_ = DeviceBuffer<double, Dev>(dev_, need);
        refresh_view();
    }
}

template <class T, class Dev>
RunReport Engine<T, Dev>::run(State<T>& s, long n, double dt, double alpha, int check_every, double size) {
    if (s.dt != dt) s.restart_clock();  // the clock counts steps of one Δt
    if (keep_velocity(s, dt)) s.touch();
    load(s);
    ensure_history(n);
    const double t0 = s.t_epoch;
    const long base = s.step - s.step_epoch;
    set_scalars(t0, base, dt, alpha);
    RunReport rep;
    const long G = check_every > 0 ? check_every : 1;
    long done = 0;
    dev_.region([&] {
        Phase ph = phase_;  // each thread keeps the same rotation
        long d = 0;
        while (d < n) {
            const long k = std::min(G, n - d);
            replay_steps(k, ph.cur, [&] {
                step_once(ph, dt, dt, false, nullptr, rep);
                ph.rotate();
            });
            d += k;
            // J belongs to the last step's input (t), the newest u to t + Δt; u[prev] is at t.
            if (check(v_.u[ph.cur], v_.u[ph.prev], clock_time(t0, base + d - 1, dt),
                      clock_time(t0, base + d, dt), size, rep)
                    .status)
                break;
        }
        if (dev_.lead()) {
            done = d;
            phase_ = ph;
        }
    });
    dev_.forget_graphs();
    store(s);
    s.t = clock_time(t0, base + done, dt);
    s.dt = dt;
    s.step += done;
    history_rows_ = done;
    rep.steps = done;
    if (rep.status == RunStatus::Ok) rep.t = s.t;
    return rep;
}

template <class T, class Dev>
RunReport Engine<T, Dev>::step(const State<T>& in, State<T>& out, double dt, double alpha) {
    State<T> tmp = in;
    tmp.touch();
    RunReport rep = run(tmp, 1, dt, alpha, 1, INFINITY);
    out = std::move(tmp);
    out.touch();
    resident_ = nullptr;
    return rep;
}

/// Dynamic relaxation with adaptive mass-proportional damping (Joldes, Wittek & Miller 2009,
/// CMAME 198:3313, §3) over the fictitious masses of Model::relax_mass; stops when the residual
/// falls below tol, or has not improved by 1 % over 1,000 checks (the round-off floor).
template <class T, class Dev>
RunReport Engine<T, Dev>::relax(State<T>& s, double t_eval, double dt, double tol, long max_steps,
                                int check_every, double size) {
    load(s);
    copy(v_.u[phase_.prev], v_.u[phase_.cur], u_[0].size());  // start at rest
    fill(v_.du[phase_.cur], T(0), du_[0].size());             // (no increment)
    ensure_history(1);                                        // relax keeps the last step's tool forces
    set_scalars(t_eval, 0, dt, 0.0);
    RunReport rep;
    long done = 0;
    dev_.region([&] {
        Phase ph = phase_;
        int fc = 0;  // f_node_[fc]: where the next step writes f(u_cur)
        long d = 0, checks = 0, best_check = 0;
        double best = INFINITY;
        bool stop = false;
        const long G = check_every > 0 ? check_every : 1;
        while (d < max_steps && !stop) {
            const long k = std::min(G, max_steps - d);
            replay_steps(k, 2 * ph.cur + fc, [&] {
                step_once(ph, dt, 0.0, true, v_.f_node[fc], rep);
                ph.rotate();
                fc = 1 - fc;
            });
            d += k;
            if (d % G != 0 || d < 2) continue;
            // The measures belong to the last step's input u[prev] (f_node[1 − fc]) and the one
            // before, u[next] (f_node[fc]).
            relax_measure(v_.u[ph.prev], v_.u[ph.next], v_.f_node[1 - fc], v_.f_node[fc], dt, k);
            // One read of the device scalars: the check's verdict and the measure's residual.
            // (No step-size check: a relaxation's pseudo-time moves as its fictitious masses let it.)
            const Scalars<T> seen = check(v_.u[ph.prev], nullptr, t_eval, t_eval, size, rep);
            const bool ok = seen.status == 0;
            const double residual = seen.residual;
            ++checks;
            if (residual < 0.99 * best) {
                best = residual;
                best_check = checks;
            }
            stop = !ok || residual < tol || checks - best_check > 1000;
            if (dev_.lead()) rep.residual = residual;
        }
        if (dev_.lead()) {
            done = d;
            phase_ = ph;
        }
    });
    dev_.forget_graphs();
    if (m_.visco_terms > 0)  // the viscous state of the equilibrium: fully relaxed, stored
        dev_.region([&] { forces(v_.u[phase_.cur], ViscoMode::RelaxedStore, dt); });
    copy(v_.u[phase_.prev], v_.u[phase_.cur], u_[0].size());  // equilibrium: at rest
    fill(v_.du[phase_.cur], T(0), du_[0].size());             // (no increment)
    rep.damping = dev_.read(&v_.sc->alpha);
    store(s);
    s.t = t_eval;
    s.dt = dt;
    s.restart_clock();
    history_rows_ = 1;
    rep.steps = done;
    if (rep.status == RunStatus::Ok) rep.t = t_eval;
    return rep;
}

template <class T, class Dev>
ElementResults<T> Engine<T, Dev>::measures(const State<T>& s) {
    load(s);
    const std::size_t M = static_cast<std::size_t>(m_.n_elems);
    DeviceBuffer<T, Dev> out(dev_, 20 * M);
    const T* u = v_.u[phase_.cur];
    dev_.region([&] {
        if (m_.anp || v_.smoothed) {  // the stresses the forces see: averaged pressure, edge stresses
            forces(u, ViscoMode::Stored, s.dt);
        }
        dispatch(
            [&]<class M_, Variant V>(const Span& sp) { launch_measures<M_, V>(sp, u, s.dt, out.data()); });
        dev_.barrier();
    });
    const std::vector<T> h = out.to_host();
    ElementResults<T> r;
    r.J.resize(M), r.W.resize(M), r.S.resize(6 * M), r.sigma.resize(6 * M), r.E.resize(6 * M);
    for (std::size_t e = 0; e < M; ++e) {
        const T* o = &h[20 * e];
        r.J[e] = o[0];
        r.W[e] = o[1];
        for (int c = 0; c < 6; ++c) {
            r.S[6 * e + c] = o[2 + c];
            r.sigma[6 * e + c] = o[8 + c];
            r.E[6 * e + c] = o[14 + c];
        }
    }
    return r;
}

/// f(u) [N] of the state's displacements, SoA (3, P): kernel 1 (stored viscoelastic state), with
/// damped the β damping forces of the state's du and Δt, then the gather of kernel 2 with no loads
/// and a zero integrator.
template <class T, class Dev>
std::vector<T> Engine<T, Dev>::internal_forces(const State<T>& s, bool damped) {
    load(s);
    const Integrator<T> zero{T(0), T(0)};
    Scalars<T> sc = dev_.read(v_.sc);
    sc.it = zero;
    sc_.upload(&sc, 1);
    fill(v_.pf, T(0), pf_.size());
    const Phase ph = phase_;
    dev_.region([&] {
        forces(v_.u[ph.cur], ViscoMode::Stored, s.dt);
        if (damped && m_.stiffness_damping > 0.0 && s.dt > 0.0) damping(ph, s.dt);
        node_pass(Phase{ph.cur, ph.cur, 3 - ph.cur - ph.prev}, false, v_.f_node[0]);
    });
    return f_node_[0].to_host();
}

/// The external loads [N] at the state's u and the curves at t [s], SoA (3, P): the pattern factors
/// at t, then applied_loads per node (what the node pass drives each node with).
template <class T, class Dev>
std::vector<T> Engine<T, Dev>::external_forces(const State<T>& s, double t) {
    load(s);
    const Phase ph = phase_;
    dev_.region([&] { load_pass(t, v_.u[ph.cur], v_.f_node[0]); });
    return f_node_[0].to_host();
}

/// Columns [begin, begin + width) of the last run's history rows (tools: 6 each, then pairs: 3 each).
template <class T, class Dev>
std::vector<double> Engine<T, Dev>::history_columns(std::size_t begin, std::size_t width) {
    const std::size_t rows = static_cast<std::size_t>(history_rows_);
    const std::size_t w = 6 * tools_.size() + 3 * static_cast<std::size_t>(m_.soft_pairs);
    std::vector<double> all(rows * w), h(rows * width);
    hist_.download(all.data(), all.size());
    for (std::size_t r = 0; r < rows; ++r)
        for (std::size_t c = 0; c < width; ++c) h[r * width + c] = all[r * w + begin + c];
    return h;
}

template <class T, class Dev>
std::vector<double> Engine<T, Dev>::tool_history() {
    return history_columns(0, 6 * tools_.size());
}

template <class T, class Dev>
std::vector<double> Engine<T, Dev>::pair_history() {
    return history_columns(6 * tools_.size(), 3 * static_cast<std::size_t>(m_.soft_pairs));
}

template <class T, class Dev>
ContactReport Engine<T, Dev>::contact_report() {
    return {ctool_.to_host(), cforce_.to_host(), sforce_.to_host()};
}

template <class T, class Dev>
void Engine<T, Dev>::set_tool_keys(const std::vector<std::vector<double>>& keys,
                                   const std::vector<std::vector<double>>& grips,
                                   const std::vector<double>& reach) {
    if (keys.size() != tools_.size() || grips.size() != tools_.size() || reach.size() != tools_.size())
        throw std::invalid_argument("set_tool_keys: " + std::to_string(keys.size()) + " key lists, " +
                                    std::to_string(grips.size()) + " grip lists and " +
                                    std::to_string(reach.size()) + " reaches, expected one each per tool (" +
                                    std::to_string(tools_.size()) + ")");
    for (std::size_t k = 0; k < tools_.size(); ++k) {  // everything checked before anything changes
        if (keys[k].empty() || keys[k].size() % 8)
            throw std::invalid_argument("set_tool_keys: tool " + std::to_string(k) + " has " +
                                        std::to_string(keys[k].size()) +
                                        " numbers; expected 8 per keyframe (t, position, quaternion)");
        for (std::size_t j = 1; j < grips[k].size(); ++j)
            if (!(grips[k][j] > grips[k][j - 1]))
                throw std::invalid_argument("set_tool_keys: tool " + std::to_string(k) +
                                            ": grip times must increase");
    }
    std::vector<double> times;
    for (std::size_t k = 0; k < grips.size(); ++k) {
        tools_[k].grip_begin = static_cast<index_t>(times.size());
        tools_[k].grip_count = static_cast<index_t>(grips[k].size());
        tools_[k].reach = reach[k];
        times.insert(times.end(), grips[k].begin(), grips[k].end());
    }
    if (times.size() > d_grips_.size()) d_grips_ = DeviceBuffer<double, Dev>(dev_, times.size());
    d_grips_.upload(times.data(), times.size());
    std::vector<double> all;
    for (std::size_t k = 0; k < keys.size(); ++k) {
        tools_[k].key_begin = static_cast<index_t>(all.size() / 8);
        tools_[k].key_count = static_cast<index_t>(keys[k].size() / 8);
        all.insert(all.end(), keys[k].begin(), keys[k].end());
    }
    if (all.size() > d_keys_.size()) d_keys_ = DeviceBuffer<double, Dev>(dev_, all.size());
    d_keys_.upload(all.data(), all.size());
    d_tools_.upload(tools_.data(), tools_.size());
    refresh_view();
}

template <class T, class Dev>
void Engine<T, Dev>::scale_materials(double factor) {
    if (!(factor > 0.0 && std::isfinite(factor)))
        throw std::invalid_argument("scale_materials: factor must be finite and > 0");
    for (std::size_t g = 0; g < groups_.size(); ++g) {
        MaterialParams<T>& mat = groups_[g].material;
        for (int k = 0; k < kMaterialParams; ++k)
            mat.p[k] = T(double(m_.groups[g].material.p[k]) * (is_modulus(mat.kind, k) ? factor : 1.0));
    }
    material_scale_ = factor;
    upload_materials();
}

/// The groups' material parameters to the device (where the element kernels read them), and the
/// membranes' values with their moduli times material_scale_ (membrane.hpp, kMembraneModuli).
template <class T, class Dev>
void Engine<T, Dev>::upload_materials() {
    std::vector<MaterialParams<T>> mats(groups_.size());
    for (std::size_t g = 0; g < groups_.size(); ++g) mats[g] = groups_[g].material;
    d_mats_.upload(mats.data(), mats.size());
    std::vector<T> geom = m_.mem_geom;
    for (std::size_t i = kMembraneModuli; i < geom.size(); i += kMembraneValues)
        for (int k = 0; k < kMembraneValues - kMembraneModuli; ++k)
            geom[i + k] = T(double(geom[i + k]) * material_scale_);
    d_mem_geom_.upload(geom.data(), geom.size());
    std::vector<T> bend = m_.mem_bend;
    for (std::size_t i = kBendModuli; i < bend.size(); i += kBendValues)
        for (int k = 0; k < kBendValues - kBendModuli; ++k)
            bend[i + k] = T(double(bend[i + k]) * material_scale_);
    d_mem_bend_.upload(bend.data(), bend.size());
}

}  // namespace pliant
