// pliant — building the bending of membrane triangles (membrane.hpp, membrane_bending_forces): each
// bending membrane's patch coefficients from its reference geometry.
//
// A triangle's curvature is its mean second derivative, by the divergence theorem over the
// triangle in its convected coordinates ξ (the Basic Shell Triangle: Oñate & Zárate 2000, IJNME
// 47:557): H_αβ = −2 Σ_e ∂N_e/∂ξβ (∂x/∂ξα|_e − ∂x/∂ξα|_own), edge e opposite corner e. The gradient
// at an edge is one shared by the two triangles that meet there, so that the edges' terms cancel
// inside the sheet (the patch test: a constant moment gives no force inside). Here it is the
// gradient at the edge's midpoint of the quadratic fitted, in the least-squares sense, to the
// edge's stencil (its two nodes, the two opposite nodes and the nodes across the two triangles'
// other edges, unfolded into one plane about the edge): exact for any quadratic shape on any mesh.
// Where the stencil has too few nodes for a quadratic (next to the boundary), the gradient from the
// edge's four nodes (NiftySim's tledElementShellBSTP1Edge: exact where the two triangles form a
// parallelogram); the triangle's own at a free edge, the reference one at a clamped edge.
#include "model.hpp"

#include <algorithm>
#include <cmath>
#include <string>

namespace pliant {

namespace {

/// The largest stencil of an edge: its two nodes and the two opposite, two across each triangle
/// (eight); a free edge's: its triangle, two across it and two across each of those (nine).
constexpr int kStencil = 9;

struct Vec {
    double v[3];
    double operator[](int d) const { return v[d]; }
};

Vec node_at(const ModelInput& in, index_t n) {
    const double* p = &in.X[3 * static_cast<std::size_t>(n)];
    return {{p[0], p[1], p[2]}};
}

double dot(const Vec& a, const Vec& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
Vec sub(const Vec& a, const Vec& b) { return {{a[0] - b[0], a[1] - b[1], a[2] - b[2]}}; }
Vec axpy(double s, const Vec& a, const Vec& b) {
    return {{s * a[0] + b[0], s * a[1] + b[1], s * a[2] + b[2]}};
}

/// The unit vector in the plane of the edge (a, b) and the point o, perpendicular to the edge, on
/// o's side; false where o lies on the edge's line.
bool toward(const Vec& a, const Vec& t, const Vec& o, Vec& m) {
    const Vec r = sub(o, a);
    m = axpy(-dot(r, t), t, r);
    const double len = std::sqrt(dot(m, m));
    if (!(len > 1e-8 * std::sqrt(dot(r, r)))) return false;
    m = {{m[0] / len, m[1] / len, m[2] / len}};
    return true;
}

/// The point y across the edge (a, b) of a triangle (a, b, o), unfolded into the triangle's plane
/// about the edge (its distance from the edge kept, on the far side from o). False where o or y
/// lies on the edge's line.
bool unfold(const Vec& a, const Vec& b, const Vec& o, const Vec& y, Vec& Y) {
    Vec t = sub(b, a), m, my;
    const double lt = std::sqrt(dot(t, t));
    t = {{t[0] / lt, t[1] / lt, t[2] / lt}};
    if (!toward(a, t, o, m) || !toward(a, t, y, my)) return false;
    const Vec r = sub(y, a);
    const double along = dot(r, t), off = dot(r, my);
    Y = axpy(-off, m, axpy(along, t, a));
    return true;
}

/// The gradient at the origin of the quadratic fitted by least squares to n points s [1] of a
/// chart: grad[q][p], the coefficient of point p's value in ∂/∂s_q. False with fewer than six
/// points or where they lie (nearly) on one conic.
bool quadratic_gradient(int n, const double s[kStencil][2], double grad[2][kStencil]) {
    if (n < 6) return false;
    double A[6][6 + kStencil] = {};  // [VᵀV | Vᵀ], V the points' rows of 1, s1, s2, s1², s1 s2, s2²
    for (int p = 0; p < n; ++p) {
        const double x = s[p][0], y = s[p][1];
        const double row[6] = {1.0, x, y, x * x, x * y, y * y};
        for (int r = 0; r < 6; ++r) {
            for (int c = 0; c < 6; ++c) A[r][c] += row[r] * row[c];
            A[r][6 + p] = row[r];
        }
    }
    double largest = 0.0;
    for (int col = 0; col < 6; ++col) {  // Gauss–Jordan with partial pivoting
        int piv = col;
        for (int r = col + 1; r < 6; ++r)
            if (std::fabs(A[r][col]) > std::fabs(A[piv][col])) piv = r;
        largest = std::max(largest, std::fabs(A[piv][col]));
        if (!(std::fabs(A[piv][col]) > 1e-10 * largest)) return false;
        for (int k = 0; k < 6 + n; ++k) std::swap(A[col][k], A[piv][k]);
        const double inv = 1.0 / A[col][col];
        for (int k = 0; k < 6 + n; ++k) A[col][k] *= inv;
        for (int r = 0; r < 6; ++r)
            if (r != col && A[r][col] != 0.0) {
                const double f = A[r][col];
                for (int k = 0; k < 6 + n; ++k) A[r][k] -= f * A[col][k];
            }
    }
    for (int p = 0; p < n; ++p) grad[0][p] = A[1][6 + p], grad[1][p] = A[2][6 + p];
    return true;
}

/// Corner a's shape gradient ∂N_a/∂ξ in a triangle's convected coordinates.
constexpr double kDN[3][2] = {{-1.0, -1.0}, {1.0, 0.0}, {0.0, 1.0}};

/// An edge's stencil in a chart about the edge: s = ((Y − o)·t, (Y − o)·m) / l, o its midpoint,
/// t along it, m across it in the plane of the triangle a point was unfolded into, l its length.
/// A node met twice (a vertex of few triangles: across one triangle's edge and across its
/// neighbour's) is one point at the mean of its unfoldings, and none of the first four again: the
/// same stencil from both triangles of an edge.
struct Stencil {
    const index_t* slot_node;
    Vec o, t;
    double l;
    double s[kStencil][2];
    int slot[kStencil], count[kStencil], n = 0;

    Stencil(const index_t* nodes, const Vec& a, const Vec& b) : slot_node(nodes) {
        t = sub(b, a);
        l = std::sqrt(dot(t, t));
        t = {{t[0] / l, t[1] / l, t[2] / l}};
        o = axpy(0.5, sub(b, a), a);
    }
    void add(int sl, const Vec& Y, const Vec& across) {
        const double s0 = dot(sub(Y, o), t) / l, s1 = dot(sub(Y, o), across) / l;
        for (int q = 0; q < n; ++q)
            if (slot_node[slot[q]] == slot_node[sl]) {
                if (q < 4) return;
                s[q][0] = (s[q][0] * count[q] + s0) / (count[q] + 1);
                s[q][1] = (s[q][1] * count[q] + s1) / (count[q] + 1);
                ++count[q];
                return;
            }
        if (n < kStencil) s[n][0] = s0, s[n][1] = s1, slot[n] = sl, count[n++] = 1;
    }
    /// ∂s_q/∂ξα [1] of a triangle with tangents G [m] lying in the chart across m: J[α][q].
    void jacobian(const Vec* G, const Vec& m, double J[2][2]) const {
        for (int a = 0; a < 2; ++a) J[a][0] = dot(G[a], t) / l, J[a][1] = dot(G[a], m) / l;
    }
    /// The least-squares quadratic's gradient at the midpoint as ∂x/∂ξα of a triangle with
    /// tangents G lying in the chart across m (coefficients added to mid); false where it fails.
    bool fit(const Vec* G, const Vec& m, double mid[2][kMembraneSlots]) const {
        double grad[2][kStencil], J[2][2];
        if (!quadratic_gradient(n, s, grad)) return false;
        jacobian(G, m, J);
        for (int a = 0; a < 2; ++a)
            for (int p = 0; p < n; ++p) mid[a][slot[p]] += grad[0][p] * J[a][0] + grad[1][p] * J[a][1];
        return true;
    }
};

/// The gradient ∂x/∂ξα at the midpoint of a membrane's edge e (opposite corner e, with a node
/// across it) as coefficients on the patch's slots, mid[α][slot] (the file's header): the
/// least-squares quadratic over the edge's stencil, unfolded into a chart about the edge (axes
/// along the edge and across it in each triangle's plane), or the four nodes' gradient where that
/// fails. False where a triangle of the edge is degenerate.
bool edge_gradient(const ModelInput& in, int e, const index_t* slot_node, const Vec* G,
                   double mid[2][kMembraneSlots]) {
    const int i = (e + 1) % 3, j = (e + 2) % 3;
    const Vec Xi = node_at(in, slot_node[i]), Xj = node_at(in, slot_node[j]), Xe = node_at(in, slot_node[e]);
    const Vec Xk = node_at(in, slot_node[3 + e]);
    Stencil st(slot_node, Xi, Xj);
    Vec mT, mN;  // across the edge in each triangle's plane: the own away from e, the other toward k
    if (!toward(Xi, st.t, Xe, mT) || !toward(Xi, st.t, Xk, mN)) return false;
    mT = {{-mT[0], -mT[1], -mT[2]}};
    st.add(i, Xi, mT), st.add(j, Xj, mT), st.add(e, Xe, mT), st.add(3 + e, Xk, mN);
    Vec Y;
    // The own triangle's other across nodes (unfolded into its plane), then the other's.
    if (slot_node[3 + i] >= 0 && unfold(Xj, Xe, Xi, node_at(in, slot_node[3 + i]), Y)) st.add(3 + i, Y, mT);
    if (slot_node[3 + j] >= 0 && unfold(Xe, Xi, Xj, node_at(in, slot_node[3 + j]), Y)) st.add(3 + j, Y, mT);
    if (slot_node[6 + 2 * e] >= 0 && unfold(Xj, Xk, Xi, node_at(in, slot_node[6 + 2 * e]), Y))
        st.add(6 + 2 * e, Y, mN);
    if (slot_node[7 + 2 * e] >= 0 && unfold(Xk, Xi, Xj, node_at(in, slot_node[7 + 2 * e]), Y))
        st.add(7 + 2 * e, Y, mN);
    if (st.fit(G, mT, mid)) return true;
    // The four nodes' gradient: the linear map taking the edge (s_j − s_i) to x_j − x_i and the
    // segment between the opposite nodes (s_k − s_e) to x_k − x_e.
    const double a0 = st.s[1][0] - st.s[0][0], a1 = st.s[1][1] - st.s[0][1];
    const double c0 = st.s[3][0] - st.s[2][0], c1 = st.s[3][1] - st.s[2][1];
    const double dd = a0 * c1 - a1 * c0;
    if (!(std::fabs(dd) > 0.0)) return false;
    const double r0[2] = {c1 / dd, -c0 / dd}, r1[2] = {-a1 / dd, a0 / dd};  // rows of [a c]⁻¹
    double J[2][2];
    st.jacobian(G, mT, J);
    for (int a = 0; a < 2; ++a)
        for (int q = 0; q < 2; ++q) {
            mid[a][j] += r0[q] * J[a][q], mid[a][i] -= r0[q] * J[a][q];
            mid[a][3 + e] += r1[q] * J[a][q], mid[a][e] -= r1[q] * J[a][q];
        }
    return true;
}

/// The gradient at the midpoint of a free edge e (no node across it) from its own side: the
/// least-squares quadratic over the triangle, its other neighbours' nodes and theirs (unfolded
/// into its plane), so that a boundary triangle's curvature is exact for quadratic shapes too and
/// the edge's moment-free condition is left to the energy (a natural boundary condition). False
/// where fewer than six points or no unique quadratic (the triangle's own gradient then).
bool free_edge_gradient(const ModelInput& in, int e, const index_t* slot_node, const Vec* G,
                        double mid[2][kMembraneSlots]) {
    const int i = (e + 1) % 3, j = (e + 2) % 3;
    const Vec X[3] = {node_at(in, slot_node[0]), node_at(in, slot_node[1]), node_at(in, slot_node[2])};
    Stencil st(slot_node, X[i], X[j]);
    Vec mT;
    if (!toward(X[i], st.t, X[e], mT)) return false;
    mT = {{-mT[0], -mT[1], -mT[2]}};
    st.add(i, X[i], mT), st.add(j, X[j], mT), st.add(e, X[e], mT);
    for (int f : {i, j}) {  // the own edge opposite corner f, its node across, and theirs
        const int a = (f + 1) % 3, b = (f + 2) % 3;
        if (slot_node[3 + f] < 0) continue;
        const Vec Xk = node_at(in, slot_node[3 + f]);
        Vec Y, Z;
        if (!unfold(X[a], X[b], X[f], Xk, Y)) continue;
        st.add(3 + f, Y, mT);
        // Across the neighbour's edges opposite corners a and b: unfolded into its plane, then
        // with it into the triangle's.
        if (slot_node[6 + 2 * f] >= 0 && unfold(X[b], Xk, X[a], node_at(in, slot_node[6 + 2 * f]), Z) &&
            unfold(X[a], X[b], X[f], Z, Y))
            st.add(6 + 2 * f, Y, mT);
        if (slot_node[7 + 2 * f] >= 0 && unfold(Xk, X[a], X[b], node_at(in, slot_node[7 + 2 * f]), Z) &&
            unfold(X[a], X[b], X[f], Z, Y))
            st.add(7 + 2 * f, Y, mT);
    }
    return st.fit(G, mT, mid);
}

/// Each patch node's share of the bending's relaxation stiffness [N/m]: a quarter of its row sum
/// in the stiffness's bound |K_pq| ≤ A0 D (1 + |ν|) n_p n_q (Gershgorin), n_p the norm of the
/// physical curvature a unit normal move of node p gives (n_p² = tr((G⁻¹ B_p)²), B_p its
/// coefficients in convected components), as an element's M Δt_c⁻² is a quarter of ω² M.
/// ``scale``: A0 D (1 + |ν|) [N·m³]. Adds to stiff (per node).
template <class T>
void add_relaxation_stiffness(const T* b, const Vec* G, const index_t* slot_node, double scale,
                              std::vector<double>& stiff) {
    const double g11 = dot(G[0], G[0]), g22 = dot(G[1], G[1]), g12 = dot(G[0], G[1]);
    const double det = g11 * g22 - g12 * g12;
    const double i11 = g22 / det, i22 = g11 / det, i12 = -g12 / det;
    double norm[kMembraneSlots], sum = 0.0;
    for (int p = 0; p < kMembraneSlots; ++p) {
        const double k11 = double(b[p]), k22 = double(b[kMembraneSlots + p]),
                     k12 = double(b[2 * kMembraneSlots + p]);
        const double m11 = i11 * k11 + i12 * k12, m12 = i11 * k12 + i12 * k22;  // G⁻¹ B_p
        const double m21 = i12 * k11 + i22 * k12, m22 = i12 * k12 + i22 * k22;
        norm[p] = slot_node[p] < 0 ? 0.0 : std::sqrt(std::max(m11 * m11 + 2.0 * m12 * m21 + m22 * m22, 0.0));
        sum += norm[p];
    }
    for (int p = 0; p < kMembraneSlots; ++p)
        if (slot_node[p] >= 0) stiff[slot_node[p]] += 0.25 * scale * norm[p] * sum;
}

}  // namespace

/// Membrane m's bending values (membrane_bending_forces, kBendValues; the file's header for the
/// method): per edge the gradient at its midpoint as coefficients on the patch's slots, the
/// curvature's B and its constant part (clamped edges), H0 and κ0 at the reference positions,
/// the moduli A0 D ν, A0 D (1 − ν)/2, D = E_b h³ / (12 (1 − ν²)). Returns an upper estimate of the
/// membrane's highest bending frequency [rad/s], 4 √(D / ρh) / alt², alt its smallest altitude
/// [m]: the plate's dispersion ω = k² √(D / ρh) at the mesh's shortest wave; measured by Lanczos on
/// sheets of regular and jittered triangles where bending sets the step (h / alt 2.4), the
/// factor is 2.9–3.0 (docs/engine.md, "Bending").
template <class T>
double Model<T>::build_bending(const ModelInput& in, index_t m, double area, double alt, NodeSums& sums) {
    const index_t* c = &in.mem_nodes[3 * static_cast<std::size_t>(m)];
    const index_t* nb = &in.mem_nbrs[static_cast<std::size_t>(kMembraneNbrs) * m];
    index_t slot_node[kMembraneSlots];
    for (int p = 0; p < kMembraneSlots; ++p) {
        slot_node[p] = p < 3 ? c[p] : nb[p - 3];
        if (p >= 3 && slot_node[p] >= n_nodes)
            throw std::invalid_argument("membrane " + std::to_string(m) + ": patch node " +
                                        std::to_string(slot_node[p]) + " is out of range");
    }
    const Vec X0 = node_at(in, c[0]);
    Vec G[2];
    for (int a = 0; a < 2; ++a) G[a] = sub(node_at(in, c[1 + a]), X0);
    double B[2][2][kMembraneSlots] = {}, Hc[2][2][3] = {};  // H_αβ's coefficients, its constant part
    for (int e = 0; e < 3; ++e) {
        const index_t k = nb[e];
        double mid[2][kMembraneSlots] = {};  // ∂x/∂ξα at the edge, coefficients on the slots
        if (k == kFreeEdge && !free_edge_gradient(in, e, slot_node, G, mid)) continue;  // the own: no term
        if (k == kClampedEdge) {  // the reference tangents
            for (int a = 0; a < 2; ++a)
                for (int be = 0; be < 2; ++be)
                    for (int d = 0; d < 3; ++d) Hc[a][be][d] += -2.0 * kDN[e][be] * G[a][d];
        } else if (k >= 0 && !edge_gradient(in, e, slot_node, G, mid)) {
            throw std::invalid_argument("membrane " + std::to_string(m) + ": its neighbour across edge " +
                                        std::to_string(e) + " is degenerate (zero area)");
        }
        for (int a = 0; a < 2; ++a)
            for (int be = 0; be < 2; ++be) {
                const double w = -2.0 * kDN[e][be];
                for (int p = 0; p < kMembraneSlots; ++p) B[a][be][p] += w * mid[a][p];
                for (int q = 0; q < 3; ++q) B[a][be][q] -= w * kDN[q][a];
            }
    }
    T* b = &mem_bend[static_cast<std::size_t>(kBendValues) * m];
    Vec N = {{G[0][1] * G[1][2] - G[0][2] * G[1][1], G[0][2] * G[1][0] - G[0][0] * G[1][2],
              G[0][0] * G[1][1] - G[0][1] * G[1][0]}};
    const double nn = std::sqrt(dot(N, N));
    N = {{N[0] / nn, N[1] / nn, N[2] / nn}};
    static const int ab[3][2] = {{0, 0}, {1, 1}, {0, 1}};
    for (int q = 0; q < 3; ++q) {
        const int a = ab[q][0], be = ab[q][1];
        double H0[3] = {0.0, 0.0, 0.0};
        for (int p = 0; p < kMembraneSlots; ++p) {
            const double coef = q < 2 ? B[a][be][p] : 0.5 * (B[0][1][p] + B[1][0][p]);
            b[kMembraneSlots * q + p] = T(coef);
            if (slot_node[p] >= 0)
                for (int d = 0; d < 3; ++d) H0[d] += coef * node_at(in, slot_node[p])[d];
        }
        double kappa0 = 0.0;
        for (int d = 0; d < 3; ++d) {
            H0[d] += q < 2 ? Hc[a][be][d] : 0.5 * (Hc[0][1][d] + Hc[1][0][d]);
            b[kBendH0 + 3 * q + d] = T(H0[d]);
            kappa0 += N[d] * H0[d];
        }
        b[kBendKappa0 + q] = T(kappa0);
    }
    const double* p = &in.mem_params[kMembraneParams * static_cast<std::size_t>(m)];
    const double* pb = &in.mem_bend[2 * static_cast<std::size_t>(m)];
    const double h = p[0], nu = pb[1];
    const double D = pb[0] * h * h * h / (12.0 * (1.0 - nu * nu));
    b[kBendModuli] = T(area * D * nu), b[kBendModuli + 1] = T(area * D * 0.5 * (1.0 - nu));
    add_relaxation_stiffness(b, G, slot_node, area * D * (1.0 + std::fabs(nu)), sums.stiff);
    return 4.0 * std::sqrt(D / (p[1] * h)) / (alt * alt);
}

template double Model<float>::build_bending(const ModelInput&, index_t, double, double, NodeSums&);
template double Model<double>::build_bending(const ModelInput&, index_t, double, double, NodeSums&);

}  // namespace pliant
