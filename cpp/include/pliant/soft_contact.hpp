// pliant — contact between deformable surfaces (two bodies, or one body with itself), header-only,
// host and device.
//
// Node-to-triangle, kinematic, after the explicit predictor and the tool contact (the approach of
// NiftySim's deformable contact: Johnsen et al. 2015, IJCARS 10:1077, §2.4, after Taylor, Cheng &
// Ourselin 2008): a surface node that crossed a triangle of another body (or a non-incident triangle
// of its own body) during the step is moved back onto it, and the triangle's three nodes are moved
// the other way. One position impulse p [kg·m] per contact, split by inverse mass and barycentric
// weight (slave Δx_s = W_s p, triangle node j: Δx_j = −w_j W_j p, W = diag of free-DOF inverse
// masses), so that Σ m Δx = 0: the pair conserves linear momentum (Heinstein, Mello, Attaway &
// Laursen 2000, CMAME 187:621, §3: mass-weighted kinematic contact). Friction: Coulomb in
// displacement form as for the tools (contact.hpp), on the relative tangential motion over the step.
// Contacts sharing a node are averaged (each impulse divided by the largest number of contacts
// any of its four nodes takes part in: Macklin et al. 2014, ACM TOG 33(4):153, §4.2), which keeps
// the Jacobi update from closing a gap twice; what is left is closed at the next steps.
//
// Broad phase: a Verlet list. Every surface node keeps up to kSoftCandidates triangles whose bounding
// sphere lies within `skin` of it, found through a hashed uniform grid of triangle centroids; the
// lists are rebuilt when some surface node has moved more than skin/2 since the last build (then no
// triangle can reach a node that is not on its list), and at the start of every run.
#pragma once

#include <cmath>

#include "tled.hpp"

namespace pliant {

/// Triangles a surface node keeps as contact candidates (the nearest by bounding-sphere distance).
constexpr int kSoftCandidates = 32;
/// A node crossing a triangle's plane counts as a contact only if it lay at most this fraction of
/// the triangle's mean edge behind the plane at the step's start (crossing test: a node deep behind
/// a face, e.g. on the far side of a sharp ridge of its own body, is not in contact with it).
constexpr double kSoftBehind = 0.25;
/// Barycentric tolerance of the projection onto a triangle (a node on an edge meets both triangles).
constexpr double kSoftEdge = 1e-3;
/// Most grid cells searched in each direction around a node (a blown-up mesh stops at this).
constexpr int kSoftReach = 8;
/// Self contact: a triangle of the node's own body counts only if its reference centroid lies at
/// least this many of its mean edges from the node's reference position (the triangles around the
/// node are its own surface, not an obstacle; folds closer than this are not detected).
constexpr double kSoftSelfGap = 0.5;
/// Jacobi sweeps of the soft-contact response per step: each detects on the corrected positions
/// and closes what the averaging left (soft_pass).
constexpr int kSoftSweeps = 3;

/// The contact surface and its settings, as device pointers (trivially copyable).
struct SoftSurface {
    index_t n_nodes = 0, n_tris = 0, labels = 0, hash_mask = 0;
    const index_t* node = nullptr;   // surface node → engine node
    const index_t* bits = nullptr;   // surface node: bit d set if DOF d is free
    const index_t* label = nullptr;  // surface node → body label
    const index_t* tri = nullptr;    // 3 surface-node indices per triangle, outward (right hand)
    const double* tri_h = nullptr;   // mean reference edge per triangle [m]
    const index_t* pair = nullptr;   // labels × labels: pair index of (slave, master), −1: none
    const double* mu = nullptr;      // per pair: μs, μk
    double skin = 0.0, cell = 0.0;   // Verlet skin and grid cell size [m]
};

/// Current position [m] of surface node i: X + u.
template <class T>
PLIANT_HD void soft_position(index_t i, const SoftSurface& s, const double* X, const T* u, index_t P,
                             double x[3]) {
    const index_t n = s.node[i];
    for (int d = 0; d < 3; ++d) x[d] = X[3 * n + d] + double(u[d * P + n]);
}

PLIANT_HD long long soft_cell(double x, double h) { return static_cast<long long>(std::floor(x / h)); }

PLIANT_HD index_t soft_hash(long long i, long long j, long long k, index_t mask) {
    const unsigned long long h = static_cast<unsigned long long>(i) * 73856093ull ^
                                 static_cast<unsigned long long>(j) * 19349663ull ^
                                 static_cast<unsigned long long>(k) * 83492791ull;
    return static_cast<index_t>(h & static_cast<unsigned long long>(mask));
}

/// The broad phase's grid (one thread, triangles in order: the same lists for any thread count):
/// each triangle's centroid tc (3) and bounding radius tr [m] at u, bucketed by the hash of its
/// centroid's cell (counting sort: bucket b holds cell_tris[head[b] .. head[b + 1])). Returns the
/// largest bounding radius [m]. Scratch: cursor (buckets), tri_bucket (triangles).
template <class T>
PLIANT_HD double soft_grid(const SoftSurface& s, const double* X, const T* u, index_t P, index_t* head,
                           index_t* cursor, index_t* tri_bucket, double* tc, double* tr, index_t* cell_tris) {
    const index_t H = s.hash_mask + 1;
    for (index_t b = 0; b <= H; ++b) head[b] = 0;
    double rmax = 0.0;
    for (index_t t = 0; t < s.n_tris; ++t) {
        double v[3][3], c[3] = {0.0, 0.0, 0.0}, r = 0.0;
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
        tr[t] = ok ? r : 0.0;
        if (ok && r > rmax) rmax = r;
        const index_t b = ok ? soft_hash(soft_cell(c[0], s.cell), soft_cell(c[1], s.cell),
                                         soft_cell(c[2], s.cell), s.hash_mask)
                             : 0;
        tri_bucket[t] = b;
        ++head[b + 1];
    }
    for (index_t b = 0; b < H; ++b) {
        head[b + 1] += head[b];
        cursor[b] = head[b];
    }
    for (index_t t = 0; t < s.n_tris; ++t) cell_tris[cursor[tri_bucket[t]]++] = t;
    return rmax;
}

/// Whether triangle t lies within kSoftSelfGap mean edges of surface node i in the reference
/// configuration (self contact skips it).
PLIANT_HD bool soft_reference_near(index_t i, index_t t, const SoftSurface& s, const double* X) {
    const index_t n = s.node[i];
    double d2 = 0.0;
    for (int d = 0; d < 3; ++d) {
        double c = 0.0;
        for (int k = 0; k < 3; ++k) c += X[3 * s.node[s.tri[3 * t + k]] + d] / 3.0;
        d2 += (X[3 * n + d] - c) * (X[3 * n + d] - c);
    }
    const double gap = kSoftSelfGap * s.tri_h[t];
    return d2 < gap * gap;
}

/// Candidate triangles of surface node i (cand: kSoftCandidates entries, nearest first by the
/// distance from the node to the triangle's bounding sphere, ties by triangle; −1 pads): those
/// within `skin` [m], of a body the node's body may touch, not incident to the node. xb (3 per
/// node) records where the node was, for the rebuild test.
template <class T>
PLIANT_HD void soft_candidates(index_t i, const SoftSurface& s, const double* X, const T* u, index_t P,
                               double rmax, const index_t* head, const index_t* cell_tris, const double* tc,
                               const double* tr, index_t* cand, double* xb) {
    double x[3];
    soft_position(i, s, X, u, P, x);
    for (int d = 0; d < 3; ++d) xb[3 * i + d] = x[d];
    index_t* out = cand + static_cast<std::size_t>(i) * kSoftCandidates;
    double key[kSoftCandidates];
    int n = 0;
    if (std::isfinite(x[0] + x[1] + x[2])) {
        int reach = static_cast<int>(std::ceil((rmax + s.skin) / s.cell));
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
                        if (s.label[v[0]] == s.label[i] && soft_reference_near(i, t, s, X)) continue;
                        const double dx = x[0] - tc[3 * t], dy = x[1] - tc[3 * t + 1],
                                     dz = x[2] - tc[3 * t + 2];
                        const double dist = std::sqrt(dx * dx + dy * dy + dz * dz) - tr[t];
                        if (!(dist <= s.skin)) continue;
                        bool seen = false;  // two cells of one bucket list a triangle twice
                        for (int q = 0; q < n; ++q) seen = seen || out[q] == t;
                        if (seen) continue;
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
}

/// Signed distance [m] of x from the plane of triangle (a, b, c) along its unit normal n (out), and
/// the barycentric weights w (out) of x's projection; returns false for a degenerate triangle.
PLIANT_HD bool soft_project(const double a[3], const double b[3], const double c[3], const double x[3],
                            double n[3], double w[3], double& dist) {
    const double e0[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const double e1[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    n[0] = e0[1] * e1[2] - e0[2] * e1[1];
    n[1] = e0[2] * e1[0] - e0[0] * e1[2];
    n[2] = e0[0] * e1[1] - e0[1] * e1[0];
    const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(len > 0.0)) return false;
    for (int d = 0; d < 3; ++d) n[d] /= len;
    const double r[3] = {x[0] - a[0], x[1] - a[1], x[2] - a[2]};
    dist = r[0] * n[0] + r[1] * n[1] + r[2] * n[2];
    const double d00 = e0[0] * e0[0] + e0[1] * e0[1] + e0[2] * e0[2];
    const double d01 = e0[0] * e1[0] + e0[1] * e1[1] + e0[2] * e1[2];
    const double d11 = e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2];
    const double d20 = r[0] * e0[0] + r[1] * e0[1] + r[2] * e0[2];
    const double d21 = r[0] * e1[0] + r[1] * e1[1] + r[2] * e1[2];
    const double den = d00 * d11 - d01 * d01;
    w[1] = (d11 * d20 - d01 * d21) / den;
    w[2] = (d00 * d21 - d01 * d20) / den;
    w[0] = 1.0 - w[1] - w[2];
    return true;
}

/// Free-DOF inverse mass of surface node i [1/kg] per DOF.
template <class T>
PLIANT_HD void soft_inverse_mass(index_t i, const SoftSurface& s, const T* mass, double W[3]) {
    const double m = double(mass[s.node[i]]);
    for (int d = 0; d < 3; ++d) W[d] = ((s.bits[i] >> d) & 1) && m > 0.0 ? 1.0 / m : 0.0;
}

/// Narrow phase and response of surface node i (the slave): among its candidates, the triangle it
/// crossed during the step (x⁺ behind its plane, x at most kSoftBehind × h behind it at the step's
/// start, projection inside) closest to x⁺; the position impulse p [kg·m] on the node that puts it
/// back on the triangle (normal part λ n, λ = gap / (nᵀW_s n + Σ w_j² nᵀW_j n)) with Coulomb friction
/// on the relative tangential motion over the step (stick if the impulse that removes it is within
/// μs λ, else μk λ against it). Outputs rec_tri[i] (−1: no contact), rec_w (3 weights), rec_p (3).
/// Inputs: reference X [m] AoS, mass [kg], u and u⁺ [m] SoA (3, P) (u⁺ after the tool contact).
template <class T>
PLIANT_HD void soft_detect(index_t i, const SoftSurface& s, const double* X, const T* mass, const T* u,
                           const T* u_next, index_t P, const index_t* cand, index_t* rec_tri, double* rec_w,
                           double* rec_p) {
    rec_tri[i] = -1;
    const index_t* list = cand + static_cast<std::size_t>(i) * kSoftCandidates;
    if (list[0] < 0) return;
    double x0[3], x1[3];
    soft_position(i, s, X, u, P, x0);
    soft_position(i, s, X, u_next, P, x1);
    index_t best = -1;
    double best_d = -INFINITY, best_n[3] = {0.0, 0.0, 0.0}, best_w[3] = {0.0, 0.0, 0.0};
    // Triangles whose plane the node is in front of (outside) while projecting onto them, for the
    // inside test below: at most kSoftCandidates, their bodies.
    index_t front[kSoftCandidates];
    int n_front = 0;
    for (int q = 0; q < kSoftCandidates && list[q] >= 0; ++q) {
        const index_t t = list[q];
        const index_t* v = s.tri + 3 * t;
        double a[3], b[3], c[3], n[3], w[3], d1, d0;
        soft_position(v[0], s, X, u_next, P, a);
        soft_position(v[1], s, X, u_next, P, b);
        soft_position(v[2], s, X, u_next, P, c);
        if (!soft_project(a, b, c, x1, n, w, d1)) continue;
        if (w[0] < -kSoftEdge || w[1] < -kSoftEdge || w[2] < -kSoftEdge) continue;
        if (!(d1 < 0.0)) {
            front[n_front++] = s.label[v[0]];
            continue;
        }
        if (!(d1 > best_d || (d1 == best_d && t < best))) continue;
        double a0[3], b0[3], c0[3], n0[3], w0[3];
        soft_position(v[0], s, X, u, P, a0);
        soft_position(v[1], s, X, u, P, b0);
        soft_position(v[2], s, X, u, P, c0);
        if (!soft_project(a0, b0, c0, x0, n0, w0, d0) || d0 < -kSoftBehind * s.tri_h[t]) continue;
        best = t, best_d = d1;
        for (int d = 0; d < 3; ++d) {
            best_n[d] = n[d];
            best_w[d] = w[d] < 0.0 ? 0.0 : w[d];
        }
    }
    if (best < 0) return;
    // Inside test: a node in front of a face of that body which it projects onto is outside it
    // (e.g. a node beside a sliding block's bottom edge, behind its side face's plane only).
    const index_t body = s.label[s.tri[3 * best]];
    for (int q = 0; q < n_front; ++q)
        if (front[q] == body) return;
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
    double rel[3], dot = 0.0;
    for (int d = 0; d < 3; ++d) {
        rel[d] = x1[d] - x0[d];
        for (int k = 0; k < 3; ++k) {
            const index_t j = s.tri[3 * best + k];
            const index_t nj = s.node[j];
            rel[d] -= best_w[k] * (double(u_next[d * P + nj]) - double(u[d * P + nj]));
        }
        dot += rel[d] * best_n[d];
    }
    double tan[3], mag2 = 0.0;
    for (int d = 0; d < 3; ++d) {
        tan[d] = rel[d] - dot * best_n[d];
        mag2 += tan[d] * tan[d];
    }
    double p[3];
    for (int d = 0; d < 3; ++d) p[d] = lambda * best_n[d];
    const index_t pr = s.pair[static_cast<std::size_t>(s.label[i]) * s.labels + s.label[s.tri[3 * best]]];
    const double mag = std::sqrt(mag2);
    if (mag > 0.0) {
        const double e[3] = {tan[0] / mag, tan[1] / mag, tan[2] / mag};
        const double kt = inverse_mass(e);
        if (kt > 0.0) {
            const double stick = mag / kt;
            const double lt = stick <= s.mu[2 * pr] * lambda ? stick : s.mu[2 * pr + 1] * lambda;
            for (int d = 0; d < 3; ++d) p[d] -= lt * e[d];
        }
    }
    rec_tri[i] = best;
    for (int d = 0; d < 3; ++d) {
        rec_w[3 * i + d] = best_w[d];
        rec_p[3 * i + d] = p[d];
    }
}

}  // namespace pliant
