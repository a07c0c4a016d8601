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

/// Adds weight w to surface node n's share of the sweep's contacts (sshare: 1 for each contact it
/// is the slave of, its barycentric weight in each it is a triangle node of; 0 again once
/// applied); its first contact lists it in stouched.
template <class T>
PLIANT_HD void soft_count(const DeviceView<T>& v, index_t n, double w) {
    if (v.sshare[n] == 0.0) v.stouched[v.sc->soft_touched++] = n;
    v.sshare[n] += w;
}

/// Step (3) of soft_pass, one thread: the contacts' impulses, averaged over the contacts sharing a
/// node (Macklin et al. 2014 §4.2: each impulse divided by the largest share among its nodes, or by
/// one if that is less (a lone edge contact's weights are below one), the
/// shares counted by barycentric weight, so that a node at the corner of a triangle others hit
/// counts about once, not once per triangle), into sacc (3 per surface node) in node order, and the
/// force each pair's first body received from its second, p/γ1 [N], into the step's history row.
template <class T>
PLIANT_HD void soft_gather(const DeviceView<T>& v, const SoftSurface& s, bool first) {
    Scalars<T>& sc = *v.sc;
    sc.soft_touched = 0;
    for (index_t a = 0; a < sc.soft_active; ++a) {
        const index_t i = v.sactive[a], t = v.srec[i];
        if (t < 0) continue;
        soft_count(v, i, 1.0);
        for (int k = 0; k < 3; ++k)
            if (v.srec_w[3 * i + k] > 0.0) soft_count(v, s.tri[3 * t + k], v.srec_w[3 * i + k]);
    }
    for (index_t q = 0; q < sc.soft_edges_active; ++q) {  // edge–edge contacts: four nodes, weighted
        const index_t e = v.eactive[q], f = soft_edge_partner(v, e);
        if (f < 0) continue;
        const index_t nodes[4] = {s.edge[2 * e], s.edge[2 * e + 1], s.edge[2 * f], s.edge[2 * f + 1]};
        const double w[4] = {1.0 - v.erec_w[2 * e], v.erec_w[2 * e], 1.0 - v.erec_w[2 * e + 1],
                             v.erec_w[2 * e + 1]};
        for (int j = 0; j < 4; ++j) soft_count(v, nodes[j], w[j]);
    }
    double* row = v.hist + sc.row * v.hist_width + 6 * v.n_tools;
    if (first)
        for (index_t k = 0; k < 3 * v.n_pairs; ++k) row[k] = 0.0;
    const double g1 = double(sc.it.g1);
    for (index_t a = 0; a < sc.soft_active; ++a) {
        const index_t i = v.sactive[a], t = v.srec[i];
        if (t < 0) continue;
        const index_t* tri = s.tri + 3 * t;
        double share = v.sshare[i];
        for (int k = 0; k < 3; ++k)
            if (v.srec_w[3 * i + k] > 0.0 && v.sshare[tri[k]] > share) share = v.sshare[tri[k]];
        const index_t la = s.label[i], lb = s.label[tri[0]];
        const index_t pr = s.pair[static_cast<std::size_t>(la) * s.labels + lb];
        const double sign = la <= lb ? 1.0 : -1.0;  // the pair's first body is its lower label
        for (int d = 0; d < 3; ++d) {
            const double p = v.srec_p[3 * i + d] / share;
            v.sacc[3 * i + d] += p;
            for (int k = 0; k < 3; ++k) v.sacc[3 * tri[k] + d] -= v.srec_w[3 * i + k] * p;
            row[3 * pr + d] += sign * p / g1;
        }
    }
    for (index_t q = 0; q < sc.soft_edges_active; ++q) {
        const index_t e = v.eactive[q], f = soft_edge_partner(v, e);
        if (f < 0) continue;
        const index_t nodes[4] = {s.edge[2 * e], s.edge[2 * e + 1], s.edge[2 * f], s.edge[2 * f + 1]};
        const double w[4] = {1.0 - v.erec_w[2 * e], v.erec_w[2 * e], -(1.0 - v.erec_w[2 * e + 1]),
                             -v.erec_w[2 * e + 1]};
        double share = 1.0;  // never below one: a lone contact (weights < 1) gets its whole impulse
        for (int j = 0; j < 4; ++j) share = v.sshare[nodes[j]] > share ? v.sshare[nodes[j]] : share;
        const index_t la = s.label[nodes[0]], lb = s.label[nodes[2]];
        const index_t pr = s.pair[static_cast<std::size_t>(la) * s.labels + lb];
        const double sign = la <= lb ? 1.0 : -1.0;
        for (int d = 0; d < 3; ++d) {
            const double p = v.erec_p[3 * e + d] / share;
            for (int j = 0; j < 4; ++j) v.sacc[3 * nodes[j] + d] += w[j] * p;
            row[3 * pr + d] += sign * p / g1;
        }
    }
    // A sweep after one that moved nothing would find what it found: nothing (soft_pass skips it).
    sc.soft_redo = sc.soft_touched > 0 ? sc.soft_items : 0;
}

/// The soft-contact pass of a step: (1) skin test, one thread per surface node (and the surface
/// positions sx), a rebuild of the candidate lists if a surface node moved more than skin/2 since
/// the last one (or the run just started: soft_lists), and the list of the nodes that have candidates; (2)
/// per such node, its contact and impulse (soft_detect); (3) one thread adds the impulses into the nodes, in
/// node order, each averaged over the contacts sharing its nodes, and into the step's per-pair forces; (4)
/// per node touched, the correction W p applied to u⁺ (and sx) and its force p/γ1 kept for reports; (2)–(4)
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
        dev_.each_counted_then(
            items, first ? &v.sc->soft_items : &v.sc->soft_redo,
            [=] PLIANT_KERNEL(index_t a) {
                if (a < v.sc->soft_active)
                    soft_detect(v.sactive[a], s, v.X, mass, uc, un, v.P, v.sx, v.scand, v.srec, v.srec_w,
                                v.srec_p);
                if (a < v.sc->soft_edges_active)
                    soft_edge_detect(v.eactive[a], s, v.X, mass, uc, v.P, v.sx, v.scand, v.snear, v.erec,
                                     v.erec_w, v.erec_p);
            },
            [=] PLIANT_KERNEL() { soft_gather(v, s, first); });
        dev_.each_counted(s.n_nodes, &v.sc->soft_touched, [=] PLIANT_KERNEL(index_t a) {
            const index_t i = v.stouched[a];
            double W[3];
            soft_inverse_mass(i, s, mass, W);
            const index_t n = s.node[i];
            const double g1 = double(v.sc->it.g1);
            for (int d = 0; d < 3; ++d) {
                const double p = v.sacc[3 * i + d];
                un[d * v.P + n] = T(double(un[d * v.P + n]) + W[d] * p);
                // The correction adds to the step's increment as computed, not u⁺ − u again: that
                // difference re-rounds the increment on every contact node every step (in float32 it
                // loses the digits the increment keeps; in float64 it destabilized the relaxation
                // of validate's two soft paraboloids, whose 1 ulp disturbances grew).
                dun[d * v.P + n] = T(double(dun[d * v.P + n]) + W[d] * p);
                v.sforce[3 * i + d] += W[d] > 0.0 ? p / g1 : 0.0;
                v.sacc[3 * i + d] = 0.0;
            }
            soft_position(i, s, v.X, un, v.P, v.sx + 3 * i);
            v.sshare[i] = 0.0;
        });
    }
}

}  // namespace pliant
