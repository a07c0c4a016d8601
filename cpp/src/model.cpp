// pliant — building the CPU model: AoSoA padding per material group, reference geometry,
// lumped mass, node → element incidence, constraints, loads and the critical time step.
#include "model.hpp"

#include <algorithm>
#include <atomic>
#include <limits>

namespace pliant {

std::uint64_t new_version() {
    static std::atomic<std::uint64_t> counter{0};
    return ++counter;
}

template <class T>
Model<T>::Model(const ModelInput& in) {
    n_nodes = in.n_nodes;
    n_pad = (n_nodes + kLanes - 1) / kLanes * kLanes;
    n_elems = in.n_elems;
    build_groups(in);
    NodeSums sums = build_elements(in);
    build_membranes(in, sums);
    build_masses(in, sums);
    build_incidence(sums.count);
    build_smoothing(in);
    build_loads(in, sums.mass);
    build_pressure(in);
    build_constraints(in);
    build_contact_and_tables(in);
    build_soft_contact(in);
}

/// Material groups; each starts on a fresh block so that a block has a single material.
template <class T>
void Model<T>::build_groups(const ModelInput& in) {
    index_t begin = 0, blocks = 0;
    for (std::size_t g = 0; g < in.group_end.size(); ++g) {
        const index_t end = in.group_end[g];
        const index_t nb = (end - begin + kLanes - 1) / kLanes;
        Group<T> grp{blocks, blocks + nb, {static_cast<MaterialKind>(in.group_kind[g]), {}}, Prony<T>{}};
        for (int k = 0; k < kMaterialParams; ++k)
            grp.material.p[k] = T(in.group_params[kMaterialParams * g + k]);
        if (!in.group_visco.empty()) {
            const double* v = &in.group_visco[(2 + 2 * kPronyMax) * g];
            grp.visco.n_iso = static_cast<int>(v[0]);
            grp.visco.n_vol = static_cast<int>(v[1]);
            for (int k = 0; k < kPronyMax; ++k) {
                grp.visco.alpha[k] = T(v[2 + 2 * k]);
                grp.visco.tau[k] = T(v[3 + 2 * k]);
            }
            visco_terms = std::max(visco_terms, grp.visco.terms());
        }
        groups.push_back(grp);
        for (index_t b = 0; b < nb; ++b) block_group.push_back(static_cast<index_t>(g));
        blocks += nb;
        begin = end;
    }
    n_blocks = blocks;
}

/// Element slots (AoSoA): nodes, reference gradients and volumes, the critical time step; per-node
/// sums of mass, relaxation stiffness and volume, and incidence counts.
template <class T>
typename Model<T>::NodeSums Model<T>::build_elements(const ModelInput& in) {
    const std::size_t P = static_cast<std::size_t>(n_pad);
    const std::size_t S = static_cast<std::size_t>(n_blocks) * kLanes;  // padded element slots
    elem_nodes.assign(4 * S, 0);
    elem_grad.assign(9 * S, T(0));
    elem_vol.assign(S, T(0));
    elem_id.assign(S, -1);
    elem_dt.assign(static_cast<std::size_t>(n_elems), 0.0);
    mass.assign(P, T(0));
    NodeSums sums{std::vector<double>(P, 0.0), std::vector<double>(P, 0.0), std::vector<double>(P, 0.0),
                  std::vector<index_t>(n_nodes + 1, 0)};
    std::vector<double>&mass_d = sums.mass, &stiff_d = sums.stiff, &vol_d = sums.vol;
    std::vector<index_t>& count = sums.count;

    index_t begin = 0;
    for (std::size_t g = 0; g < groups.size(); ++g) {
        const index_t end = in.group_end[g];
        const index_t first_slot = groups[g].block_begin * kLanes;
        MaterialParams<double> md{groups[g].material.kind, {}};
        for (int k = 0; k < kMaterialParams; ++k) md.p[k] = in.group_params[kMaterialParams * g + k];
        const double modulus = with_material(md, [](auto m) { return m.dilatational_modulus(); });
        for (index_t e = begin; e < end; ++e) {
            const index_t s = first_slot + (e - begin);
            double X[4][3], grad[4][3], vol, alt;
            for (int a = 0; a < 4; ++a) {
                const index_t n = in.tets[4 * e + a];
                elem_nodes[aosoa(s / kLanes, s % kLanes, a, 4)] = n;
                ++count[n + 1];
                for (int d = 0; d < 3; ++d) X[a][d] = in.X[3 * n + d];
            }
            tet_reference(X, grad, vol, alt);
            if (!(vol > 0.0))
                throw std::invalid_argument("element " + std::to_string(e) +
                                            " has non-positive reference volume");
            for (int a = 0; a < 3; ++a)
                for (int d = 0; d < 3; ++d)
                    elem_grad[aosoa(s / kLanes, s % kLanes, 3 * a + d, 9)] = T(grad[a][d]);
            elem_vol[s] = T(vol);
            elem_id[s] = e;
            const double rho = in.density[e];
            for (int a = 0; a < 4; ++a) {
                mass_d[in.tets[4 * e + a]] += rho * vol / 4.0;
                vol_d[in.tets[4 * e + a]] += vol;
                stiff_d[in.tets[4 * e + a]] += modulus * vol / (alt * alt) / 4.0;  // ρ' Δt_c⁻²
            }
            const double dt_e = alt / std::sqrt(modulus / rho);
            elem_dt[e] = dt_e;
            if (dt_critical_elem < 0 || dt_e < dt_critical) {
                dt_critical = dt_e;
                dt_critical_elem = e;
            }
        }
        begin = end;
    }
    return sums;
}

/// Membrane triangles (membrane.hpp): reference tangents, inverse metric and moduli times the
/// reference area; each corner's lumped mass ρ h A0 / 3 and relaxation stiffness; each membrane's
/// critical step, its smallest altitude over the plane-stress wave speed √(M / ρ), M = E / (1 − ν²)
/// (St Venant–Kirchhoff) or 4 μ (incompressible Neo-Hookean: E = 3 μ, ν = ½; M = 0 on a sheet that
/// only bends: bending alone sets its step), which may lower
/// dt_critical; the node → corner incidence (ordered by membrane: a fixed summation order).
template <class T>
void Model<T>::build_membranes(const ModelInput& in, NodeSums& sums) {
    const index_t nm = static_cast<index_t>(in.mem_kind.size());
    if (in.mem_nodes.size() != 3 * static_cast<std::size_t>(nm) ||
        in.mem_params.size() != kMembraneParams * static_cast<std::size_t>(nm))
        throw std::invalid_argument("membranes: expected 3 nodes and 5 parameters per membrane");
    const bool bending = !in.mem_nbrs.empty() || !in.mem_bend.empty();
    if (bending && (in.mem_nbrs.size() != kMembraneNbrs * static_cast<std::size_t>(nm) ||
                    in.mem_bend.size() != 2 * static_cast<std::size_t>(nm)))
        throw std::invalid_argument(
            "membranes: expected 9 patch nodes and 2 bending parameters per membrane");
    mem_nodes = in.mem_nodes;
    mem_kind.assign(in.mem_kind.begin(), in.mem_kind.end());
    mem_geom.assign(static_cast<std::size_t>(kMembraneValues) * nm, T(0));
    mem_nbrs = in.mem_nbrs;
    mem_bend.assign(bending ? static_cast<std::size_t>(kBendValues) * nm : 0, T(0));
    mem_dt.assign(nm, 0.0);
    std::vector<index_t> count(static_cast<std::size_t>(n_nodes) + 1, 0);
    for (index_t m = 0; m < nm; ++m) {
        const double* p = &in.mem_params[kMembraneParams * static_cast<std::size_t>(m)];
        const double h = p[0], rho = p[1];
        const bool nh = in.mem_kind[m] == static_cast<int>(MembraneKind::NeoHookean);
        const double* pb = bending ? &in.mem_bend[2 * static_cast<std::size_t>(m)] : nullptr;
        const bool bends = pb != nullptr && pb[0] != 0.0;
        const bool ok =
            h > 0.0 && rho > 0.0 && std::isfinite(h * rho) && (p[2] > 0.0 || (p[2] == 0.0 && bends)) &&
            std::isfinite(p[2]) && (nh || (p[3] > -1.0 && p[3] <= 0.5)) && (p[4] == 0.0 || p[4] == 1.0) &&
            (pb == nullptr || (pb[0] >= 0.0 && std::isfinite(pb[0]) && pb[1] > -1.0 && pb[1] <= 0.5));
        if (!ok || (!nh && in.mem_kind[m] != static_cast<int>(MembraneKind::StVenantKirchhoff)))
            throw std::invalid_argument("membrane " + std::to_string(m) +
                                        ": kind or parameters out of range");
        for (int a = 0; a < 3; ++a)
            if (in.mem_nodes[3 * m + a] < 0 || in.mem_nodes[3 * m + a] >= n_nodes)
                throw std::invalid_argument("membrane " + std::to_string(m) +
                                            " refers to a node out of range");
        double G[2][3], X0[3];
        for (int d = 0; d < 3; ++d) X0[d] = in.X[3 * in.mem_nodes[3 * m] + d];
        for (int i = 0; i < 2; ++i)
            for (int d = 0; d < 3; ++d) G[i][d] = in.X[3 * in.mem_nodes[3 * m + 1 + i] + d] - X0[d];
        double g11 = 0.0, g22 = 0.0, g12 = 0.0, e3 = 0.0;
        for (int d = 0; d < 3; ++d)
            g11 += G[0][d] * G[0][d], g22 += G[1][d] * G[1][d], g12 += G[0][d] * G[1][d];
        for (int d = 0; d < 3; ++d) e3 += (G[1][d] - G[0][d]) * (G[1][d] - G[0][d]);
        const double det = g11 * g22 - g12 * g12;
        const double longest = std::sqrt(std::max({g11, g22, e3}));
        if (!(det > 1e-16 * longest * longest * longest * longest))
            throw std::invalid_argument("membrane " + std::to_string(m) + " is degenerate (zero area)");
        const double area = 0.5 * std::sqrt(det), alt = 2.0 * area / longest;
        T* q = &mem_geom[static_cast<std::size_t>(kMembraneValues) * m];
        for (int i = 0; i < 2; ++i)
            for (int d = 0; d < 3; ++d) q[3 * i + d] = T(G[i][d]);
        q[6] = T(g22 / det), q[7] = T(g11 / det), q[8] = T(-g12 / det);
        const double E = p[2], nu = p[3];
        const double mu = nh ? E : E / (2.0 * (1.0 + nu)), lam = nh ? 0.0 : E * nu / (1.0 - nu * nu);
        q[9] = T(area * h * (nh ? mu : lam)), q[10] = T(nh ? 0.0 : area * h * mu);
        q[11] = T(p[4] == 0.0 ? 0.0 : area * h * (nh ? mu : E));  // the wrinkled state's modulus
        const double modulus = nh ? 4.0 * mu : lam + 2.0 * mu;
        const double dt_plane = modulus > 0.0 ? alt / std::sqrt(modulus / rho)            // in-plane waves
                                              : std::numeric_limits<double>::infinity();  // only bends
        const double w_bend = bends ? build_bending(in, m, area, alt, sums) : 0.0;        // ω_max of bending
        const double dt_m = 1.0 / std::sqrt(1.0 / (dt_plane * dt_plane) + 0.25 * w_bend * w_bend);
        mem_dt[m] = dt_m;
        if (dt_critical_elem < 0 || dt_m < dt_critical) {
            dt_critical = dt_m;
            dt_critical_membrane = m;
        }
        for (int a = 0; a < 3; ++a) {
            const index_t n = in.mem_nodes[3 * m + a];
            sums.mass[n] += rho * h * area / 3.0;
            sums.stiff[n] += rho * h * area / (dt_plane * dt_plane) / 3.0;  // ρ' Δt_c⁻², an element's
            ++count[n + 1];
        }
    }
    auto patch = [&](index_t m, int k) {  // patch node k of a bending membrane, or −1
        return bending && in.mem_bend[2 * m] != 0.0
                   ? in.mem_nbrs[kMembraneNbrs * static_cast<std::size_t>(m) + k]
                   : kFreeEdge;
    };
    for (index_t m = 0; m < nm; ++m)
        for (int k = 0; k < kMembraneNbrs; ++k)
            if (patch(m, k) >= 0) ++count[patch(m, k) + 1];
    for (index_t n = 0; n < n_nodes; ++n) count[n + 1] += count[n];
    mem_offsets.assign(count.begin(), count.end());
    mem_index.assign(static_cast<std::size_t>(count[n_nodes]), 0);
    std::vector<index_t> fill(count.begin(), count.end() - 1);
    for (index_t m = 0; m < nm; ++m)
        for (int s = 0; s < kMembraneSlots; ++s) {
            const index_t n = s < 3 ? in.mem_nodes[3 * m + s] : patch(m, s - 3);
            if (n >= 0) mem_index[fill[n]++] = kMembraneSlots * m + s;
        }
}

/// Lumped and relaxation masses; nodal volumes for T4ANP (which needs decoupled, elastic groups).
template <class T>
void Model<T>::build_masses(const ModelInput& in, const NodeSums& sums) {
    const std::size_t P = static_cast<std::size_t>(n_pad);
    const std::vector<double>&mass_d = sums.mass, &stiff_d = sums.stiff, &vol_d = sums.vol;
    anp = in.anp;
    if (!(in.stiffness_damping >= 0.0 && std::isfinite(in.stiffness_damping)))
        throw std::invalid_argument("stiffness damping must be finite and >= 0 [s]");
    stiffness_damping = in.stiffness_damping;
    if (!(in.anp_stabilization >= 0.0 && in.anp_stabilization <= 1.0))
        throw std::invalid_argument("the T4ANP stabilization must be between 0 and 1");
    anp_stabilization = in.anp_stabilization;
    anp_shear = in.anp_shear;
    if (anp && visco_terms > 0)
        throw std::invalid_argument(
            "average nodal pressure (T4ANP) and viscoelastic materials "
            "cannot be combined yet");
    if (anp) {
        for (const Group<T>& g : groups)
            if (!with_material(g.material, [](const auto& m) { return m.decoupled; }))
                throw std::invalid_argument(
                    "average nodal pressure (T4ANP) needs decoupled "
                    "materials (a separate volumetric term)");
        node_volume.assign(P, T(0));
        for (std::size_t n = 0; n < P; ++n) node_volume[n] = T(vol_d[n] > 0.0 ? vol_d[n] : 1.0);
    }
    inv_mass.assign(P, T(0));
    relax_mass.assign(P, T(0));
    relax_inv_mass.assign(P, T(0));
    for (std::size_t n = 0; n < P; ++n) {
        mass[n] = T(mass_d[n]);
        inv_mass[n] = mass_d[n] > 0.0 ? T(1.0 / mass_d[n]) : T(0);
        const double mr = stiff_d[n] * dt_critical * dt_critical;  // ρ' = M Δt_c² / h² per element
        relax_mass[n] = T(mr);
        relax_inv_mass[n] = mr > 0.0 ? T(1.0 / mr) : T(0);
    }
}

/// Node → (element slot, corner) incidence, ordered by slot: a fixed summation order.
template <class T>
void Model<T>::build_incidence(std::vector<index_t> count) {
    const std::size_t S = static_cast<std::size_t>(n_blocks) * kLanes;
    for (index_t n = 0; n < n_nodes; ++n) count[n + 1] += count[n];
    inc_offsets.assign(count.begin(), count.end());
    inc_index.assign(static_cast<std::size_t>(count[n_nodes]), 0);
    // T4ANP's nodal average (nodal_pressure) reads element values, one per slot: each incidence's
    // slot, beside its force offset
    inc_slot.assign(anp ? inc_index.size() : 0, 0);
    std::vector<index_t> fill(count.begin(), count.end() - 1);
    for (std::size_t s = 0; s < S; ++s) {
        if (elem_id[s] < 0) continue;
        for (int a = 0; a < 4; ++a) {
            const index_t n = elem_nodes[aosoa(static_cast<index_t>(s / kLanes), s % kLanes, a, 4)];
            if (anp) inc_slot[fill[n]] = static_cast<index_t>(s);
            inc_index[fill[n]++] = corner_force(static_cast<index_t>(s / kLanes), s % kLanes, a);
        }
    }
}

/// Edge smoothing domains (smoothing.hpp): every (group, edge) with its elements, weights
/// (V_e/6)/V_k and each slot's six edges; numbered by group, then by node pair (locality); each
/// group's edges padded to whole blocks of kLanes (one material per block of the SIMD pass).
template <class T>
void Model<T>::build_smoothing(const ModelInput& in) {
    smoothing = in.smoothing;
    if (smoothing == StrainSmoothing::Element) return;
    struct Inc {
        index_t group, n0, n1, slot;
        int local;
    };
    static constexpr int kEdge[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
    const std::size_t S = static_cast<std::size_t>(n_blocks) * kLanes;
    std::vector<Inc> inc;
    inc.reserve(6 * static_cast<std::size_t>(n_elems));
    for (std::size_t s = 0; s < S; ++s) {
        if (elem_id[s] < 0) continue;
        const index_t b = static_cast<index_t>(s / kLanes);
        const int l = static_cast<int>(s % kLanes);
        for (int j = 0; j < 6; ++j) {
            const index_t p = elem_nodes[aosoa(b, l, kEdge[j][0], 4)],
                          q = elem_nodes[aosoa(b, l, kEdge[j][1], 4)];
            inc.push_back({block_group[b], std::min(p, q), std::max(p, q), static_cast<index_t>(s), j});
        }
    }
    std::sort(inc.begin(), inc.end(), [](const Inc& a, const Inc& b) {
        if (a.group != b.group) return a.group < b.group;
        if (a.n0 != b.n0) return a.n0 < b.n0;
        if (a.n1 != b.n1) return a.n1 < b.n1;
        return a.slot < b.slot;
    });
    elem_edges.assign(6 * S, 0);
    edge_slot.resize(inc.size());
    edge_w.resize(inc.size());
    edge_off.assign(1, 0);
    group_edge_begin.assign(groups.size() + 1, 0);
    for (std::size_t i = 0; i < inc.size();) {
        std::size_t j = i;
        double vk = 0.0;
        for (; j < inc.size() && inc[j].group == inc[i].group && inc[j].n0 == inc[i].n0 &&
               inc[j].n1 == inc[i].n1;
             ++j)
            vk += double(elem_vol[inc[j].slot]);
        const index_t k = static_cast<index_t>(edge_off.size() - 1);
        for (std::size_t r = i; r < j; ++r) {
            const index_t s = inc[r].slot;
            edge_slot[r] = s;
            edge_w[r] = T(double(elem_vol[s]) / vk);  // (V_e/6) / Σ (V_e/6)
            elem_edges[aosoa(s / kLanes, s % kLanes, inc[r].local, 6)] = k;
        }
        edge_group.push_back(inc[i].group);
        edge_off.push_back(static_cast<index_t>(j));
        if (j == inc.size() || inc[j].group != inc[i].group) {  // a group's edges fill whole blocks
            while (edge_group.size() % kLanes) {
                edge_group.push_back(inc[i].group);
                edge_off.push_back(static_cast<index_t>(j));  // no elements: H̄ = 0, never gathered
            }
            group_edge_begin[static_cast<std::size_t>(inc[i].group) + 1] =
                static_cast<index_t>(edge_group.size());
        }
        i = j;
    }
    if (edge_group.size() > static_cast<std::size_t>(INT32_MAX / 9))  // 9 k must fit an index_t
        throw std::invalid_argument("too many edges for edge-smoothed strain (" +
                                    std::to_string(edge_group.size()) + "; at most " +
                                    std::to_string(INT32_MAX / 9) + ")");
    n_edges = static_cast<index_t>(edge_group.size());
    for (std::size_t g = 1; g < group_edge_begin.size(); ++g)  // groups without elements
        group_edge_begin[g] = std::max(group_edge_begin[g], group_edge_begin[g - 1]);
}

/// Load patterns (K, N, 3) → (K, 3, P), and gravity as one more pattern (m_a g).
template <class T>
void Model<T>::build_loads(const ModelInput& in, const std::vector<double>& mass_d) {
    const std::size_t P = static_cast<std::size_t>(n_pad);
    pattern_curve = in.pattern_curve;
    load_patterns.assign(static_cast<std::size_t>(in.n_patterns) * 3 * P, T(0));
    for (int k = 0; k < in.n_patterns; ++k)
        for (index_t n = 0; n < n_nodes; ++n)
            for (int d = 0; d < 3; ++d)
                load_patterns[(static_cast<std::size_t>(k) * 3 + d) * P + n] =
                    T(in.patterns[(static_cast<std::size_t>(k) * n_nodes + n) * 3 + d]);

    if (in.gravity_curve >= 0) {  // body force ρg lumped like the mass: m_a·g
        const std::size_t k = pattern_curve.size();
        pattern_curve.push_back(in.gravity_curve);
        load_patterns.resize((k + 1) * 3 * P, T(0));
        for (int d = 0; d < 3; ++d)
            for (index_t n = 0; n < n_nodes; ++n)
                load_patterns[(k * 3 + d) * P + n] = T(mass_d[n] * in.gravity[d]);
    }
    n_load_patterns = static_cast<int>(pattern_curve.size());
}

/// Follower pressure and surface traction: one pattern-factor slot per distinct curve, reference
/// edges, node → face CSR in face order (a fixed summation order).
template <class T>
void Model<T>::build_pressure(const ModelInput& in) {
    const index_t nf = static_cast<index_t>(in.press_value.size());
    press_nodes = in.press_nodes;
    press_value.resize(nf);
    press_slot.resize(nf);
    press_edges.resize(6 * static_cast<std::size_t>(nf));
    press_traction.assign(3 * static_cast<std::size_t>(nf), T(0));
    if (in.press_traction.size() == 3 * static_cast<std::size_t>(nf))
        for (std::size_t k = 0; k < press_traction.size(); ++k) press_traction[k] = T(in.press_traction[k]);
    pface_offsets.assign(static_cast<std::size_t>(n_nodes) + 1, 0);
    for (index_t f = 0; f < nf; ++f) {
        press_value[f] = T(in.press_value[f]);
        const index_t c = in.press_curve[f];
        index_t slot = n_load_patterns;
        while (slot < static_cast<index_t>(pattern_curve.size()) && pattern_curve[slot] != c) ++slot;
        if (slot == static_cast<index_t>(pattern_curve.size())) pattern_curve.push_back(c);
        press_slot[f] = slot;
        const index_t* v = &press_nodes[3 * f];
        for (int d = 0; d < 3; ++d) {
            press_edges[6 * f + d] = T(in.X[3 * v[1] + d] - in.X[3 * v[0] + d]);
            press_edges[6 * f + 3 + d] = T(in.X[3 * v[2] + d] - in.X[3 * v[0] + d]);
        }
        for (int a = 0; a < 3; ++a) ++pface_offsets[v[a] + 1];
    }
    for (index_t n = 0; n < n_nodes; ++n) pface_offsets[n + 1] += pface_offsets[n];
    pface_index.assign(static_cast<std::size_t>(pface_offsets[n_nodes]), 0);
    {
        std::vector<index_t> fill(pface_offsets.begin(), pface_offsets.end() - 1);
        for (index_t f = 0; f < nf; ++f)
            for (int a = 0; a < 3; ++a) pface_index[fill[press_nodes[3 * f + a]]++] = f;
    }
}

/// Prescribed DOFs sorted by node (values, curves, per-node offsets) and the free-DOF mask.
template <class T>
void Model<T>::build_constraints(const ModelInput& in) {
    const std::size_t P = static_cast<std::size_t>(n_pad);
    free_mask.assign(3 * P, T(1));
    std::vector<std::size_t> order(in.cons_node.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::stable_sort(order.begin(), order.end(),
                     [&](std::size_t a, std::size_t b) { return in.cons_node[a] < in.cons_node[b]; });
    cons_offsets.assign(static_cast<std::size_t>(n_nodes) + 1, 0);
    for (std::size_t i : order) {
        const index_t dof = in.cons_dim[i] * n_pad + in.cons_node[i];
        cons_dof.push_back(dof);
        cons_value.push_back(T(in.cons_value[i]));
        cons_curve.push_back(in.cons_curve[i]);
        free_mask[dof] = T(0);
        ++cons_offsets[in.cons_node[i] + 1];
    }
    for (index_t n = 0; n < n_nodes; ++n) cons_offsets[n + 1] += cons_offsets[n];
}

/// Reference positions, contact nodes with their free-DOF and tool bits, tools, curves and tables
/// (never empty, so that device copies have an address).
template <class T>
void Model<T>::build_contact_and_tables(const ModelInput& in) {
    X.assign(in.X, in.X + 3 * static_cast<std::size_t>(n_nodes));
    contact_nodes = in.contact_nodes;
    contact_skin = in.contact_skin.empty() ? std::vector<double>(contact_nodes.size(), 0.0) : in.contact_skin;
    if (contact_skin.size() != contact_nodes.size())
        throw std::invalid_argument("contact_skin: expected one value per contact node");
    for (const double s : contact_skin)
        if (!(s >= 0.0 && std::isfinite(s)))
            throw std::invalid_argument("contact_skin: expected finite values >= 0 [m]");
    if (contact_skin.empty()) contact_skin.push_back(0.0);  // (an address for the device copy)
    contact_bits.assign(contact_nodes.size(), 0);
    for (std::size_t i = 0; i < contact_nodes.size(); ++i) {
        contact_bits[i] = node_bits(in.contact_masks.empty() ? ~index_t(0) : in.contact_masks[i]);
        for (int d = 0; d < 3; ++d)
            if (free_mask[d * n_pad + contact_nodes[i]] == T(0)) contact_bits[i] &= ~(index_t(1) << d);
    }
    tools = in.tools;
    tool_keys = in.tool_keys;
    tool_grid = in.tool_grid;
    if (tool_grid.empty()) tool_grid.push_back(0.0);
    tool_grips = in.tool_grips;
    curves = in.curves;
    if (curves.empty()) curves.push_back({CurveKind::Constant, 0.0, 0.0, 0, 0});
    table_t = in.table_t;
    table_v = in.table_v;
    if (table_t.empty()) {
        table_t.push_back(0.0);
        table_v.push_back(0.0);
    }
}

/// The soft-contact surface (soft_contact.hpp), checked: its nodes' free-DOF bits, each triangle's
/// mean reference edge, the grid's cell (the longest reference edge, at least the skin) and a hash
/// table of at least twice as many buckets as triangles.
template <class T>
void Model<T>::build_soft_contact(const ModelInput& in) {
    const std::size_t ns = in.soft_nodes.size(), nt = in.soft_tris.size() / 3;
    const std::size_t L = static_cast<std::size_t>(in.soft_labels);
    if (ns == 0) return;
    if (in.soft_label.size() != ns || in.soft_tris.size() % 3 || in.soft_pair.size() != L * L ||
        !(in.soft_skin > 0.0) || (!in.soft_sheet_h.empty() && in.soft_sheet_h.size() != L))
        throw std::invalid_argument("soft contact: inconsistent surface arrays");
    for (double h : in.soft_sheet_h)
        if (!(h >= 0.0 && std::isfinite(h)))
            throw std::invalid_argument("soft contact: a sheet's half thickness must be finite and >= 0");
    for (std::size_t i = 0; i < ns; ++i)
        if (in.soft_nodes[i] < 0 || in.soft_nodes[i] >= n_nodes || in.soft_label[i] < 0 ||
            in.soft_label[i] >= in.soft_labels)
            throw std::invalid_argument("soft contact: surface node " + std::to_string(i) + " out of range");
    for (index_t v : in.soft_tris)
        if (v < 0 || static_cast<std::size_t>(v) >= ns)
            throw std::invalid_argument("soft contact: a triangle names surface node " + std::to_string(v));
    index_t pairs = 0;
    for (index_t p : in.soft_pair) pairs = p + 1 > pairs ? p + 1 : pairs;
    if (in.soft_mu.size() != 2 * static_cast<std::size_t>(pairs))
        throw std::invalid_argument("soft contact: expected μs and μk for each of " + std::to_string(pairs) +
                                    " pairs");
    soft_nodes = in.soft_nodes, soft_label = in.soft_label, soft_tris = in.soft_tris;
    soft_pair = in.soft_pair, soft_mu = in.soft_mu, soft_labels = in.soft_labels, soft_pairs = pairs;
    soft_skin = in.soft_skin;
    soft_sheet_h = in.soft_sheet_h.empty() ? std::vector<double>(L, 0.0) : in.soft_sheet_h;
    soft_bits.assign(ns, 0);
    for (std::size_t i = 0; i < ns; ++i)
        for (int d = 0; d < 3; ++d)
            if (free_mask[d * n_pad + soft_nodes[i]] != T(0)) soft_bits[i] |= index_t(1) << d;
    soft_tri_h.assign(nt, 0.0);
    double longest = 0.0;
    for (std::size_t t = 0; t < nt; ++t) {
        for (int k = 0; k < 3; ++k) {
            const index_t a = soft_nodes[soft_tris[3 * t + k]],
                          b = soft_nodes[soft_tris[3 * t + (k + 1) % 3]];
            double e2 = 0.0;
            for (int d = 0; d < 3; ++d) e2 += (X[3 * a + d] - X[3 * b + d]) * (X[3 * a + d] - X[3 * b + d]);
            soft_tri_h[t] += std::sqrt(e2) / 3.0;
            longest = std::sqrt(e2) > longest ? std::sqrt(e2) : longest;
        }
    }
    // The farthest a contact's closest point lies: the band and a sheet's half thickness, and the
    // half thickness of the sheet the node is on (soft_detect).
    soft_band = 0.0;
    double thickest = 0.0;
    for (std::size_t t = 0; t < nt; ++t) {
        const double h = soft_sheet_h[soft_label[soft_tris[3 * t]]];
        const double b = kSoftBehind * soft_tri_h[t] + h;
        soft_band = b > soft_band ? b : soft_band;
        thickest = h > thickest ? h : thickest;
    }
    soft_band += thickest;
    // A triangle's bounding radius is at most 2/3 of its longest edge, so with cells this large the
    // candidates of an undeformed surface lie in the 27 cells around a node (soft_candidates' reach).
    const double reach = 2.0 / 3.0 * longest + soft_skin + soft_band;
    soft_cell = longest > reach ? longest : reach;
    build_soft_adjacency();
    build_soft_edges();
    std::size_t H = 1;
    while (H < 2 * nt) H *= 2;
    soft_hash_mask = static_cast<index_t>(H - 1);
}

/// Each surface node's triangles, ascending, in CSR form (soft_vtri_off, soft_vtri): the
/// neighbourhood self contact skips (soft_adjacent) and the faces around a vertex or an edge whose
/// pseudo-normal tells inside from outside (soft_pseudo_normal).
template <class T>
void Model<T>::build_soft_adjacency() {
    const std::size_t ns = soft_nodes.size(), nt = soft_tris.size() / 3;
    soft_vtri_off.assign(ns + 1, 0);
    for (index_t v : soft_tris) ++soft_vtri_off[static_cast<std::size_t>(v) + 1];
    for (std::size_t i = 0; i < ns; ++i) soft_vtri_off[i + 1] += soft_vtri_off[i];
    soft_vtri.resize(3 * nt);
    std::vector<index_t> fill(soft_vtri_off.begin(), soft_vtri_off.end() - 1);
    for (std::size_t t = 0; t < nt; ++t)  // triangles in order: each node's list ascends
        for (int k = 0; k < 3; ++k) soft_vtri[fill[soft_tris[3 * t + k]]++] = static_cast<index_t>(t);
}

/// The sharp edges of the contact surface (soft_edges), those where its two triangles' reference
/// normals differ by more than acos(kSoftSharpCos), and each triangle's edges among them
/// (soft_tri_edge): the edges the edge–edge test watches (soft_edge_detect).
template <class T>
void Model<T>::build_soft_edges() {
    const std::size_t nt = soft_tris.size() / 3;
    auto normal = [&](std::size_t t, double n[3]) {
        double v[3][3];
        for (int k = 0; k < 3; ++k)
            for (int d = 0; d < 3; ++d) v[k][d] = X[3 * soft_nodes[soft_tris[3 * t + k]] + d];
        const double e0[3] = {v[1][0] - v[0][0], v[1][1] - v[0][1], v[1][2] - v[0][2]};
        const double e1[3] = {v[2][0] - v[0][0], v[2][1] - v[0][1], v[2][2] - v[0][2]};
        n[0] = e0[1] * e1[2] - e0[2] * e1[1];
        n[1] = e0[2] * e1[0] - e0[0] * e1[2];
        n[2] = e0[0] * e1[1] - e0[1] * e1[0];
        const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (int d = 0; d < 3; ++d) n[d] = len > 0.0 ? n[d] / len : 0.0;
    };
    struct Half {
        index_t a, b, t, k;
    };
    std::vector<Half> half;
    half.reserve(3 * nt);
    for (std::size_t t = 0; t < nt; ++t)
        for (int k = 0; k < 3; ++k) {
            const index_t a = soft_tris[3 * t + k], b = soft_tris[3 * t + (k + 1) % 3];
            half.push_back({a < b ? a : b, a < b ? b : a, static_cast<index_t>(t), k});
        }
    std::sort(half.begin(), half.end(), [](const Half& p, const Half& q) {
        return p.a != q.a ? p.a < q.a : (p.b != q.b ? p.b < q.b : p.t < q.t);
    });
    soft_edges.clear();
    soft_tri_edge.assign(3 * nt, -1);
    for (std::size_t i = 0; i < half.size();) {
        std::size_t j = i;
        while (j < half.size() && half[j].a == half[i].a && half[j].b == half[i].b) ++j;
        const bool sheet = soft_sheet_h[soft_label[half[i].a]] > 0.0;
        if (sheet && j - i == 1) {  // a sheet's boundary: no contact beside it (soft_sheet_target)
            soft_tri_edge[3 * half[i].t + half[i].k] = kSoftSheetEdge;
            soft_bits[half[i].a] |= kSoftSheetRim;
            soft_bits[half[i].b] |= kSoftSheetRim;
        } else if (!sheet && j - i == 2) {  // a manifold edge: sharp if its faces meet at an angle
            double n0[3], n1[3];
            normal(static_cast<std::size_t>(half[i].t), n0);
            normal(static_cast<std::size_t>(half[i + 1].t), n1);
            if (n0[0] * n1[0] + n0[1] * n1[1] + n0[2] * n1[2] < kSoftSharpCos) {
                const index_t e = static_cast<index_t>(soft_edges.size() / 2);
                soft_edges.push_back(half[i].a);
                soft_edges.push_back(half[i].b);
                for (std::size_t q = i; q < j; ++q) soft_tri_edge[3 * half[q].t + half[q].k] = e;
            }
        }
        i = j;
    }
}

template <class T>
std::size_t Model<T>::bytes() const {
    auto b = [](const auto& v) { return v.size() * sizeof(v[0]); };
    return b(elem_nodes) + b(elem_grad) + b(elem_vol) + b(elem_id) + b(block_group) + b(inc_offsets) +
           b(inc_index) + b(inc_slot) + b(mass) + b(inv_mass) + b(relax_mass) + b(relax_inv_mass) +
           b(node_volume) + b(free_mask) + b(pface_offsets) + b(pface_index) + b(press_nodes) +
           b(press_slot) + b(press_edges) + b(press_value) + b(press_traction) + b(load_patterns) +
           b(cons_dof) + b(cons_value) + b(cons_curve) + b(cons_offsets) + b(edge_off) + b(edge_slot) +
           b(edge_group) + b(elem_edges) + b(edge_w) + b(mem_offsets) + b(mem_index) + b(mem_nodes) +
           b(mem_kind) + b(mem_nbrs) + b(mem_geom) + b(mem_bend);
}

template struct Model<float>;
template struct Model<double>;

}  // namespace pliant
