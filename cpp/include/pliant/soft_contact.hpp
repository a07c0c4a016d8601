// pliant — contact between deformable surfaces (two bodies, or one body with itself), header-only,
// host and device.
//
// Node-to-triangle, kinematic, after the explicit predictor and the tool contact (the approach of
// NiftySim's deformable contact: Johnsen et al. 2015, IJCARS 10:1077, §2.4, after Taylor, Cheng &
// Ourselin 2008): a surface node found inside another body (or inside its own body, away from its
// neighbourhood) is moved back onto its closest point on that body's surface, and the nodes of the
// triangle holding that point are moved the other way. Inside or outside is told by the angle-
// weighted pseudo-normal at the closest point (Bærentzen & Aanæs 2005), so that a node at an edge
// or a corner of the other surface is pushed towards it, not along one face's normal and then the
// other's. Sharp edges of different bodies that crossed each other between nodes are put back in
// touch the same way (soft_edge_detect). One position impulse p [kg·m] per contact, split by inverse mass and
// barycentric weight (slave Δx_s = W_s p, triangle node j: Δx_j = −w_j W_j p, W = diag of free-DOF inverse
// masses), so that Σ m Δx = 0: the pair conserves linear momentum (Heinstein, Mello, Attaway &
// Laursen 2000, CMAME 187:621, §3: mass-weighted kinematic contact). Friction: Coulomb in
// displacement form as for the tools (contact.hpp), on the relative tangential motion over the step.
// Contacts sharing a node are averaged (each impulse divided by the largest number of contacts
// any of its four nodes takes part in, at least one: Macklin et al. 2014, ACM TOG 33(4):153, §4.2), which
// keeps the Jacobi update from closing a gap twice; what is left is closed at the next steps.
//
// Broad phase: a Verlet list. Every surface node keeps up to kSoftCandidates triangles that lie
// within `skin` plus the triangle's contact band of it (soft_candidates), found through a hashed
// uniform grid of triangle centroids; the lists are rebuilt when some surface node has moved more
// than skin/2 since the last build (then no triangle can come within its band of a node that does
// not list it), and at the start of every run.
#pragma once

#include <cmath>

#include "tled.hpp"

namespace pliant {

/// Triangles a surface node keeps as contact candidates (the nearest by bounding-sphere distance).
constexpr int kSoftCandidates = 32;
/// A node inside a body counts as a contact only if its closest point on that body's surface lies
/// within this fraction of the triangle's mean edge (a node that went deeper than that in one step
/// is lost; self contact: the nearest triangles that are not the node's neighbours lie about an
/// edge away, farther than this band, so the node's own surface at a convex edge is no contact).
constexpr double kSoftBehind = 0.25;
/// Most grid cells searched in each direction around a node (a blown-up mesh stops at this).
constexpr int kSoftReach = 8;
/// Jacobi sweeps of the soft-contact response per step, each detecting on the positions the last
/// one corrected; what the averaging leaves of a gap is closed at the next steps. Measured (1 / 2 /
/// 3 sweeps): the deepest node in two blocks colliding at 1 m/s 0.18 % / 0.04 % / 0 of an element;
/// a stiff cut column at rest on its cut, its fastest node 0.1–0.24 / 0.05–0.09 / 0.02–0.06 m/s;
/// contact's share of the step on examples/organs_contact.toml 21 / 26 / 32 % (2 threads).
constexpr int kSoftSweeps = 2;
/// Sweeps per step in a dynamic relaxation, whose residual wants each step's contact closed within
/// the step (a block resting on another, μ = 0.5: converged to 3e-6 in 90 steps with three; one
/// stalls at 2e-4).
constexpr int kSoftRelaxSweeps = 3;
/// A surface edge is sharp, and watched by the edge–edge test, where its two faces' reference
/// normals differ by more than 40° (cos 40°): at such edges two surfaces can cross edge through edge
/// with no node going through a face (two blocks' edges, thin parts); smooth regions are covered by
/// the nodes.
constexpr double kSoftSharpCos = 0.766;

/// A sheet of membranes (two-sided, SoftSurface::sheet_h > 0) marks its boundary: each triangle's
/// boundary edge in tri_edge, and its nodes on the boundary in bits (beside the DOF bits 0–2). A
/// node whose closest point on a sheet lies on that boundary meets the sheet's rounded rim
/// (soft_sheet_target).
constexpr index_t kSoftSheetEdge = -2;
constexpr index_t kSoftSheetRim = 8;

/// The contact surface and its settings, as device pointers (trivially copyable).
struct SoftSurface {
    index_t n_nodes = 0, n_tris = 0, labels = 0, hash_mask = 0;
    const index_t* node = nullptr;      // surface node → engine node
    const index_t* bits = nullptr;      // surface node: bit d set if DOF d is free; kSoftSheetRim
    const index_t* label = nullptr;     // surface node → body label
    const index_t* tri = nullptr;       // 3 surface-node indices per triangle, outward (right hand)
    const double* tri_h = nullptr;      // mean reference edge per triangle [m]
    const index_t* vtri_off = nullptr;  // surface node i's triangles:
    const index_t* vtri = nullptr;      //   vtri[vtri_off[i] .. vtri_off[i + 1]), ascending
    index_t n_edges = 0;                // sharp surface edges (kSoftSharpCos)
    const index_t* edge = nullptr;      // 2 surface nodes per sharp edge
    const index_t* tri_edge = nullptr;  // per triangle, its edge k (v_k, v_k+1): sharp edge, −1 or
                                        // kSoftSheetEdge
    const double* sheet_h = nullptr;    // per label: half a sheet's thickness [m]; 0: a solid
    const index_t* pair = nullptr;      // labels × labels: pair index of (slave, master), −1: none
    const double* mu = nullptr;         // per pair: μs, μk
    double skin = 0.0, cell = 0.0;      // Verlet skin and grid cell size [m]
    double band_max = 0.0;              // kSoftBehind × the longest mean edge of a triangle [m]
};

/// Current position [m] of surface node i: X + u.
template <class T>
PLIANT_HD void soft_position(index_t i, const SoftSurface& s, const double* X, const T* u, index_t P,
                             double x[3]) {
    const index_t n = s.node[i];
    for (int d = 0; d < 3; ++d) x[d] = X[3 * n + d] + double(u[d * P + n]);
}

/// Surface node i's position [m] from xs, the surface positions at u⁺ (3 per surface node, as
/// soft_position computes them: kept by the soft-contact pass so that the narrow phase reads one
/// contiguous triple per node instead of an index, X and three strided u).
PLIANT_HD void soft_current(index_t i, const double* xs, double x[3]) {
    for (int d = 0; d < 3; ++d) x[d] = xs[3 * i + d];
}

PLIANT_HD long long soft_cell(double x, double h) { return static_cast<long long>(std::floor(x / h)); }

PLIANT_HD index_t soft_hash(long long i, long long j, long long k, index_t mask) {
    const unsigned long long h = static_cast<unsigned long long>(i) * 73856093ull ^
                                 static_cast<unsigned long long>(j) * 19349663ull ^
                                 static_cast<unsigned long long>(k) * 83492791ull;
    return static_cast<index_t>(h & static_cast<unsigned long long>(mask));
}

/// The broad phase's grid, per triangle t (one thread each): its centroid tc (3) and bounding radius
/// tr [m] at u, and the bucket of its centroid's cell (tri_bucket), returned with the radius in r.
/// The engine counts the triangles per bucket and lists them by bucket (a counting sort: bucket b
/// holds cell_tris[head[b] .. head[b + 1])), in whatever order the threads file them: the candidate
/// lists do not depend on it (soft_candidates keeps the nearest by distance, then triangle).
template <class T>
PLIANT_HD index_t soft_grid_triangle(index_t t, const SoftSurface& s, const double* X, const T* u, index_t P,
                                     double* tc, double* tr, index_t* tri_bucket, double& r) {
    double v[3][3], c[3] = {0.0, 0.0, 0.0};
    r = 0.0;
    for (int k = 0; k < 3; ++k) {
        soft_position(s.tri[3 * t + k], s, X, u, P, v[k]);
        for (int d = 0; d < 3; ++d) c[d] += v[k][d] / 3.0;
    }
    for (int k = 0; k < 3; ++k) {
        const double a = v[k][0] - c[0], b = v[k][1] - c[1], e = v[k][2] - c[2];
        const double rk = std::sqrt(a * a + b * b + e * e);
        r = rk > r ? rk : r;
    }
    const bool ok = std::isfinite(c[0] + c[1] + c[2] + r);  // a blown-up node: the check reports it
    for (int d = 0; d < 3; ++d) tc[3 * t + d] = ok ? c[d] : 0.0;
    r = ok ? r : 0.0;
    tr[t] = r;
    const index_t b =
        ok ? soft_hash(soft_cell(c[0], s.cell), soft_cell(c[1], s.cell), soft_cell(c[2], s.cell), s.hash_mask)
           : 0;
    tri_bucket[t] = b;
    return b;
}

/// Whether triangle t touches surface node i's neighbourhood: it shares a vertex with a triangle
/// around i (one of its vertices is i or a node joined to i by a surface edge). Self contact skips
/// such triangles: they are the node's own surface, not an obstacle (at a convex edge the node lies
/// behind its neighbours' faces). The test is topological, so that two faces that coincide without
/// sharing nodes (the sides of a cut) do meet.
PLIANT_HD bool soft_adjacent(index_t i, index_t t, const SoftSurface& s) {
    const index_t* v = s.tri + 3 * t;
    for (index_t j = s.vtri_off[i]; j < s.vtri_off[i + 1]; ++j) {
        const index_t* r = s.tri + 3 * s.vtri[j];
        for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b)
                if (v[a] == r[b]) return true;
    }
    return false;
}

/// Closest point of triangle (a, b, c) to x (Ericson 2005, Real-Time Collision Detection, §5.1.5,
/// by Voronoi regions): its barycentric weights w (out) and the feature it lies on, returned: k
/// (0–2) vertex k, 3 + k the edge from vertex k to vertex k + 1 (mod 3), 6 the face's inside.
PLIANT_HD int soft_closest(const double a[3], const double b[3], const double c[3], const double x[3],
                           double w[3]) {
    double ab[3], ac[3], ap[3], bp[3], cp[3];
    for (int d = 0; d < 3; ++d) {
        ab[d] = b[d] - a[d], ac[d] = c[d] - a[d];
        ap[d] = x[d] - a[d], bp[d] = x[d] - b[d], cp[d] = x[d] - c[d];
    }
    auto dot = [](const double* p, const double* q) { return p[0] * q[0] + p[1] * q[1] + p[2] * q[2]; };
    auto set = [&](double w0, double w1, double w2, int feature) {
        w[0] = w0, w[1] = w1, w[2] = w2;
        return feature;
    };
    const double d1 = dot(ab, ap), d2 = dot(ac, ap);
    if (d1 <= 0.0 && d2 <= 0.0) return set(1.0, 0.0, 0.0, 0);
    const double d3 = dot(ab, bp), d4 = dot(ac, bp);
    if (d3 >= 0.0 && d4 <= d3) return set(0.0, 1.0, 0.0, 1);
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
        const double v = d1 / (d1 - d3);
        return set(1.0 - v, v, 0.0, 3);
    }
    const double d5 = dot(ab, cp), d6 = dot(ac, cp);
    if (d6 >= 0.0 && d5 <= d6) return set(0.0, 0.0, 1.0, 2);
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
        const double v = d2 / (d2 - d6);
        return set(1.0 - v, 0.0, v, 5);
    }
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0) {
        const double v = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return set(0.0, 1.0 - v, v, 4);
    }
    const double den = va + vb + vc;
    if (!(den > 0.0)) return -1;  // degenerate triangle
    return set(va / den, vb / den, vc / den, 6);
}

/// soft_closest, and the squared distance [m²] from x to that closest point (d2, out); a degenerate
/// triangle (feature −1) gives its first vertex (w = 1, 0, 0).
PLIANT_HD int soft_closest_d2(const double a[3], const double b[3], const double c[3], const double x[3],
                              double w[3], double& d2) {
    w[0] = 1.0, w[1] = w[2] = 0.0;
    const int feature = soft_closest(a, b, c, x, w);
    d2 = 0.0;
    for (int d = 0; d < 3; ++d) {
        const double e = x[d] - (w[0] * a[d] + w[1] * b[d] + w[2] * c[d]);
        d2 += e * e;
    }
    return feature;
}

/// Closest point of triangle t to x [m] at the surface positions xs [m] (soft_current):
/// soft_closest_d2's feature (returned), weights w (out) and squared distance d2 [m²] (out).
PLIANT_HD int soft_closest_to(index_t t, const SoftSurface& s, const double* xs, const double x[3],
                              double w[3], double& d2) {
    double a[3], b[3], c[3];
    soft_current(s.tri[3 * t], xs, a);
    soft_current(s.tri[3 * t + 1], xs, b);
    soft_current(s.tri[3 * t + 2], xs, c);
    return soft_closest_d2(a, b, c, x, w, d2);
}

/// soft_detect's closest point of a node's candidate q (triangle t) to its position x [m]
/// (soft_closest_to's feature, weights w and squared distance d2), computed as the node's thread
/// walks its candidates (the CPU; SoftClosestStored reads them from a launch before).
struct SoftClosestComputed {
    const SoftSurface* s;
    const double* xs;  // the surface positions [m] (soft_current)
    PLIANT_HD int operator()(int, index_t t, const double x[3], double w[3], double& d2) const {
        return soft_closest_to(t, *s, xs, x, w, d2);
    }
};
/// soft_detect's closest point of a node's candidate q, read from slot base + q, where a launch
/// before, one thread per (node, candidate), stored it (Dev::kSplitsDetection: on a GPU one thread
/// walking the candidates was the detection's longest chain of loads): features f, squared distances
/// d2 [m²], weights w (3 per slot). The same bits as SoftClosestComputed's.
struct SoftClosestStored {
    const int* f;
    const double *d2, *w;
    std::size_t base;
    PLIANT_HD int operator()(int q, index_t, const double*, double w_out[3], double& d2_out) const {
        const std::size_t k = base + static_cast<std::size_t>(q);
        for (int d = 0; d < 3; ++d) w_out[d] = w[3 * k + d];
        d2_out = d2[k];
        return f[k];
    }
};

/// Whether surface node i lay within a mean edge of triangle t in the reference configuration X
/// [m] (a cut's two sides coincide there), plus the half thicknesses of the sheets the two belong to
/// (0 for a solid's): the self contact of edges is for surfaces that deformation brought together
/// (soft_edge_detect), and so is a sheet's self contact (soft_detect: a sheet lies in its own plane,
/// its next triangles but one within the band and its thickness of a node).
PLIANT_HD bool soft_near_reference(index_t i, index_t t, const SoftSurface& s, const double* X) {
    double v[3][3], x[3], w[3], d2;
    for (int d = 0; d < 3; ++d) {
        x[d] = X[3 * s.node[i] + d];
        for (int k = 0; k < 3; ++k) v[k][d] = X[3 * s.node[s.tri[3 * t + k]] + d];
    }
    soft_closest_d2(v[0], v[1], v[2], x, w, d2);
    const double r = s.tri_h[t] + s.sheet_h[s.label[s.tri[3 * t]]] + s.sheet_h[s.label[i]];
    return d2 < r * r;
}

/// Distance [m] from x to the triangle of surface nodes v[0..3) at displacements u (X + u; a
/// degenerate triangle: to its first node).
template <class T>
PLIANT_HD double soft_distance(const double x[3], const index_t* v, const SoftSurface& s, const double* X,
                               const T* u, index_t P) {
    double a[3], b[3], c[3], w[3], d2;
    soft_position(v[0], s, X, u, P, a);
    soft_position(v[1], s, X, u, P, b);
    soft_position(v[2], s, X, u, P, c);
    soft_closest_d2(a, b, c, x, w, d2);
    return std::sqrt(d2);
}

/// Candidate triangles of surface node i (cand: kSoftCandidates entries, nearest first, ties by
/// triangle; −1 pads): those of a body the node's body may touch, not incident to the node nor, in
/// its own body, to its neighbours (soft_adjacent), that lie within skin + band [m] of it (band =
/// kSoftBehind × the triangle's mean edge: the farthest a contact's closest point may lie). Until the
/// next rebuild the node and every vertex move at most skin/2 (the skin test), and a point's
/// distance to a triangle changes by at most the largest of those moves together, so every triangle
/// that comes within its band of the node before then is on the list: soft_detect, which looks no
/// farther, finds what a search of the whole surface would. Triangles with a sharp edge are also kept
/// while their bounding sphere lies within the skin: the edge–edge test of the node's edges reads
/// their edges (soft_edge_detect), and edges can cross farther from their end nodes than the band.
/// A bounding sphere's distance bounds the triangle's from below and sorts out the far ones before
/// the closest point is computed. near[i]: bit q set if candidate q is of the node's own body and was
/// near it in the reference configuration (soft_near_reference). xb (3 per node) records where the
/// node was, for the rebuild test.
template <class T>
PLIANT_HD void soft_candidates(index_t i, const SoftSurface& s, const double* X, const T* u, index_t P,
                               double rmax, const index_t* head, const index_t* cell_tris, const double* tc,
                               const double* tr, index_t* cand, index_t* near, double* xb) {
    double x[3];
    soft_position(i, s, X, u, P, x);
    for (int d = 0; d < 3; ++d) xb[3 * i + d] = x[d];
    index_t* out = cand + static_cast<std::size_t>(i) * kSoftCandidates;
    double key[kSoftCandidates];
    int n = 0;
    if (std::isfinite(x[0] + x[1] + x[2])) {
        int reach = static_cast<int>(std::ceil((rmax + s.skin + s.band_max) / s.cell));
        reach = reach < 1 ? 1 : (reach > kSoftReach ? kSoftReach : reach);
        const long long c0 = soft_cell(x[0], s.cell), c1 = soft_cell(x[1], s.cell),
                        c2 = soft_cell(x[2], s.cell);
        const index_t* pair_row = s.pair + static_cast<std::size_t>(s.label[i]) * s.labels;
        for (int a = -reach; a <= reach; ++a)
            for (int b = -reach; b <= reach; ++b)
                for (int c = -reach; c <= reach; ++c) {
                    const index_t h = soft_hash(c0 + a, c1 + b, c2 + c, s.hash_mask);
                    for (index_t j = head[h]; j < head[h + 1]; ++j) {
                        const index_t t = cell_tris[j];
                        const index_t* v = s.tri + 3 * t;
                        if (v[0] == i || v[1] == i || v[2] == i || pair_row[s.label[v[0]]] < 0) continue;
                        if (s.label[v[0]] == s.label[i] && soft_adjacent(i, t, s)) continue;
                        const double dx = x[0] - tc[3 * t], dy = x[1] - tc[3 * t + 1],
                                     dz = x[2] - tc[3 * t + 2];
                        const double sphere = std::sqrt(dx * dx + dy * dy + dz * dz) - tr[t];
                        const double reach_t = s.skin + kSoftBehind * s.tri_h[t] + s.sheet_h[s.label[v[0]]] +
                                               s.sheet_h[s.label[i]];
                        if (!(sphere <= reach_t)) continue;
                        bool seen = false;  // two cells of one bucket list a triangle twice
                        for (int q = 0; q < n; ++q) seen = seen || out[q] == t;
                        if (seen) continue;
                        const double dist = soft_distance(x, v, s, X, u, P);
                        const bool sharp = s.tri_edge[3 * t] >= 0 || s.tri_edge[3 * t + 1] >= 0 ||
                                           s.tri_edge[3 * t + 2] >= 0;
                        if (!(dist <= reach_t) && !(sharp && sphere <= s.skin)) continue;
                        // Insertion into the sorted list, the farthest dropped when full.
                        int p = n < kSoftCandidates ? n++ : kSoftCandidates;
                        while (p > 0 && (key[p - 1] > dist || (key[p - 1] == dist && out[p - 1] > t))) {
                            if (p < kSoftCandidates) {
                                key[p] = key[p - 1];
                                out[p] = out[p - 1];
                            }
                            --p;
                        }
                        if (p < kSoftCandidates) {
                            key[p] = dist;
                            out[p] = t;
                        }
                    }
                }
    }
    for (int q = n; q < kSoftCandidates; ++q) out[q] = -1;
    unsigned mask = 0;
    for (int q = 0; q < n; ++q)
        if (s.label[s.tri[3 * out[q]]] == s.label[i] && soft_near_reference(i, out[q], s, X)) mask |= 1u << q;
    near[i] = static_cast<index_t>(mask);
}

/// Free-DOF inverse mass of surface node i [1/kg] per DOF.
template <class T>
PLIANT_HD void soft_inverse_mass(index_t i, const SoftSurface& s, const T* mass, double W[3]) {
    const double m = double(mass[s.node[i]]);
    for (int d = 0; d < 3; ++d) W[d] = ((s.bits[i] >> d) & 1) && m > 0.0 ? 1.0 / m : 0.0;
}

/// Unit normal (out) of triangle t at the surface positions xs [m] (right hand: outward), and, if
/// angle is given, the interior angle [rad] at its vertex k (an atan2: only a vertex's pseudo-normal
/// needs it); false for a degenerate triangle.
PLIANT_HD bool soft_face(index_t t, int k, const SoftSurface& s, const double* xs, double n[3],
                         double* angle) {
    double v[3][3];
    for (int j = 0; j < 3; ++j) soft_current(s.tri[3 * t + j], xs, v[j]);
    double e0[3], e1[3];
    for (int d = 0; d < 3; ++d) {
        e0[d] = v[(k + 1) % 3][d] - v[k][d];
        e1[d] = v[(k + 2) % 3][d] - v[k][d];
    }
    n[0] = e0[1] * e1[2] - e0[2] * e1[1];
    n[1] = e0[2] * e1[0] - e0[0] * e1[2];
    n[2] = e0[0] * e1[1] - e0[1] * e1[0];
    const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(len > 0.0)) return false;
    for (int d = 0; d < 3; ++d) n[d] /= len;
    if (angle) *angle = std::atan2(len, e0[0] * e1[0] + e0[1] * e1[1] + e0[2] * e1[2]);
    return true;
}

/// Sum (out, not normalized) of the normals at the surface positions xs [m] of surface node a's
/// triangles: those that also hold node b if b >= 0 (an edge's pseudo-normal: its two faces', each
/// weighing 1), else all of them, each weighted by its angle at a (a vertex's pseudo-normal).
PLIANT_HD void soft_node_normal(index_t a, index_t b, const SoftSurface& s, const double* xs, double n[3]) {
    double f[3], angle = 1.0;
    n[0] = n[1] = n[2] = 0.0;
    for (index_t j = s.vtri_off[a]; j < s.vtri_off[a + 1]; ++j) {
        const index_t q = s.vtri[j];
        const index_t* r = s.tri + 3 * q;
        const int k = r[0] == a ? 0 : (r[1] == a ? 1 : 2);
        if (b >= 0 && r[0] != b && r[1] != b && r[2] != b) continue;  // not on the edge
        if (!soft_face(q, k, s, xs, f, b < 0 ? &angle : nullptr)) continue;
        for (int d = 0; d < 3; ++d) n[d] += angle * f[d];
    }
}

/// Pseudo-normal (out, not normalized) of the feature of triangle t that a closest point lies on
/// (soft_closest's numbering), at the surface positions xs [m]: the face's normal; for an edge, the sum of
/// the normals of the triangles sharing it; for a vertex, the normals of its triangles weighted by their
/// angles there (Bærentzen & Aanæs 2005, IEEE TVCG 11(3):243: x lies outside a closed surface if (x − c)·n >
/// 0 for the pseudo-normal n at its closest point c).
PLIANT_HD void soft_pseudo_normal(index_t t, int feature, const SoftSurface& s, const double* xs,
                                  double n[3]) {
    if (feature == 6) {
        n[0] = n[1] = n[2] = 0.0;
        double f[3];
        if (soft_face(t, 0, s, xs, f, nullptr))
            for (int d = 0; d < 3; ++d) n[d] = f[d];
        return;
    }
    const index_t a = s.tri[3 * t + feature % 3], b = s.tri[3 * t + (feature % 3 + 1) % 3];
    soft_node_normal(a, feature >= 3 ? b : -1, s, xs, n);
}

/// Coulomb friction of a contact in displacement form (as the tools', contact.hpp): rel [m] the
/// relative motion over the step of the two sides' contact points, n the unit normal, λ [kg·m]
/// the normal impulse, mu (μs, μk), inverse_mass(q) [1/kg] the contact's effective inverse mass
/// along a unit vector q. The tangential impulse that stops the tangential motion if it is at most
/// μs λ (stick), else μk λ (slip), against that motion, is taken from p [kg·m] (the first side's).
template <class InverseMass>
PLIANT_HD void soft_friction(const double rel[3], const double n[3], double lambda, const double* mu,
                             const InverseMass& inverse_mass, double p[3]) {
    double dot = 0.0, tan[3], mag2 = 0.0;
    for (int d = 0; d < 3; ++d) dot += rel[d] * n[d];
    for (int d = 0; d < 3; ++d) {
        tan[d] = rel[d] - dot * n[d];
        mag2 += tan[d] * tan[d];
    }
    const double mag = std::sqrt(mag2);
    if (!(mag > 0.0)) return;
    const double t[3] = {tan[0] / mag, tan[1] / mag, tan[2] / mag};
    const double kt = inverse_mass(t);
    if (!(kt > 0.0)) return;
    const double stick = mag / kt;
    const double lt = stick <= mu[0] * lambda ? stick : mu[1] * lambda;
    for (int d = 0; d < 3; ++d) p[d] -= lt * t[d];
}

/// The unit vector e from x1 to target (out) and the distance gap [m] between them; false where they
/// coincide (or either is not finite).
PLIANT_HD bool soft_toward(const double target[3], const double x1[3], double e[3], double& gap) {
    double g2 = 0.0;
    for (int d = 0; d < 3; ++d) {
        e[d] = target[d] - x1[d];
        g2 += e[d] * e[d];
    }
    gap = std::sqrt(g2);
    if (!(gap > 0.0)) return false;
    for (int d = 0; d < 3; ++d) e[d] /= gap;
    return true;
}

/// Contact of node i with a sheet of membranes (two-sided, half thickness h [m]) at its closest
/// point c on triangle t (feature f, weights w) to the node at u⁺, x1: the node keeps to the side
/// of the sheet's mid-surface it was on at u, x0 (the sign σ of (x0 − c0)·n0, c0 the same point and
/// n0 the face's normal at u), at least h from it. On that side within h of c, the target is h from
/// c along x1 − c; through the mid-surface, h beyond c on σ's side, c + σ h n1 (n1 the normal at
/// u⁺). Where c lies on the sheet's boundary (an edge of one triangle, kSoftSheetEdge, or a node
/// on such an edge, kSoftSheetRim) the node is beside the sheet and meets its rim, rounded: within
/// h of c, the target is h from c along x1 − c (c + σ h n1 if x1 is c). The sheet with its
/// thickness is the set of points within h of its mid-surface: a slab over its faces, a
/// half-cylinder along its rim (two equal sheets stacked rim on rim rest on each other there too).
/// Writes the unit vector e from x1 to the target and the distance gap [m] to it; false where
/// the node is farther than h on its side (or from the rim), or the face is degenerate. The offset
/// surface of a sheet with thickness, as NiftySim's membrane contact surfaces are (Taylor et al.
/// 2008, IEEE TMI 27(5):650, §IV-C; NiftySim's tledDeformableMembraneContactSurface).
template <class T>
PLIANT_HD bool soft_sheet_target(index_t t, int f, const double w[3], double h, const SoftSurface& s,
                                 const double* X, const T* u, index_t P, const double* xs, const double x0[3],
                                 const double x1[3], double e[3], double& gap) {
    const index_t* v = s.tri + 3 * t;
    const bool rim = (f >= 3 && f < 6 && s.tri_edge[3 * t + f - 3] == kSoftSheetEdge) ||
                     (f < 3 && (s.bits[v[f]] & kSoftSheetRim));
    double y0[3][3], n0[3], n1[3];
    for (int j = 0; j < 3; ++j) soft_position(v[j], s, X, u, P, y0[j]);
    const double a[3] = {y0[1][0] - y0[0][0], y0[1][1] - y0[0][1], y0[1][2] - y0[0][2]};
    const double b[3] = {y0[2][0] - y0[0][0], y0[2][1] - y0[0][1], y0[2][2] - y0[0][2]};
    n0[0] = a[1] * b[2] - a[2] * b[1], n0[1] = a[2] * b[0] - a[0] * b[2], n0[2] = a[0] * b[1] - a[1] * b[0];
    if (!soft_face(t, 0, s, xs, n1, nullptr)) return false;
    double y1[3][3], side0 = 0.0, side1 = 0.0, r[3], c[3], dist2 = 0.0;
    for (int j = 0; j < 3; ++j) soft_current(v[j], xs, y1[j]);
    for (int d = 0; d < 3; ++d) {
        c[d] = w[0] * y1[0][d] + w[1] * y1[1][d] + w[2] * y1[2][d];
        const double c0 = w[0] * y0[0][d] + w[1] * y0[1][d] + w[2] * y0[2][d];
        side0 += (x0[d] - c0) * n0[d];
        r[d] = x1[d] - c[d];
        side1 += r[d] * n1[d];
        dist2 += r[d] * r[d];
    }
    const double sigma = side0 >= 0.0 ? 1.0 : -1.0;
    double target[3];
    // Beside the rim (off it), or on its side of a face: within h of c, out along x1 − c.
    if (rim ? dist2 > 0.0 : sigma * side1 > 0.0) {
        if (!(dist2 < h * h)) return false;
        const double dist = std::sqrt(dist2);
        for (int d = 0; d < 3; ++d) target[d] = c[d] + h * r[d] / dist;
    } else {  // through the mid-surface, or on the rim itself: h beyond c on σ's side
        for (int d = 0; d < 3; ++d) target[d] = c[d] + sigma * h * n1[d];
    }
    return soft_toward(target, x1, e, gap);
}

/// Contact of a sheet's node (half thickness h [m]) with a solid at its closest point c on triangle t
/// (feature f, weights w) to the node at u⁺, x1: the node keeps h outside the solid's surface, as a
/// solid's node keeps a sheet's h from the sheet's mid-surface. Outside ((x1 − c)·n > 0, n the
/// pseudo-normal at c) within h of c, the target is h from c along x1 − c; inside, c + h n/|n|.
/// Writes e and gap as soft_sheet_target; false where the node is h or more outside, or n vanishes.
PLIANT_HD bool soft_offset_target(index_t t, int f, const double w[3], double h, const SoftSurface& s,
                                  const double* xs, const double x1[3], double e[3], double& gap) {
    double pn[3], y[3][3], c[3], r[3], side = 0.0, r2 = 0.0, n2 = 0.0;
    soft_pseudo_normal(t, f, s, xs, pn);
    for (int j = 0; j < 3; ++j) soft_current(s.tri[3 * t + j], xs, y[j]);
    for (int d = 0; d < 3; ++d) {
        c[d] = w[0] * y[0][d] + w[1] * y[1][d] + w[2] * y[2][d];
        r[d] = x1[d] - c[d];
        side += r[d] * pn[d], r2 += r[d] * r[d], n2 += pn[d] * pn[d];
    }
    if (!(n2 > 0.0)) return false;
    double target[3];
    if (side > 0.0) {  // outside: within h of c
        if (!(r2 < h * h)) return false;
        const double dist = std::sqrt(r2);
        for (int d = 0; d < 3; ++d) target[d] = c[d] + h * r[d] / dist;
    } else {  // inside
        const double nn = std::sqrt(n2);
        for (int d = 0; d < 3; ++d) target[d] = c[d] + h * pn[d] / nn;
    }
    return soft_toward(target, x1, e, gap);
}

/// Narrow phase and response of surface node i (the slave). For each body among its candidates,
/// the closest point c on that body's candidate triangles to x⁺; the node is inside the body if
/// (x⁺ − c)·n < 0 for the pseudo-normal n there (soft_pseudo_normal) and it lies at most
/// kSoftBehind × the triangle's mean edge from c. Of the bodies it is inside, the shallowest: the
/// position impulse p [kg·m] on the node that puts it back on c (along the unit vector from x⁺ to c,
/// λ = gap / (eᵀW_s e + Σ w_j² eᵀW_j e)) with Coulomb friction on the relative tangential motion
/// over the step (stick if the impulse that removes it is within μs λ, else μk λ against it).
/// A sheet of membranes is met two-sided (soft_sheet_target), at the half thicknesses of both the
/// sheet and, if the node is a sheet's, the node's own; a sheet's node keeps its half thickness
/// outside a solid too (soft_offset_target); a sheet's own triangles that lay near the node in the
/// reference configuration (near, soft_near_reference) are no contact of it.
/// Outputs rec_tri[i] (−1: no contact), rec_w (3 weights of c), rec_p (3). Inputs: reference X
/// [m] AoS, mass [kg], u and u⁺ [m] SoA (3, P) (u⁺ after the tool contact), xs the surface
/// positions at u⁺ [m] (soft_current), cand and near (soft_candidates), closest: the closest points
/// of the node's candidates (SoftClosestComputed, or SoftClosestStored).
template <class T, class Closest>
PLIANT_HD void soft_detect(index_t i, const SoftSurface& s, const double* X, const T* mass, const T* u,
                           const T* u_next, index_t P, const double* xs, const index_t* cand,
                           const index_t* near_ref, const Closest& closest, index_t* rec_tri, double* rec_w,
                           double* rec_p) {
    rec_tri[i] = -1;
    const index_t* list = cand + static_cast<std::size_t>(i) * kSoftCandidates;
    if (list[0] < 0) return;
    const index_t own = s.label[i];
    const double own_h = s.sheet_h[own];  // half the node's sheet's thickness; 0: a solid's node
    // Candidates of the node's own sheet that were near it in the reference: its sheet around it.
    const unsigned skip = own_h > 0.0 ? static_cast<unsigned>(near_ref[i]) : 0u;
    double x0[3], x1[3];
    soft_position(i, s, X, u, P, x0);
    soft_current(i, xs, x1);
    // The closest candidate triangle of each body: body, triangle, squared distance, feature, weights.
    index_t body[kSoftCandidates], near[kSoftCandidates];
    double near_d2[kSoftCandidates], near_w[kSoftCandidates][3];
    int near_f[kSoftCandidates], n_bodies = 0;
    for (int q = 0; q < kSoftCandidates && list[q] >= 0; ++q) {
        const index_t t = list[q];
        if ((skip >> q) & 1u) continue;  // bit q: of the node's own body (soft_candidates)
        double w[3], d2;
        const int feature = closest(q, t, x1, w, d2);
        if (feature < 0) continue;
        const index_t lb = s.label[s.tri[3 * t]];
        int k = 0;
        while (k < n_bodies && body[k] != lb) ++k;
        if (k == n_bodies)
            ++n_bodies;
        else if (!(d2 < near_d2[k] || (d2 == near_d2[k] && t < near[k])))
            continue;
        body[k] = lb, near[k] = t, near_d2[k] = d2, near_f[k] = feature;
        for (int d = 0; d < 3; ++d) near_w[k][d] = w[d];
    }
    index_t best = -1;
    double best_d = -INFINITY, best_n[3] = {0.0, 0.0, 0.0}, best_w[3] = {0.0, 0.0, 0.0};
    // The contact of triangle t (distance gap [m] to its target along e, weights w) if the
    // shallowest so far (ties: the lower triangle).
    auto keep = [&](index_t t, double gap, const double e[3], const double w[3]) {
        if (!(-gap > best_d || (-gap == best_d && t < best))) return;
        best = t, best_d = -gap;
        for (int d = 0; d < 3; ++d) best_n[d] = e[d], best_w[d] = w[d];
    };
    for (int k = 0; k < n_bodies; ++k) {
        const index_t t = near[k];
        if (s.sheet_h[body[k]] > 0.0) {  // a sheet of membranes: two-sided
            const double h = s.sheet_h[body[k]] + own_h;
            double e[3], gap;
            if (!(near_d2[k] <= (kSoftBehind * s.tri_h[t] + h) * (kSoftBehind * s.tri_h[t] + h))) continue;
            if (soft_sheet_target(t, near_f[k], near_w[k], h, s, X, u, P, xs, x0, x1, e, gap))
                keep(t, gap, e, near_w[k]);
            continue;
        }
        if (own_h > 0.0) {  // a sheet's node against a solid: its half thickness outside it
            const double reach = kSoftBehind * s.tri_h[t] + own_h;
            double e[3], gap;
            if (!(near_d2[k] <= reach * reach)) continue;
            if (soft_offset_target(t, near_f[k], near_w[k], own_h, s, xs, x1, e, gap))
                keep(t, gap, e, near_w[k]);
            continue;
        }
        const double band = kSoftBehind * s.tri_h[t];
        if (!(near_d2[k] > 0.0 && near_d2[k] <= band * band)) continue;
        const double gap = std::sqrt(near_d2[k]);
        if (!(-gap > best_d || (-gap == best_d && t < best))) continue;
        double pn[3], y[3][3], e[3], side = 0.0;
        soft_pseudo_normal(t, near_f[k], s, xs, pn);
        for (int j = 0; j < 3; ++j) soft_current(s.tri[3 * t + j], xs, y[j]);
        for (int d = 0; d < 3; ++d) {
            const double c = near_w[k][0] * y[0][d] + near_w[k][1] * y[1][d] + near_w[k][2] * y[2][d];
            e[d] = (c - x1[d]) / gap;  // from the node to c: out of the body if the node is inside
            side -= e[d] * pn[d];
        }
        if (side < 0.0) keep(t, gap, e, near_w[k]);  // inside this body
    }
    if (best < 0) return;
    const double wsum = best_w[0] + best_w[1] + best_w[2];
    for (int d = 0; d < 3; ++d) best_w[d] /= wsum;
    // Effective inverse mass along a direction e: eᵀ W_s e + Σ w_j² eᵀ W_j e.
    double Ws[3], Wt[3][3];
    soft_inverse_mass(i, s, mass, Ws);
    for (int k = 0; k < 3; ++k) soft_inverse_mass(s.tri[3 * best + k], s, mass, Wt[k]);
    auto inverse_mass = [&](const double e[3]) {
        double r = 0.0;
        for (int d = 0; d < 3; ++d) {
            double wd = Ws[d];
            for (int k = 0; k < 3; ++k) wd += best_w[k] * best_w[k] * Wt[k][d];
            r += e[d] * e[d] * wd;
        }
        return r;
    };
    const double kn = inverse_mass(best_n);
    if (!(kn > 0.0)) return;  // every node of the contact held: the constraints carry it
    const double lambda = -best_d / kn;
    // Relative motion over the step: the slave's minus the triangle point's.
    double rel[3];
    for (int d = 0; d < 3; ++d) {
        rel[d] = x1[d] - x0[d];
        for (int k = 0; k < 3; ++k) {
            const index_t j = s.tri[3 * best + k];
            const index_t nj = s.node[j];
            rel[d] -= best_w[k] * (double(u_next[d * P + nj]) - double(u[d * P + nj]));
        }
    }
    double p[3];
    for (int d = 0; d < 3; ++d) p[d] = lambda * best_n[d];
    const index_t pr = s.pair[static_cast<std::size_t>(s.label[i]) * s.labels + s.label[s.tri[3 * best]]];
    soft_friction(rel, best_n, lambda, s.mu + 2 * pr, inverse_mass, p);
    rec_tri[i] = best;
    for (int d = 0; d < 3; ++d) {
        rec_w[3 * i + d] = best_w[d];
        rec_p[3 * i + d] = p[d];
    }
}

/// Triple product ((b − a) × (d − c)) · (c − a) [m³]: its sign tells on which side of edge ab the
/// edge cd passes (Provot 1997's coplanarity test of two edges).
PLIANT_HD double soft_edge_volume(const double a[3], const double b[3], const double c[3], const double d[3],
                                  double n[3]) {
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const double v[3] = {d[0] - c[0], d[1] - c[1], d[2] - c[2]};
    n[0] = u[1] * v[2] - u[2] * v[1];
    n[1] = u[2] * v[0] - u[0] * v[2];
    n[2] = u[0] * v[1] - u[1] * v[0];
    return n[0] * (c[0] - a[0]) + n[1] * (c[1] - a[1]) + n[2] * (c[2] - a[2]);
}

/// How far [m] a stored displacement of surface nodes q[0..4) may lie from the value a correction
/// gave it: 4 units in the last place of the largest component (T = float: a contact closed at the
/// last step starts this one this far from touching, on either side, not at 0).
template <class T>
PLIANT_HD double soft_rounding(const index_t q[4], const SoftSurface& s, const T* u, index_t P) {
    double m = 0.0;
    for (int j = 0; j < 4; ++j)
        for (int d = 0; d < 3; ++d) {
            const double a = std::fabs(double(u[d * P + s.node[q[j]]]));
            m = a > m ? a : m;
        }
    return 4.0 * (sizeof(T) == 4 ? 1.1920928955078125e-7 : 2.220446049250313e-16) * m;
}

/// The side (+1, −1; 0: none told) of sharp edge q[0]q[1] that sharp edge q[2]q[3] (of another body,
/// or of its own in self contact) belongs on, for two edges touching: the sign of n·(o_e − o_f), n = (b − a)
/// × (d − c) (area = |n|), o_e, o_f the edges' unit outward pseudo-normals at the surface positions xs [m]
/// (each on the side the other's outside faces), if beyond ±0.5 of its range ±2 (not two edges meeting
/// side-on).
PLIANT_HD double soft_edge_side(const double n[3], double area, const index_t q[4], const SoftSurface& s,
                                const double* xs) {
    double oe[3], of[3];
    soft_node_normal(q[0], q[1], s, xs, oe);
    soft_node_normal(q[2], q[3], s, xs, of);
    const double le = std::sqrt(oe[0] * oe[0] + oe[1] * oe[1] + oe[2] * oe[2]);
    const double lf = std::sqrt(of[0] * of[0] + of[1] * of[1] + of[2] * of[2]);
    if (!(le > 0.0 && lf > 0.0)) return 0.0;
    double k = 0.0;
    for (int d = 0; d < 3; ++d) k += n[d] * (oe[d] / le - of[d] / lf);
    k /= area;
    return k > 0.5 ? 1.0 : (k < -0.5 ? -1.0 : 0.0);
}

/// Closest points of segments ab and cd: parameters s, t in [0, 1] (out); false if parallel.
PLIANT_HD bool soft_segments(const double a[3], const double b[3], const double c[3], const double d[3],
                             double& s, double& t) {
    double u[3], v[3], w[3];
    for (int k = 0; k < 3; ++k) u[k] = b[k] - a[k], v[k] = d[k] - c[k], w[k] = a[k] - c[k];
    const double A = u[0] * u[0] + u[1] * u[1] + u[2] * u[2], B = u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
    const double C = v[0] * v[0] + v[1] * v[1] + v[2] * v[2], D = u[0] * w[0] + u[1] * w[1] + u[2] * w[2];
    const double E = v[0] * w[0] + v[1] * w[1] + v[2] * w[2];
    const double den = A * C - B * B;
    if (!(den > 1e-12 * A * C)) return false;
    s = (B * E - C * D) / den;
    t = (A * E - B * D) / den;
    return true;
}

/// Whether segments ab and cd (surface nodes) lie within kSoftBehind × |ab| of each other in the
/// reference configuration X [m]: their closest points, clamped to the segments (Ericson 2005,
/// Real-Time Collision Detection, §5.1.9).
PLIANT_HD bool soft_edges_near(index_t a, index_t b, index_t c, index_t d, const SoftSurface& s,
                               const double* X) {
    double d1[3], d2[3], r[3];
    for (int k = 0; k < 3; ++k) {
        d1[k] = X[3 * s.node[b] + k] - X[3 * s.node[a] + k];
        d2[k] = X[3 * s.node[d] + k] - X[3 * s.node[c] + k];
        r[k] = X[3 * s.node[a] + k] - X[3 * s.node[c] + k];
    }
    const double A = d1[0] * d1[0] + d1[1] * d1[1] + d1[2] * d1[2],
                 E = d2[0] * d2[0] + d2[1] * d2[1] + d2[2] * d2[2];
    const double F = d2[0] * r[0] + d2[1] * r[1] + d2[2] * r[2],
                 C = d1[0] * r[0] + d1[1] * r[1] + d1[2] * r[2];
    const double B = d1[0] * d2[0] + d1[1] * d2[1] + d1[2] * d2[2], den = A * E - B * B;
    if (!(A > 0.0 && E > 0.0)) return true;  // a degenerate edge: no contact of its own
    auto clamp = [](double x) { return x < 0.0 ? 0.0 : (x > 1.0 ? 1.0 : x); };
    double sp = den > 1e-12 * A * E ? clamp((B * F - C * E) / den) : 0.0;
    double tp = (B * sp + F) / E;
    if (tp < 0.0) {
        tp = 0.0, sp = clamp(-C / A);
    } else if (tp > 1.0) {
        tp = 1.0, sp = clamp((B - C) / A);
    }
    double dist2 = 0.0;
    for (int k = 0; k < 3; ++k) {
        const double g = r[k] + sp * d1[k] - tp * d2[k];
        dist2 += g * g;
    }
    return dist2 < kSoftBehind * kSoftBehind * A;
}

/// Edge–edge test of sharp edge e (nodes a, b) and response, after the node-to-triangle one: among
/// the sharp edges of its end nodes' candidate triangles (of its own body, in self contact, only
/// those that were not together in the reference configuration: near, soft_near_reference, and
/// soft_edges_near; a cut's coincident staircases, whose edges lie in each other's planes, made
/// resting pieces jitter), an edge f (c, d) that crossed it during the step — the sign of soft_edge_volume at
/// u⁺ is, beyond round-off, the other side than the one f came from — with the closest points inside both
/// edges at u⁺ and no further apart than kSoftBehind × the edges' length, the closest to it. The side f came
/// from is the sign of soft_edge_volume at u, or, for edges touching at u (a contact closed at the last step
/// leaves them so, within soft_rounding), soft_edge_side's: Provot's test alone let touching edges pass
/// through each other. The position impulse p [kg·m] on e's closest point puts the edges back in touch along
/// n = ±(b − a) × (d − c), on the side they came from: e's nodes get w p (w = 1 − s, s), f's nodes −w p (1 −
/// t, t), so momentum is conserved; with Coulomb friction on the relative tangential motion of the two
/// closest points over the step, as soft_detect's. Outputs erec[e] (f or −1), erec_w (s, t), erec_p (3).
/// Inputs: reference X [m] AoS, mass [kg], u [m] SoA (3, P), xs the surface positions at u⁺ [m]
/// (soft_current), cand and near (soft_candidates).
template <class T>
PLIANT_HD void soft_edge_detect(index_t e, const SoftSurface& s, const double* X, const T* mass, const T* u,
                                index_t P, const double* xs, const index_t* cand, const index_t* near,
                                index_t* erec, double* erec_w, double* erec_p) {
    erec[e] = -1;
    const index_t ea = s.edge[2 * e], eb = s.edge[2 * e + 1];
    const index_t* lists[2] = {cand + static_cast<std::size_t>(ea) * kSoftCandidates,
                               cand + static_cast<std::size_t>(eb) * kSoftCandidates};
    if (lists[0][0] < 0 && lists[1][0] < 0) return;
    double a0[3], b0[3], a1[3], b1[3];
    soft_position(ea, s, X, u, P, a0);
    soft_position(eb, s, X, u, P, b0);
    soft_current(ea, xs, a1);
    soft_current(eb, xs, b1);
    index_t best = -1;
    double best_gap = INFINITY, best_s = 0.0, best_t = 0.0, best_n[3] = {0.0, 0.0, 0.0};
    for (int l = 0; l < 2; ++l)
        for (int q = 0; q < kSoftCandidates && lists[l][q] >= 0; ++q) {
            if ((static_cast<unsigned>(near[l == 0 ? ea : eb]) >> q) & 1u) continue;  // soft_near_reference
            for (int k = 0; k < 3; ++k) {
                const index_t f = s.tri_edge[3 * lists[l][q] + k];
                if (f < 0 || f == e) continue;
                const index_t fc = s.edge[2 * f], fd = s.edge[2 * f + 1];
                double c0[3], d0[3], c1[3], d1[3], n0[3], n1[3], sp, tp;
                soft_position(fc, s, X, u, P, c0);
                soft_position(fd, s, X, u, P, d0);
                soft_current(fc, xs, c1);
                soft_current(fd, xs, d1);
                const double v0 = soft_edge_volume(a0, b0, c0, d0, n0);
                const double v1 = soft_edge_volume(a1, b1, c1, d1, n1);
                // Round-off: a volume below 1e-9 of |ab × cd| × the edges' length is no side.
                const double len =
                    std::sqrt((b1[0] - a1[0]) * (b1[0] - a1[0]) + (b1[1] - a1[1]) * (b1[1] - a1[1]) +
                              (b1[2] - a1[2]) * (b1[2] - a1[2])) +
                    std::sqrt((d1[0] - c1[0]) * (d1[0] - c1[0]) + (d1[1] - c1[1]) * (d1[1] - c1[1]) +
                              (d1[2] - c1[2]) * (d1[2] - c1[2]));
                const double area = std::sqrt(n1[0] * n1[0] + n1[1] * n1[1] + n1[2] * n1[2]);
                const double eps = 1e-9 * area * len;
                if (!(area > 0.0) || !(v1 > eps || v1 < -eps)) continue;
                // The side f came from (+1: the +n side of e): v0's, or where the edges touched at
                // the start (as a contact closed at the last step leaves them), their outward normals'.
                // Within 1e-3 of the edges' length a start closer than round-off and the rounding of
                // the stored displacements counts as touching.
                double sign = v0 > 0.0 ? 1.0 : -1.0;
                if (!(std::fabs(v0) > 1e-3 * area * len)) {
                    const index_t q[4] = {ea, eb, fc, fd};
                    const double touch = eps + area * soft_rounding(q, s, u, P);
                    sign = v0 > touch ? 1.0 : (v0 < -touch ? -1.0 : soft_edge_side(n1, area, q, s, xs));
                }
                if (!(sign * v1 < -eps)) continue;  // on f's side still, or no side to tell
                if (s.label[fc] == s.label[ea] && soft_edges_near(ea, eb, fc, fd, s, X))
                    continue;  // self contact: edges that were together in the reference configuration
                if (!soft_segments(a1, b1, c1, d1, sp, tp) || sp <= 0.0 || sp >= 1.0 || tp <= 0.0 ||
                    tp >= 1.0)
                    continue;
                double gap = 0.0, nn[3];
                for (int d = 0; d < 3; ++d) {
                    nn[d] = sign * n1[d] / area;
                    const double pe = a1[d] + sp * (b1[d] - a1[d]), pf = c1[d] + tp * (d1[d] - c1[d]);
                    gap -= nn[d] * (pf - pe);
                }
                if (!(gap > 0.0 && gap <= kSoftBehind * 0.5 * len) ||
                    !(gap < best_gap || (gap == best_gap && f < best)))
                    continue;
                best = f, best_gap = gap, best_s = sp, best_t = tp;
                for (int d = 0; d < 3; ++d) best_n[d] = nn[d];
            }
        }
    if (best < 0) return;
    // Effective inverse mass along a direction q: Σ w_j² qᵀ W_j q over the four nodes.
    const index_t nodes[4] = {ea, eb, s.edge[2 * best], s.edge[2 * best + 1]};
    const double w[4] = {1.0 - best_s, best_s, 1.0 - best_t, best_t};
    double W[4][3];
    for (int j = 0; j < 4; ++j) soft_inverse_mass(nodes[j], s, mass, W[j]);
    auto inverse_mass = [&](const double q[3]) {
        double r = 0.0;
        for (int j = 0; j < 4; ++j)
            for (int d = 0; d < 3; ++d) r += w[j] * w[j] * q[d] * q[d] * W[j][d];
        return r;
    };
    const double k = inverse_mass(best_n);
    if (!(k > 0.0)) return;
    const double lambda = best_gap / k;
    double p[3];
    for (int d = 0; d < 3; ++d) p[d] = -lambda * best_n[d];  // e moves against n
    // Friction on the motion over the step of e's closest point relative to f's.
    double x0[4][3], x1[4][3], rel[3];
    for (int j = 0; j < 4; ++j) {
        soft_position(nodes[j], s, X, u, P, x0[j]);
        soft_current(nodes[j], xs, x1[j]);
    }
    for (int d = 0; d < 3; ++d) {
        rel[d] = 0.0;
        for (int j = 0; j < 4; ++j) rel[d] += (j < 2 ? w[j] : -w[j]) * (x1[j][d] - x0[j][d]);
    }
    const index_t pr = s.pair[static_cast<std::size_t>(s.label[ea]) * s.labels + s.label[nodes[2]]];
    if (pr >= 0) soft_friction(rel, best_n, lambda, s.mu + 2 * pr, inverse_mass, p);
    erec[e] = best;
    erec_w[2 * e] = best_s, erec_w[2 * e + 1] = best_t;
    for (int d = 0; d < 3; ++d) erec_p[3 * e + d] = p[d];
}

}  // namespace pliant
