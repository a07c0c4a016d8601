// pliant — the engine's soft-contact pass (included by engine.hpp): contact between deformable
// surfaces, after the tool contact of a step. The physics are soft_contact.hpp's.
#pragma once

namespace pliant {

/// Prefix sums over items [0, n), in chunks (chunk_size), the same on every device and thread count:
/// (1) one thread per chunk sums count(i) over its items into spart; (2) one thread turns those
/// into each chunk's offset and calls total(the sum of all); (3) one thread per chunk calls
/// emit(i, before, k) for its items in order, k = count(i), before = the sum of count over the items before
/// i. The kernels return at once unless *flag (inside `when`, CUDA launches them whatever it holds).
template <class T, class Dev>
template <class Count, class Total, class Emit>
void Engine<T, Dev>::scan(index_t n, const int* flag, const Count& count, const Total& total,
                          const Emit& emit) {
    const index_t size = chunk_size(n), chunks = chunk_count(n);  // spart holds chunks (allocate_soft)
    std::int64_t* part = v_.spart;
    dev_.each(chunks, [=] PLIANT_KERNEL(index_t c) {
        if (!*flag) return;
        const index_t end = (c + 1) * size < n ? (c + 1) * size : n;
        std::int64_t sum = 0;
        for (index_t i = c * size; i < end; ++i) sum += count(i);
        part[c] = sum;
    });
    dev_.serial([=] PLIANT_KERNEL() {
        if (!*flag) return;
        std::int64_t sum = 0;
        for (index_t c = 0; c < chunks; ++c) {
            const std::int64_t k = part[c];
            part[c] = sum;
            sum += k;
        }
        total(sum);
    });
    dev_.each(chunks, [=] PLIANT_KERNEL(index_t c) {
        if (!*flag) return;
        const index_t end = (c + 1) * size < n ? (c + 1) * size : n;
        std::int64_t before = part[c];
        for (index_t i = c * size; i < end; ++i) {
            const std::int64_t k = count(i);
            emit(i, before, k);
            before += k;
        }
    });
}

/// A rebuild of the broad phase at displacements u [m], every part in parallel: (1) per triangle,
/// its centroid, radius and bucket (soft_grid_triangle), counted per bucket (scursor) and the
/// largest radius kept; (2) the buckets' starts (shead, by scan); (3) per triangle, its slot in its
/// bucket (scursor counts down to 0 again, ready for the next rebuild); (4) per surface node, its
/// candidates (soft_candidates); (5) the surface nodes that have some, in order (sactive, their
/// count soft_active), and the sharp edges with an end node that has some (eactive): only they are
/// checked until the next rebuild (one scan: nodes count in the low 32 bits, edges in the high).
template <class T, class Dev>
void Engine<T, Dev>::soft_lists(const T* u) {
    const DeviceView<T> v = v_;
    const SoftSurface s = v.soft;
    const int* flag = &v.sc->soft_rebuild;
    const index_t H = s.hash_mask + 1;
    dev_.each(s.n_tris, [=] PLIANT_KERNEL(index_t t) {
        if (!v.sc->soft_rebuild) return;
        double r;
        const index_t b = soft_grid_triangle(t, s, v.X, u, v.P, v.stc, v.str, v.sbucket, r);
        atomic_add(&v.scursor[b], 1);
        atomic_max(&v.sc->soft_rmax, double_bits(r));  // r >= 0: its bits order as the values do
    });
    scan(
        H, flag, [=] PLIANT_KERNEL(index_t b) -> std::int64_t { return v.scursor[b]; },
        [=] PLIANT_KERNEL(std::int64_t sum) { v.shead[H] = static_cast<index_t>(sum); },
        [=] PLIANT_KERNEL(index_t b, std::int64_t before, std::int64_t) {
            v.shead[b] = static_cast<index_t>(before);
        });
    dev_.each(s.n_tris, [=] PLIANT_KERNEL(index_t t) {
        if (!v.sc->soft_rebuild) return;
        const index_t b = v.sbucket[t];
        v.scell[v.shead[b] + atomic_add(&v.scursor[b], -1) - 1] = t;
    });
    dev_.each(s.n_nodes, [=] PLIANT_KERNEL(index_t i) {
        if (v.sc->soft_rebuild)
            soft_candidates(i, s, v.X, u, v.P, bits_double(v.sc->soft_rmax), v.shead, v.scell, v.stc, v.str,
                            v.scand, v.snear, v.sb);
    });
    const index_t ns = s.n_nodes;
    auto has = [=] PLIANT_KERNEL(index_t i) {
        return v.scand[static_cast<std::size_t>(i) * kSoftCandidates] >= 0;
    };
    scan(
        ns + s.n_edges, flag,
        [=] PLIANT_KERNEL(index_t k) -> std::int64_t {
            if (k < ns) return has(k) ? 1 : 0;
            const index_t e = k - ns;
            return has(s.edge[2 * e]) || has(s.edge[2 * e + 1]) ? std::int64_t(1) << 32 : 0;
        },
        [=] PLIANT_KERNEL(std::int64_t sum) {
            Scalars<T>& sc = *v.sc;
            sc.soft_active = static_cast<index_t>(sum & 0xffffffff);
            sc.soft_edges_active = static_cast<index_t>(sum >> 32);
            sc.soft_items = sc.soft_active > sc.soft_edges_active ? sc.soft_active : sc.soft_edges_active;
            sc.soft_lanes = sc.soft_active * kSoftCandidates;
        },
        [=] PLIANT_KERNEL(index_t k, std::int64_t before, std::int64_t active) {
            if (k < ns) {
                if (active) v.sactive[before & 0xffffffff] = k;
                return;
            }
            v.erec[k - ns] = -1;  // inactive edges hold no contact (soft_edge_partner reads the other side's)
            if (active) v.eactive[before >> 32] = k - ns;
        });
}

/// The sharp edge that edge e's contact of the sweep is with, or −1: none, or the same two edges found
/// from the other one's side too (erec[f] == e) and f < e, so counted at f. Both sides' impulses
/// are equal and opposite; applying both closed the gap twice (their shares, weights summing to one
/// per node, did not average them).
template <class T>
PLIANT_HD index_t soft_edge_partner(const DeviceView<T>& v, index_t e) {
    const index_t f = v.erec[e];
    return f >= 0 && f < e && v.erec[f] == e ? -1 : f;
}

/// One unit of a sweep's fixed-point shares is 2^-32: a weight w in (0, 1] counts
/// max(1, round(w 2^32)) units, so that every node a contact reaches counts at least one.
constexpr double kSoftShareUnits = 4294967296.0;  // 2^32 units per share of one

/// x / unit rounded to the nearest integer (ties to even), given per_unit = 1/unit; 0 for NaN or
/// beyond ±2^62, which soft_gather's units keep every finite sweep within.
PLIANT_HD std::int64_t soft_fixed(double x, double per_unit) {
    const double y = x * per_unit;
    if (!(std::fabs(y) < 4.6e18)) return 0;
#if defined(__CUDA_ARCH__)
    return __double2ll_rn(y);
#else
    return std::llrint(y);
#endif
}

/// Contact c of a sweep: c < soft_active, the node contact of sactive[c] (its slave, then its
/// triangle's nodes); beyond, the edge contact of eactive[c − soft_active] (the edge's ends, then
/// its partner's). Its nodes, their weights (the first body's positive: 1 for a slave, 1 − a and a
/// for an edge; the second body's negative: the barycentric weights, 1 − b and b), and its impulse
/// p [kg·m] (3, on the first body). False if it has no contact this sweep.
struct SoftContact {
    index_t node[4];
    double w[4];
    const double* p;
};
template <class T>
PLIANT_HD bool soft_contact_at(const DeviceView<T>& v, const SoftSurface& s, index_t c, SoftContact& k) {
    const index_t na = v.sc->soft_active;
    if (c < na) {
        const index_t i = v.sactive[c], t = v.srec[i];
        if (t < 0) return false;
        k.node[0] = i, k.w[0] = 1.0, k.p = v.srec_p + 3 * i;
        for (int j = 0; j < 3; ++j) k.node[j + 1] = s.tri[3 * t + j], k.w[j + 1] = -v.srec_w[3 * i + j];
        return true;
    }
    const index_t e = v.eactive[c - na], f = soft_edge_partner(v, e);
    if (f < 0) return false;
    const double a = v.erec_w[2 * e], b = v.erec_w[2 * e + 1];
    k.node[0] = s.edge[2 * e], k.node[1] = s.edge[2 * e + 1], k.w[0] = 1.0 - a, k.w[1] = a;
    k.node[2] = s.edge[2 * f], k.node[3] = s.edge[2 * f + 1], k.w[2] = -(1.0 - b), k.w[3] = -b;
    k.p = v.erec_p + 3 * e;
    return true;
}

/// Whether a contact's weight w reaches its node (a weight of 0 moves nothing; NaN neither).
PLIANT_HD bool soft_reaches(double w) { return w > 0.0 || w < 0.0; }

/// Step (3a) of soft_pass for contact c: each node it reaches adds |w| to its share of the sweep's
/// contacts (sshare, fixed point: kSoftShareUnits), the contact first reaching it lists it in
/// stouched, it counts itself (soft_contacts), and its impulse's largest component raises the
/// sweep's (soft_pmax).
template <class T, class Team>
PLIANT_HD void soft_count(const DeviceView<T>& v, const SoftSurface& s, const Team& team, index_t c) {
    SoftContact k;
    if (!soft_contact_at(v, s, c, k)) return;
    team.add(&v.sc->soft_contacts, index_t(1));
    for (int j = 0; j < 4; ++j) {
        if (!soft_reaches(k.w[j])) continue;
        std::int64_t q = soft_fixed(std::fabs(k.w[j]), kSoftShareUnits);
        if (q < 1) q = 1;
        const index_t n = k.node[j];
        if (team.add(&v.sshare[n], q) == 0) v.stouched[team.add(&v.sc->soft_touched, index_t(1))] = n;
    }
    for (int d = 0; d < 3; ++d) team.max(&v.sc->soft_pmax, double_bits(std::fabs(k.p[d])));
}

/// The unit [kg·m] of a sweep's fixed-point impulse sums: 2^(e_p + e_m − 62), with |p| < 2^e_p for
/// every impulse component (pmax, as bits) and m < 2^e_m contacts. A node's or a pair's sum then
/// stays below m (2^(62 − e_m) + 2) < 2^63 units (|p| / share <= |p|: every share is at least one);
/// the unit is at most 2^(e_m − 61) of the largest impulse (3e-17 of it for 60 contacts). NaN if
/// pmax is not finite (the sums are NaN then, and the step's check reports them).
PLIANT_HD double soft_unit(std::int64_t pmax, index_t m) {
    const int field = static_cast<int>((pmax >> 52) & 0x7ff);
    if (field == 0x7ff) return bits_double(std::int64_t(0x7ff8) << 48);  // NaN
    int ep = field - 1022, em = 0;                                       // pmax < 2^ep (frexp's exponent)
    if (ep < -900) ep = -900;  // below 2^-900 an impulse is nothing: keep the unit a normal number
    while (em < 31 && (std::int64_t(1) << em) <= m) ++em;
    return bits_double(std::int64_t(ep + em - 62 + 1023) << 52);  // within -962 .. 994: a normal number
}

/// Step (3b) of soft_pass for contact c: its impulse divided by the largest share among the nodes
/// it reaches (Macklin et al. 2014 §4.2: the contacts sharing a node averaged; shares counted by
/// weight, so that a node at the corner of a triangle others hit counts about once, not once per
/// triangle; never below one, so that a lone edge contact, weights below one, keeps its whole
/// impulse), w p added to each node's sum (sacc) and the first body's impulse to its pair's (spair),
/// in fixed point (soft_unit). The nodes' parts are rounded one by one and the node of the largest
/// weight takes what makes them sum to zero: the pair's impulses are equal and opposite exactly.
template <class T, class Team>
PLIANT_HD void soft_spread(const DeviceView<T>& v, const SoftSurface& s, const Team& team, index_t c,
                           double unit) {
    SoftContact k;
    if (!soft_contact_at(v, s, c, k)) return;
    std::int64_t most = static_cast<std::int64_t>(kSoftShareUnits);
    int big = 0;
    for (int j = 0; j < 4; ++j) {
        if (!soft_reaches(k.w[j])) continue;
        if (v.sshare[k.node[j]] > most) most = v.sshare[k.node[j]];
        if (std::fabs(k.w[j]) > std::fabs(k.w[big])) big = j;
    }
    // p / share in units: share >= 1 and unit a power of two
    const double scale = kSoftShareUnits / (double(most) * unit);
    const index_t la = s.label[k.node[0]], lb = s.label[k.node[2]];
    const index_t pr = s.pair[static_cast<std::size_t>(la) * s.labels + lb];
    for (int d = 0; d < 3; ++d) {
        const double p = k.p[d] * scale;
        std::int64_t q[4], sum = 0, first = 0;
        for (int j = 0; j < 4; ++j) sum += q[j] = soft_reaches(k.w[j]) ? soft_fixed(k.w[j], p) : 0;
        q[big] -= sum;
        for (int j = 0; j < 4; ++j) {
            if (soft_reaches(k.w[j])) team.add(&v.sacc[3 * k.node[j] + d], q[j]);
            if (k.w[j] > 0.0) first += q[j];
        }
        team.add(&v.spair[3 * pr + d], la <= lb ? first : -first);  // a pair's first body: its lower label
    }
}

/// Step (3) of soft_pass, on one team: the sweep's contacts' impulses into the nodes they reach
/// (sacc) and into the step's per-pair forces p/γ1 [N] (its history row), (a) the shares counted
/// (soft_count), (b) the impulses spread (soft_spread), (c) the pairs' sums added to the row. Every
/// sum is of integers (fixed point): the same bits whatever order the team's threads take.
template <class T, class Team>
PLIANT_HD void soft_gather(const DeviceView<T>& v, const SoftSurface& s, bool first, const Team& team) {
    Scalars<T>& sc = *v.sc;
    team.one([&] { sc.soft_touched = 0, sc.soft_contacts = 0; });
    team.sync();
    const index_t m = sc.soft_active + sc.soft_edges_active;
    team.each(m, [&](index_t c) { soft_count(v, s, team, c); });
    team.sync();
    // The unit from the contacts found, not from the nodes and edges that could have one: those
    // depend on when the candidate lists were last rebuilt (a run's start rebuilds them), the
    // contacts do not, so a run split in two (or saved and restored) gives the same bits.
    const double unit = soft_unit(sc.soft_pmax, sc.soft_contacts);
    team.each(m, [&](index_t c) { soft_spread(v, s, team, c, unit); });
    team.sync();
    team.one([&] {
        double* row = v.hist + sc.row * v.hist_width + 6 * v.n_tools;
        const double g1 = double(sc.it.g1);
        for (index_t k = 0; k < 3 * v.n_pairs; ++k) {
            row[k] = (first ? 0.0 : row[k]) + double(v.spair[k]) * unit / g1;
            v.spair[k] = 0;
        }
        sc.soft_unit = unit;
        sc.soft_pmax = 0;
        // A sweep after one that moved nothing would find what it found: nothing (soft_pass skips it).
        sc.soft_redo = sc.soft_touched > 0 ? sc.soft_items : 0;
        sc.soft_lanes_redo = sc.soft_touched > 0 ? sc.soft_lanes : 0;
    });
}

/// Step (2) of soft_pass, split (Dev::kSplitsDetection), for slot k = a × kSoftCandidates + q: the
/// closest point of the a-th active node's candidate q (its feature, squared distance and weights)
/// into the slot, which SoftClosestStored reads; nothing past the node's list.
template <class T>
PLIANT_HD void soft_closest_slot(const DeviceView<T>& v, const SoftSurface& s, index_t k) {
    const index_t i = v.sactive[k / kSoftCandidates];
    const index_t t = v.scand[static_cast<std::size_t>(i) * kSoftCandidates + k % kSoftCandidates];
    if (t < 0) return;
    double x[3], w[3];
    soft_current(i, v.sx, x);
    v.slane_f[k] = soft_closest_to(t, s, v.sx, x, w, v.slane_d2[k]);
    for (int d = 0; d < 3; ++d) v.slane_w[3 * static_cast<std::size_t>(k) + d] = w[d];
}

/// Step (2) of soft_pass for the a-th node that has candidates (sactive[a]): soft_detect, its
/// candidates' closest points computed as it walks them, or, if split (Dev::kSplitsDetection), read
/// from the slots the launch before filled (a kSoftCandidates from a × kSoftCandidates).
template <bool split, class T>
PLIANT_HD void soft_detect_active(const DeviceView<T>& v, const SoftSurface& s, const T* mass, const T* uc,
                                  const T* un, index_t a) {
    const index_t i = v.sactive[a];
    if constexpr (split)
        soft_detect(i, s, v.X, mass, uc, un, v.P, v.sx, v.scand, v.snear,
                    SoftClosestStored{v.slane_f, v.slane_d2, v.slane_w,
                                      static_cast<std::size_t>(a) * kSoftCandidates},
                    v.srec, v.srec_w, v.srec_p);
    else
        soft_detect(i, s, v.X, mass, uc, un, v.P, v.sx, v.scand, v.snear, SoftClosestComputed{&s, v.sx},
                    v.srec, v.srec_w, v.srec_p);
}

/// Step (4) of soft_pass for touched surface node i, on the team after its sums: the correction W p
/// [m] of its summed impulse p (sacc, in the sweep's unit) added to u⁺ [m] (un) and to the step's
/// increment (dun), its force p/γ1 [N] kept for reports (sforce: on held DOFs too, which the
/// supports carry), its surface position (sx) refreshed, its sums cleared for the next sweep. Each
/// touched node once: no two items write one node.
template <class T>
PLIANT_HD void soft_correct(const DeviceView<T>& v, const SoftSurface& s, const T* mass, index_t i, T* un,
                            T* dun) {
    double W[3];
    soft_inverse_mass(i, s, mass, W);
    const index_t n = s.node[i];
    const double g1 = double(v.sc->it.g1), unit = v.sc->soft_unit;
    for (int d = 0; d < 3; ++d) {
        const double p = double(v.sacc[3 * i + d]) * unit;
        un[d * v.P + n] = T(double(un[d * v.P + n]) + W[d] * p);
        // The correction adds to the step's increment as computed, not u⁺ − u again: that
        // difference re-rounds the increment on every contact node every step (in float32 it
        // loses the digits the increment keeps; in float64 it destabilized the relaxation
        // of validate's two soft paraboloids, whose 1 ulp disturbances grew).
        dun[d * v.P + n] = T(double(dun[d * v.P + n]) + W[d] * p);
        v.sforce[3 * i + d] += p / g1;
        v.sacc[3 * i + d] = 0;
    }
    soft_position(i, s, v.X, un, v.P, v.sx + 3 * i);
    v.sshare[i] = 0;
}

/// The soft-contact pass of a step: (1) skin test, one thread per surface node (and the surface
/// positions sx), a rebuild of the candidate lists if a surface node moved more than skin/2 since
/// the last one (or the run just started: soft_lists), and the list of the nodes that have candidates; (2)
/// per such node, its contact and impulse (soft_detect; where Dev::kSplitsDetection, a launch before
/// computes its candidates' closest points, one thread each), and per active sharp edge (soft_edge_detect);
/// (3) one team adds the impulses into the nodes, each averaged over the contacts sharing its nodes,
/// and into the step's per-pair forces (soft_gather: fixed point, in any order), then (4) per node
/// touched, the correction W p applied to u⁺ (and sx) and its force p/γ1 kept for reports
/// (soft_correct, on the same team: one launch and one wait fewer a sweep than its own); (2)–(4)
/// repeated kSoftSweeps times, kSoftRelaxSweeps in a relaxation (Jacobi sweeps on the corrected
/// positions), (2) skipped after a sweep that touched nothing. Launch sizes come from the counts
/// the kernels wrote (each_counted, when): the CPU walks only those items.
template <class T, class Dev>
void Engine<T, Dev>::soft_pass(const Phase& ph, bool relaxing) {
    const DeviceView<T> v = v_;
    const SoftSurface s = v.soft;
    const T* mass = relaxing ? v.relax_mass : v.mass;
    const T* uc = v.u[ph.cur];
    T* un = v.u[ph.next];
    T* dun = v.du[ph.next];  // the increment of what the contact moves (node_update)
    dev_.each_then(
        s.n_nodes,
        [=] PLIANT_KERNEL(index_t i) {
            double* x = v.sx + 3 * i;  // kept for the narrow phase (soft_current)
            soft_position(i, s, v.X, un, v.P, x);
            const double* b = v.sb + 3 * i;
            const double d2 =
                (x[0] - b[0]) * (x[0] - b[0]) + (x[1] - b[1]) * (x[1] - b[1]) + (x[2] - b[2]) * (x[2] - b[2]);
            // The smallest node that left its skin (NaN too: rebuild; the check reports it). A
            // minimum is the same whatever order the nodes run in.
            if (!(d2 <= 0.25 * s.skin * s.skin)) atomic_min(&v.sc->soft_moved, i);
            for (int d = 0; d < 3; ++d) v.sforce[3 * i + d] = 0.0;
        },
        [=] PLIANT_KERNEL() {
            Scalars<T>& sc = *v.sc;
            sc.soft_rebuild = sc.soft_due || sc.soft_moved != INT_MAX;
            sc.soft_due = 0;
            sc.soft_moved = INT_MAX;
            if (sc.soft_rebuild) sc.soft_rmax = 0;
        });
    // On the CPU, steps without a rebuild skip its launches.
    dev_.when(&v.sc->soft_rebuild, [&] { soft_lists(un); });
    const int sweeps = relaxing ? kSoftRelaxSweeps : kSoftSweeps;
    for (int sweep = 0; sweep < sweeps; ++sweep) {
        const bool first = sweep == 0;
        const index_t items = s.n_nodes > s.n_edges ? s.n_nodes : s.n_edges;
        if constexpr (Dev::kSplitsDetection)  // (2) split: the closest points, one thread per candidate
            dev_.each_counted(s.n_nodes * kSoftCandidates, first ? &v.sc->soft_lanes : &v.sc->soft_lanes_redo,
                              [=] PLIANT_KERNEL(index_t k) { soft_closest_slot(v, s, k); });
        dev_.each_counted_then_team(
            items, first ? &v.sc->soft_items : &v.sc->soft_redo,
            [=] PLIANT_KERNEL(index_t a) {
                if (a < v.sc->soft_active) soft_detect_active<Dev::kSplitsDetection>(v, s, mass, uc, un, a);
                if (a < v.sc->soft_edges_active)
                    soft_edge_detect(v.eactive[a], s, v.X, mass, uc, v.P, v.sx, v.scand, v.snear, v.erec,
                                     v.erec_w, v.erec_p);
            },
            [=] PLIANT_KERNEL(const typename Dev::Team& team) {
                soft_gather(v, s, first, team);
                team.sync();
                team.each(v.sc->soft_touched,
                          [&](index_t a) { soft_correct(v, s, mass, v.stouched[a], un, dun); });
            });
    }
}

}  // namespace pliant
