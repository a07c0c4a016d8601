// pliant — frictional contact of soft-body surface nodes with rigid tools, header-only, host and
// device. Kinematic correction after the explicit predictor (Taylor et al. 2008 §IV-C; Johnsen et
// al. 2015 §2.4: penetrating slave nodes are moved back onto the master surface), with Coulomb
// friction in displacement form: a correction δ of node a carries the force m_a δ / γ1, so the
// stick test |f_t| ≤ μs |f_n| reads |d_t| ≤ μs |δ_n| and slip removes μk |δ_n| of tangential motion.
#pragma once

#include <cmath>

#include "tled.hpp"

namespace pliant {

enum class ToolKind : int { Plane = 0, Sphere = 1, Capsule = 2, Box = 3, Grid = 4, Cylinder = 5 };

/// Tools 0 … kMaskedTools − 1 can be restricted to node sets (bits 3 … 30 of a contact node's
/// bits); later tools act on every contact node.
constexpr int kMaskedTools = 28;

/// Contact-node bits: DOFs 0–2 free (bits 0–2) and the tool mask `tools` (bit k: tool k) above.
PLIANT_HD index_t node_bits(index_t tools) {
    return 7 | static_cast<index_t>((static_cast<unsigned>(tools) << 3) & 0x7ffffff8u);
}

/// A rigid tool: shape parameters in its own frame, friction, and its keyframed trajectory.
/// Plane: the half-space z' ≤ 0 of the tool frame (outward normal +z'). Sphere: radius p[0].
/// Capsule: segment from (0,0,−p[1]) to (0,0,+p[1]) in the tool frame, radius p[0]. Cylinder: the
/// same axis and radius with flat ends. Box: half extents p[0..2]. Grid: signed-distance grid
/// (origin p[0..2], spacing p[3], dims in grid_dims; the surface lies inside it, with a margin).
struct RigidTool {
    ToolKind kind;
    double p[4];
    double mu_s, mu_k;
    index_t key_begin, key_count;  // keyframes: time [s], position [m] (3), quaternion (w,x,y,z)
    index_t grid_begin, grid_dims[3];
    index_t grip_begin, grip_count;  // grasping: times [s] it closes, opens, closes… (ascending)
    double reach;                    // a closing tool grasps the nodes within this distance [m]
};

/// Whether a grasping tool is closed at time t [s]: an odd number of its close/open times lie
/// before t (closed on (t_close, t_open]: a tool that closes at t0 holds from the step after t0).
PLIANT_HD bool tool_closed(const RigidTool& tl, double t, const double* grips) {
    int before = 0;
    for (index_t j = 0; j < tl.grip_count; ++j) before += grips[tl.grip_begin + j] < t ? 1 : 0;
    return (before & 1) != 0;
}

/// Grip bits of a tool over a step from t to t + Δt: bit 0 closed at t, bit 1 closed at t + Δt
/// (value 2: it closes during the step and grasps).
constexpr index_t kGripClosedBefore = 1, kGripClosedAfter = 2;

struct Pose {
    double R[9];  // rotation, row-major: x_world = R x_tool + t
    double t[3];
};

/// Pose of a tool at time t [s]: linear interpolation of positions and normalized linear
/// interpolation of quaternions between keyframes, held before the first and after the last.
PLIANT_HD Pose tool_pose(const RigidTool& tool, double t, const double* keys) {
    const double* k = keys + 8 * tool.key_begin;
    index_t i = 0;
    double w = 0.0;
    if (tool.key_count > 1 && t > k[0]) {
        if (t >= k[8 * (tool.key_count - 1)]) {
            i = tool.key_count - 1;
        } else {
            while (k[8 * (i + 1)] < t) ++i;
            w = (t - k[8 * i]) / (k[8 * (i + 1)] - k[8 * i]);
        }
    }
    const double* a = k + 8 * i;
    const double* b = (w > 0.0) ? a + 8 : a;
    double q[4], n = 0.0;
    double sgn = (a[4] * b[4] + a[5] * b[5] + a[6] * b[6] + a[7] * b[7]) < 0.0 ? -1.0 : 1.0;
    for (int c = 0; c < 4; ++c) {
        q[c] = (1.0 - w) * a[4 + c] + w * sgn * b[4 + c];
        n += q[c] * q[c];
    }
    n = 1.0 / std::sqrt(n);
    const double qw = q[0] * n, qx = q[1] * n, qy = q[2] * n, qz = q[3] * n;
    Pose P;
    P.R[0] = 1 - 2 * (qy * qy + qz * qz);
    P.R[1] = 2 * (qx * qy - qz * qw);
    P.R[2] = 2 * (qx * qz + qy * qw);
    P.R[3] = 2 * (qx * qy + qz * qw);
    P.R[4] = 1 - 2 * (qx * qx + qz * qz);
    P.R[5] = 2 * (qy * qz - qx * qw);
    P.R[6] = 2 * (qx * qz - qy * qw);
    P.R[7] = 2 * (qy * qz + qx * qw);
    P.R[8] = 1 - 2 * (qx * qx + qy * qy);
    for (int c = 0; c < 3; ++c) P.t[c] = (1.0 - w) * a[1 + c] + w * b[1 + c];
    return P;
}

PLIANT_HD void to_tool(const Pose& P, const double x[3], double out[3]) {
    const double d[3] = {x[0] - P.t[0], x[1] - P.t[1], x[2] - P.t[2]};
    for (int r = 0; r < 3; ++r) out[r] = P.R[r] * d[0] + P.R[3 + r] * d[1] + P.R[6 + r] * d[2];
}
PLIANT_HD void to_world(const Pose& P, const double y[3], double out[3]) {
    for (int r = 0; r < 3; ++r)
        out[r] = P.R[3 * r] * y[0] + P.R[3 * r + 1] * y[1] + P.R[3 * r + 2] * y[2] + P.t[r];
}
PLIANT_HD void rotate(const Pose& P, const double y[3], double out[3]) {
    for (int r = 0; r < 3; ++r) out[r] = P.R[3 * r] * y[0] + P.R[3 * r + 1] * y[1] + P.R[3 * r + 2] * y[2];
}

/// Signed distance φ [m] of point y (tool frame) to the tool's surface, negative inside, and the
/// outward unit normal n (tool frame). Grid: trilinear interpolation of a signed-distance grid,
/// normal from its gradient.
PLIANT_HD double tool_sdf(const RigidTool& tl, const double y[3], const double* grid, double n[3]) {
    switch (tl.kind) {
        case ToolKind::Plane:
            n[0] = 0.0;
            n[1] = 0.0;
            n[2] = 1.0;
            return y[2];
        case ToolKind::Sphere:
        case ToolKind::Capsule: {
            double c[3] = {0.0, 0.0, 0.0};
            if (tl.kind == ToolKind::Capsule)
                c[2] = y[2] < -tl.p[1] ? -tl.p[1] : (y[2] > tl.p[1] ? tl.p[1] : y[2]);
            const double d[3] = {y[0] - c[0], y[1] - c[1], y[2] - c[2]};
            const double r = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            if (r > 0.0) {
                n[0] = d[0] / r;
                n[1] = d[1] / r;
                n[2] = d[2] / r;
            } else {
                n[0] = 0.0;
                n[1] = 0.0;
                n[2] = 1.0;
            }
            return r - tl.p[0];
        }
        case ToolKind::Box: {
            double q[3], out2 = 0.0, inside = -1e300;
            int arg = 0;
            for (int c = 0; c < 3; ++c) {
                q[c] = std::fabs(y[c]) - tl.p[c];
                if (q[c] > 0.0) out2 += q[c] * q[c];
                if (q[c] > inside) {
                    inside = q[c];
                    arg = c;
                }
            }
            if (out2 > 0.0) {
                const double r = std::sqrt(out2);
                for (int c = 0; c < 3; ++c) n[c] = q[c] > 0.0 ? (y[c] < 0.0 ? -q[c] : q[c]) / r : 0.0;
                return r;
            }
            for (int c = 0; c < 3; ++c) n[c] = 0.0;
            n[arg] = y[arg] < 0.0 ? -1.0 : 1.0;
            return inside;
        }
        case ToolKind::Cylinder: {  // flat ends: radius p[0], axis z from −p[1] to +p[1]
            const double r = std::sqrt(y[0] * y[0] + y[1] * y[1]);
            const double dr = r - tl.p[0], dz = std::fabs(y[2]) - tl.p[1];
            const double er[3] = {r > 0.0 ? y[0] / r : 1.0, r > 0.0 ? y[1] / r : 0.0, 0.0};
            const double ez = y[2] < 0.0 ? -1.0 : 1.0;
            if (dr > 0.0 && dz > 0.0) {  // beyond the rim: nearest point on the edge circle
                const double d = std::sqrt(dr * dr + dz * dz);
                n[0] = dr * er[0] / d;
                n[1] = dr * er[1] / d;
                n[2] = dz * ez / d;
                return d;
            }
            if (dr > dz) {
                n[0] = er[0];
                n[1] = er[1];
                n[2] = 0.0;
                return dr;
            }
            n[0] = 0.0;
            n[1] = 0.0;
            n[2] = ez;
            return dz;
        }
        default: {  // Grid
            const index_t nx = tl.grid_dims[0], ny = tl.grid_dims[1], nz = tl.grid_dims[2];
            double g[3], off[3], off2 = 0.0;
            index_t i0[3];
            const index_t dims[3] = {nx, ny, nz};
            for (int c = 0; c < 3; ++c) {
                g[c] = (y[c] - tl.p[c]) / tl.p[3];
                if (!std::isfinite(g[c])) {  // a non-finite position: no contact (the check reports it)
                    n[0] = 0.0;
                    n[1] = 0.0;
                    n[2] = 1.0;
                    return INFINITY;
                }
                // Outside the grid (which holds the surface with a margin), the point is clamped
                // onto the grid's box and its distance to the box added below: extrapolating the
                // trilinear field far beyond its last cell is not a distance, and can be negative.
                const double gc = g[c] < 0.0 ? 0.0 : (g[c] > dims[c] - 1 ? double(dims[c] - 1) : g[c]);
                off[c] = (g[c] - gc) * tl.p[3];
                off2 += off[c] * off[c];
                g[c] = gc;
                double f = std::floor(g[c]);
                if (f > dims[c] - 2) f = dims[c] - 2;
                i0[c] = static_cast<index_t>(f);
                g[c] -= f;
            }
            const double* G = grid + tl.grid_begin;
            auto at = [&](index_t a, index_t b, index_t c) { return G[(a * ny + b) * nz + c]; };
            double v[2][2][2];
            for (int a = 0; a < 2; ++a)
                for (int b = 0; b < 2; ++b)
                    for (int c = 0; c < 2; ++c) v[a][b][c] = at(i0[0] + a, i0[1] + b, i0[2] + c);
            const double x = g[0], yy = g[1], z = g[2];
            auto lerp = [](double p, double q, double s) { return p + s * (q - p); };
            const double phi =
                lerp(lerp(lerp(v[0][0][0], v[0][0][1], z), lerp(v[0][1][0], v[0][1][1], z), yy),
                     lerp(lerp(v[1][0][0], v[1][0][1], z), lerp(v[1][1][0], v[1][1][1], z), yy), x);
            n[0] = lerp(lerp(v[1][0][0] - v[0][0][0], v[1][0][1] - v[0][0][1], z),
                        lerp(v[1][1][0] - v[0][1][0], v[1][1][1] - v[0][1][1], z), yy);
            n[1] = lerp(lerp(v[0][1][0] - v[0][0][0], v[0][1][1] - v[0][0][1], z),
                        lerp(v[1][1][0] - v[1][0][0], v[1][1][1] - v[1][0][1], z), x);
            n[2] = lerp(lerp(v[0][0][1] - v[0][0][0], v[0][1][1] - v[0][1][0], yy),
                        lerp(v[1][0][1] - v[1][0][0], v[1][1][1] - v[1][1][0], yy), x);
            if (off2 > 0.0) {  // outside the grid: at least its distance to the grid's box
                const double d = std::sqrt(off2);
                for (int c = 0; c < 3; ++c) n[c] = off[c] / d;
                return d + (phi > 0.0 ? phi : 0.0);
            }
            const double r = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            if (r > 0.0) {
                n[0] /= r;
                n[1] /= r;
                n[2] /= r;
            } else {
                n[2] = 1.0;
            }
            return phi;
        }
    }
}

/// The contact part of contact_node: x1 (the node at t + Δt) moved out of every tool it comes
/// nearer than skin [m] to (a sheet's half thickness: its face meets the tool, not its mid-surface),
/// with friction against the tool's motion from x0; tool_out[i]: the last tool touched.
PLIANT_HD void contact_tools(index_t i, const index_t* node_bits, const RigidTool* tools, int n_tools,
                             const Pose* pose0, const Pose* pose1, const double* grid, double skin,
                             const double x0[3], double x1[3], index_t* tool_out) {
    for (int k = 0; k < n_tools; ++k) {
        if (k < kMaskedTools && !((node_bits[i] >> (3 + k)) & 1)) continue;
        double y[3], nt[3], nw[3];
        to_tool(pose1[k], x1, y);
        const double phi = tool_sdf(tools[k], y, grid, nt) - skin;
        if (!(phi < 0.0)) continue;
        rotate(pose1[k], nt, nw);
        double dn = -phi;
        for (int d = 0; d < 3; ++d) x1[d] += dn * nw[d];
        // Tool displacement over the step at the node's previous position (rigid motion).
        double y0[3], w1[3];
        to_tool(pose0[k], x0, y0);
        to_world(pose1[k], y0, w1);
        double drel[3], dot = 0.0;
        for (int d = 0; d < 3; ++d) {
            drel[d] = (x1[d] - x0[d]) - (w1[d] - x0[d]);
            dot += drel[d] * nw[d];
        }
        double dt_[3], mag2 = 0.0;
        for (int d = 0; d < 3; ++d) {
            dt_[d] = drel[d] - dot * nw[d];
            mag2 += dt_[d] * dt_[d];
        }
        const double mag = std::sqrt(mag2);
        if (mag > 0.0) {
            const double s = mag <= tools[k].mu_s * dn ? 1.0 : tools[k].mu_k * dn / mag;
            for (int d = 0; d < 3; ++d) x1[d] -= s * dt_[d];
        }
        tool_out[i] = k;
    }
}

/// Grasp of contact node i by a tool closing during this step: the first such tool (allowed on
/// the node) whose surface is within its reach (plus the node's skin [m]) of x⁺ [m] holds it from
/// now on at its tool-frame position (grip_tool, grip_at). Returns the tool, or −1.
PLIANT_HD index_t try_grasp(index_t i, const index_t* node_bits, const RigidTool* tools, int n_tools,
                            const Pose* pose1, const index_t* closed, const double* grid, double skin,
                            const double x1[3], index_t* grip_tool, double* grip_at) {
    for (int k = 0; k < n_tools; ++k) {
        if (closed[k] != kGripClosedAfter) continue;
        if (k < kMaskedTools && !((node_bits[i] >> (3 + k)) & 1)) continue;
        double y[3], nt[3];
        to_tool(pose1[k], x1, y);
        if (!(tool_sdf(tools[k], y, grid, nt) <= tools[k].reach + skin)) continue;
        grip_tool[i] = k;
        for (int d = 0; d < 3; ++d) grip_at[3 * i + d] = y[d];
        return k;
    }
    return -1;
}

/// Contact kernel, one surface node per lane: for each tool in turn, a node x⁺ = X + u⁺ with
/// φ(x⁺) < s (its skin: 0, or a sheet's half thickness) is moved out along the normal by
/// δ_n = (s − φ) n, then friction acts on its tangential
/// motion relative to the tool over the step, d_t: stick (remove d_t) if |d_t| ≤ μs|δ_n|, else slip
/// (remove μk|δ_n| along d_t). The force it took, m (x_corrected − x⁺)/γ1 [N], is stored per node
/// in force_out (3) with the tool index in tool_out (−1: no contact; force_out then untouched).
/// Only the node's free DOFs move (node_bits[i] bit d: DOF d is not constrained): on a symmetry
/// plane or a roller the constraint carries the rest of the correction. Tool k < kMaskedTools acts
/// on the node only if bit 3 + k is set (tools restricted to node sets, NiftySim's SlvNodes).
/// Grasping: a node held by a closed tool (grip_tool[i] = k) moves with it, at its tool-frame
/// position grip_at (3 per contact node), and the force that takes is the grasp force; a tool
/// that opens lets its nodes go; a tool that closes during the step grasps (try_grasp).
/// Inputs: contact node i → node nodes[i], its bits and skin [m] (a sheet's half thickness: contact_tools),
/// reference X [m] (3 per node, AoS, double), mass [kg], u and u⁺ [m] SoA (3, P), tools with their poses at t
/// and t + Δt and their grip bits (closed), du⁺ the step's increment [m] SoA. Outputs: u⁺ corrected and du⁺
/// plus the correction where corrected (the next step's velocity, node_update; added in double rather than
/// taken as u⁺ − u, which would round the increment again), force_out, tool_out; grip_tool,
/// grip_at updated.
template <class T>
PLIANT_HD void contact_node(index_t i, const index_t* nodes, const index_t* node_bits, const double* skin,
                            const double* X, const T* mass, const T* u, index_t P, const RigidTool* tools,
                            int n_tools, const Pose* pose0, const Pose* pose1, const index_t* closed,
                            const double* grid, double g1, T* u_next, T* du_next, double* force_out,
                            index_t* tool_out, index_t* grip_tool, double* grip_at) {
    const index_t n = nodes[i];
    double x0[3], x1[3], xs[3];
    for (int d = 0; d < 3; ++d) {
        x0[d] = X[3 * n + d] + double(u[d * P + n]);
        x1[d] = X[3 * n + d] + double(u_next[d * P + n]);
        xs[d] = x1[d];
    }
    tool_out[i] = -1;
    const index_t held = grip_tool[i];
    if (held >= 0 && (closed[held] & kGripClosedAfter)) {  // held: it moves with the jaws
        to_world(pose1[held], grip_at + 3 * i, x1);
        tool_out[i] = held;
    } else {
        if (held >= 0) grip_tool[i] = -1;  // the tool opened: released
        contact_tools(i, node_bits, tools, n_tools, pose0, pose1, grid, skin[i], x0, x1, tool_out);
        const index_t g =
            try_grasp(i, node_bits, tools, n_tools, pose1, closed, grid, skin[i], x1, grip_tool, grip_at);
        if (g >= 0 && tool_out[i] < 0) tool_out[i] = g;
    }
    if (tool_out[i] < 0) return;  // force_out is only meaningful where tool_out >= 0
    const double m_over_g1 = double(mass[n]) / g1;
    for (int d = 0; d < 3; ++d) {
        const bool free = (node_bits[i] >> d) & 1;
        force_out[3 * i + d] = free ? m_over_g1 * (x1[d] - xs[d]) : 0.0;
        if (!free) continue;
        u_next[d * P + n] = T(x1[d] - X[3 * n + d]);
        du_next[d * P + n] = T(double(du_next[d * P + n]) + (x1[d] - xs[d]));  // + the correction
    }
}

/// Adds contact node i's reaction to its tool's row of h (6 per tool: force [N] the tool
/// receives, then torque [N·m] about the tool's position at t + Δt). No-op without contact.
template <class T>
PLIANT_HD void add_tool_reaction(index_t i, const index_t* nodes, const double* X, const T* u_next, index_t P,
                                 const Pose* pose1, const double* force, const index_t* tool, double* h) {
    const index_t k = tool[i];
    if (k < 0) return;
    const index_t n = nodes[i];
    const double* f = force + 3 * i;
    double r[3];
    for (int d = 0; d < 3; ++d) {
        h[6 * k + d] -= f[d];  // the tool receives the reaction
        r[d] = X[3 * n + d] + double(u_next[d * P + n]) - pose1[k].t[d];
    }
    h[6 * k + 3] -= r[1] * f[2] - r[2] * f[1];
    h[6 * k + 4] -= r[2] * f[0] - r[0] * f[2];
    h[6 * k + 5] -= r[0] * f[1] - r[1] * f[0];
}

}  // namespace pliant
