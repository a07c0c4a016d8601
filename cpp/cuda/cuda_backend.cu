// pliant — CUDA backend: device-resident model and state, the kernels of tled.hpp and contact.hpp
// launched one element / one node per thread, the step loop captured in CUDA graphs.
#include <cuda_runtime.h>

#include <cstdio>
#include <stdexcept>
#include <string>

#include "cuda_backend.hpp"

namespace pliant::cuda {

namespace {

void check(cudaError_t e, const char* what) {
    if (e != cudaSuccess)
        throw std::runtime_error(std::string("CUDA error in ") + what + ": " + cudaGetErrorString(e));
}

template <class V>
V* upload_vec(const std::vector<V>& v) {
    V* d = nullptr;
    const std::size_t n = v.empty() ? 1 : v.size();
    check(cudaMalloc(&d, n * sizeof(V)), "cudaMalloc");
    if (!v.empty()) check(cudaMemcpy(d, v.data(), v.size() * sizeof(V), cudaMemcpyHostToDevice), "upload");
    return d;
}

constexpr int kThreads = 128;
constexpr index_t kChunk = 512;
inline unsigned grid_for(long n) { return static_cast<unsigned>((n + kThreads - 1) / kThreads); }

/// Kernel 1 (element forces), one element slot per thread, for one material group.
template <class T, class Mat>
__global__ void element_kernel(index_t b0, index_t b1, Mat mat, ElementData<T> el, const T* u,
                               index_t P, T* f_out, T* J_out) {
    const long i = static_cast<long>(blockIdx.x) * blockDim.x + threadIdx.x;
    const index_t b = b0 + static_cast<index_t>(i / kLanes);
    if (b >= b1) return;
    element_forces(b, static_cast<int>(i % kLanes), mat, el, u, P, f_out, J_out);
}

/// T4ANP pass 1: V0 p(J) per element slot, for one (decoupled) material group.
template <class T, class Mat>
__global__ void element_pressure_kernel(index_t b0, index_t b1, Mat mat, ElementData<T> el,
                                        const T* u, index_t P, T* ep_out) {
    const long i = static_cast<long>(blockIdx.x) * blockDim.x + threadIdx.x;
    const index_t b = b0 + static_cast<index_t>(i / kLanes);
    if (b >= b1) return;
    element_pressure(b, static_cast<int>(i % kLanes), mat, el, u, P, ep_out);
}

/// T4ANP pass 2: volume-averaged nodal pressures, one node per thread.
template <class T>
__global__ void nodal_pressure_kernel(index_t n_nodes, const index_t* inc_off, const index_t* inc_idx,
                                      const T* ep, const T* node_volume, T* np_out) {
    const index_t n = static_cast<index_t>(blockIdx.x * blockDim.x + threadIdx.x);
    if (n >= n_nodes) return;
    np_out[n] = nodal_pressure(n, inc_off, inc_idx, ep, node_volume);
}

/// T4ANP pass 3: element forces with the corners' mean nodal pressure, for one material group.
template <class T, class Mat>
__global__ void element_anp_kernel(index_t b0, index_t b1, Mat mat, ElementData<T> el, const T* u,
                                   index_t P, const T* node_p, T* f_out, T* J_out) {
    const long i = static_cast<long>(blockIdx.x) * blockDim.x + threadIdx.x;
    const index_t b = b0 + static_cast<index_t>(i / kLanes);
    if (b >= b1) return;
    element_forces_anp(b, static_cast<int>(i % kLanes), mat, el, u, P, node_p, f_out, J_out);
}

/// Load-curve factors at t and t + Δt (t = t0 + step·Δt, read from device memory), pattern factors,
/// tool poses. One thread.
template <class T>
__global__ void curves_kernel(const LoadCurve* curves, int nc, const double* tt, const double* tv,
                              const index_t* pattern_curve, int np, const RigidTool* tools, int nt,
                              const double* keys, const double* t0, const long* step, double dt,
                              T* cnext_out, T* pf_out, Pose* pose0_out, Pose* pose1_out) {
    if (threadIdx.x != 0 || blockIdx.x != 0) return;
    const double t = *t0 + static_cast<double>(*step) * dt;
    for (int c = 0; c < nc; ++c) cnext_out[c] = T(curve_value(curves[c], t + dt, tt, tv));
    for (int k = 0; k < np; ++k) pf_out[k] = T(curve_value(curves[pattern_curve[k]], t, tt, tv));
    for (int k = 0; k < nt; ++k) {
        pose0_out[k] = tool_pose(tools[k], t, keys);
        pose1_out[k] = tool_pose(tools[k], t + dt, keys);
    }
}

/// Kernel 2 (gather + central-difference update + the node's constraints), one node per thread.
template <class T>
__global__ void node_kernel(index_t n_nodes, NodeData<T> nd, const T* f_elem, const T* pf,
                            Integrator<T> it, const T* u, const T* u_prev, index_t P, T* u_out,
                            const index_t* co, const index_t* cdof, const T* cval,
                            const index_t* ccurve, const T* cnext) {
    const index_t n = static_cast<index_t>(blockIdx.x * blockDim.x + threadIdx.x);
    if (n >= n_nodes) return;
    node_update(n, nd, f_elem, pf, it, u, u_prev, P, u_out, static_cast<T*>(nullptr));
    for (index_t i = co[n]; i < co[n + 1]; ++i) apply_constraint(i, cdof, cval, ccurve, cnext, u_out);
}

/// Contact, one chunk of contact nodes per thread (fixed chunks: deterministic force sums).
template <class T>
__global__ void contact_kernel(index_t nc, const index_t* nodes, const index_t* node_bits,
                               const double* X, const T* mass,
                               const T* u, index_t P, const RigidTool* tools, int nt,
                               const Pose* pose0, const Pose* pose1, const double* grid, double g1,
                               T* u_next, double* force, index_t* tool, double* chunk_out) {
    const index_t c = static_cast<index_t>(blockIdx.x * blockDim.x + threadIdx.x);
    const index_t begin = c * kChunk;
    if (begin >= nc) return;
    double* h = chunk_out + static_cast<std::size_t>(c) * 6 * nt;
    for (int k = 0; k < 6 * nt; ++k) h[k] = 0.0;
    const index_t end = begin + kChunk < nc ? begin + kChunk : nc;
    for (index_t i = begin; i < end; ++i) {
        contact_node(i, nodes, node_bits, X, mass, u, P, tools, nt, pose0, pose1, grid, g1, u_next, force,
                     tool);
        add_tool_reaction(i, nodes, X, u_next, P, pose1, force, tool, h);
    }
}

/// Per-tool sums of the chunk partials in chunk order (one thread), into the step's history row;
/// then the step counter advances.
__global__ void finish_step_kernel(index_t chunks, int nt, const double* chunk, double* hist,
                                   long* step) {
    if (threadIdx.x != 0 || blockIdx.x != 0) return;
    double* hist_row = hist + (*step) * 6 * nt;
    for (int k = 0; k < 6 * nt; ++k) {
        double s = 0.0;
        for (index_t c = 0; c < chunks; ++c) s += chunk[static_cast<std::size_t>(c) * 6 * nt + k];
        hist_row[k] = s;
    }
    *step += 1;
}

struct Status {
    int status;
    index_t where;
    double value;
};

/// Stability check: the smallest bad element (J ≤ 0 or NaN) and node (non-finite or |u| > limit).
template <class T>
__global__ void check_kernel(index_t slots, const index_t* elem_id, const T* J, index_t n_nodes,
                             const T* u, index_t P, double blowup, int* bad_elem, int* bad_node) {
    const long i = static_cast<long>(blockIdx.x) * blockDim.x + threadIdx.x;
    if (i < slots && elem_id[i] >= 0 && !(J[i] > T(0))) atomicMin(bad_elem, elem_id[i]);
    if (i < n_nodes)
        for (int d = 0; d < 3; ++d) {
            const double v = u[d * P + i];
            if (!(fabs(v) <= blowup)) atomicMin(bad_node, static_cast<int>(i));
        }
}

}  // namespace

int device_count(std::string& why) {
    int n = 0;
    const cudaError_t e = cudaGetDeviceCount(&n);
    if (e != cudaSuccess) {
        why = cudaGetErrorString(e);
        cudaGetLastError();
        return 0;
    }
    if (n == 0) why = "no CUDA device";
    return n;
}

std::string device_name(int device) {
    cudaDeviceProp p{};
    if (cudaGetDeviceProperties(&p, device) != cudaSuccess) return "unknown";
    return p.name;
}

template <class T>
struct CudaEngine<T>::Impl {
    const Model<T>& m;
    int device;
    cudaStream_t stream{};
    // model
    index_t* elem_nodes{};
    T *elem_grad{}, *elem_vol{}, *mass{}, *inv_mass{}, *patterns{}, *cval{};
    index_t *elem_id{}, *inc_off{}, *inc_idx{}, *co{}, *cdof{}, *ccurve{}, *pcurve{}, *cnodes{},
        *cfree{}, *pf_off{}, *pf_idx{}, *pnodes{}, *pslot{};
    T *pedges{}, *pvalue{}, *node_vol{}, *elem_p{}, *node_p{};
    LoadCurve* curves{};
    double *tt{}, *tv{}, *X{}, *keys{}, *grid{};
    RigidTool* tools{};
    // state and scratch
    T *u[3]{}, *f_elem{}, *J{}, *cnext{}, *pf{};
    Pose *pose0{}, *pose1{};
    double *cforce{}, *chunk{}, *hist{}, *t0{};
    index_t* ctool{};
    long* step{};
    int *bad{};
    int cur = 1, prev = 0, next = 2;
    index_t chunks = 0;
    long hist_steps = 0;

    Impl(const Model<T>& model, int dev) : m(model), device(dev) {
        check(cudaSetDevice(dev), "cudaSetDevice");
        check(cudaStreamCreateWithFlags(&stream, cudaStreamNonBlocking), "stream");
        elem_nodes = upload_vec(m.elem_nodes);
        elem_grad = upload_vec(m.elem_grad);
        elem_vol = upload_vec(m.elem_vol);
        elem_id = upload_vec(m.elem_id);
        inc_off = upload_vec(m.inc_offsets);
        inc_idx = upload_vec(m.inc_index);
        mass = upload_vec(m.mass);
        inv_mass = upload_vec(m.inv_mass);
        patterns = upload_vec(m.load_patterns);
        pcurve = upload_vec(m.pattern_curve);
        co = upload_vec(m.cons_offsets);
        cdof = upload_vec(m.cons_dof);
        cval = upload_vec(m.cons_value);
        ccurve = upload_vec(m.cons_curve);
        curves = upload_vec(m.curves);
        tt = upload_vec(m.table_t);
        tv = upload_vec(m.table_v);
        X = upload_vec(m.X);
        cnodes = upload_vec(m.contact_nodes);
        cfree = upload_vec(m.contact_bits);
        pf_off = upload_vec(m.pface_offsets);
        pf_idx = upload_vec(m.pface_index);
        pnodes = upload_vec(m.press_nodes);
        pslot = upload_vec(m.press_slot);
        pedges = upload_vec(m.press_edges);
        pvalue = upload_vec(m.press_value);
        node_vol = upload_vec(m.node_volume);
        tools = upload_vec(m.tools);
        keys = upload_vec(m.tool_keys);
        grid = upload_vec(m.tool_grid);
        const std::size_t P3 = 3 * static_cast<std::size_t>(m.n_pad);
        const std::size_t S = static_cast<std::size_t>(m.n_blocks) * kLanes;
        for (auto& v : u) {
            check(cudaMalloc(&v, P3 * sizeof(T)), "cudaMalloc u");
            check(cudaMemset(v, 0, P3 * sizeof(T)), "memset u");
        }
        check(cudaMalloc(&f_elem, 12 * S * sizeof(T)), "cudaMalloc f");
        check(cudaMalloc(&J, S * sizeof(T)), "cudaMalloc J");
        check(cudaMalloc(&elem_p, (m.anp ? S : 1) * sizeof(T)), "cudaMalloc elem_p");
        check(cudaMalloc(&node_p, (m.anp ? m.n_pad : 1) * sizeof(T)), "cudaMalloc node_p");
        check(cudaMalloc(&cnext, (m.curves.size() + 1) * sizeof(T)), "cudaMalloc c");
        check(cudaMalloc(&pf, (m.pattern_curve.size() + 1) * sizeof(T)), "cudaMalloc pf");
        const std::size_t nt = m.tools.size(), nc = m.contact_nodes.size();
        chunks = static_cast<index_t>((nc + kChunk - 1) / kChunk);
        check(cudaMalloc(&pose0, (nt + 1) * sizeof(Pose)), "pose");
        check(cudaMalloc(&pose1, (nt + 1) * sizeof(Pose)), "pose");
        check(cudaMalloc(&cforce, (3 * nc + 1) * sizeof(double)), "cforce");
        check(cudaMalloc(&ctool, (nc + 1) * sizeof(index_t)), "ctool");
        check(cudaMalloc(&chunk, (static_cast<std::size_t>(chunks) * 6 * nt + 1) * sizeof(double)), "chunk");
        check(cudaMalloc(&t0, sizeof(double)), "t0");
        check(cudaMalloc(&step, sizeof(long)), "step");
        check(cudaMalloc(&bad, 2 * sizeof(int)), "bad");
    }

    ~Impl() {
        void* ptrs[] = {elem_nodes, elem_grad, elem_vol, elem_id, inc_off, inc_idx, mass, inv_mass,
                        patterns, pcurve, co, cdof, cval, ccurve, curves, tt, tv, X, cnodes, cfree, pf_off,
                        pf_idx, pnodes, pslot, pedges, pvalue, node_vol, elem_p, node_p, tools,
                        keys, grid, u[0], u[1], u[2], f_elem, J, cnext, pf, pose0, pose1, cforce,
                        ctool, chunk, t0, step, bad, hist};
        for (void* p : ptrs)
            if (p) cudaFree(p);
        if (stream) cudaStreamDestroy(stream);
    }

    // One step: curves/poses, kernel 1 per group, kernel 2, contact, bookkeeping (the history row
    // and the time come from the device step counter, so a captured graph can be replayed).
    void enqueue_step(double dt, const Integrator<T>& it) {
        const int nt = static_cast<int>(m.tools.size());
        const int nc = static_cast<int>(m.curves.size());
        const int np = static_cast<int>(m.pattern_curve.size());
        curves_kernel<T><<<1, 1, 0, stream>>>(curves, nc, tt, tv, pcurve, np, tools, nt, keys, t0,
                                             step, dt, cnext, pf, pose0, pose1);
        const ElementData<T> el{elem_nodes, elem_grad, elem_vol};
        if (m.anp) {  // T4ANP: element pressures, nodal averages, then forces
            for (const Group<T>& g : m.groups) {
                const long slots = static_cast<long>(g.block_end - g.block_begin) * kLanes;
                with_material(g.material, [&](auto mat) {
                    if constexpr (decltype(mat)::decoupled)
                        element_pressure_kernel<T, decltype(mat)><<<grid_for(slots), kThreads, 0,
                                                                     stream>>>(
                            g.block_begin, g.block_end, mat, el, u[cur], m.n_pad, elem_p);
                    return 0;
                });
            }
            nodal_pressure_kernel<T><<<grid_for(m.n_nodes), kThreads, 0, stream>>>(
                m.n_nodes, inc_off, inc_idx, elem_p, node_vol, node_p);
        }
        for (const Group<T>& g : m.groups) {
            const long slots = static_cast<long>(g.block_end - g.block_begin) * kLanes;
            with_material(g.material, [&](auto mat) {
                if constexpr (decltype(mat)::decoupled) {
                    if (m.anp) {
                        element_anp_kernel<T, decltype(mat)><<<grid_for(slots), kThreads, 0, stream>>>(
                            g.block_begin, g.block_end, mat, el, u[cur], m.n_pad, node_p, f_elem, J);
                        return 0;
                    }
                }
                element_kernel<T, decltype(mat)><<<grid_for(slots), kThreads, 0, stream>>>(
                    g.block_begin, g.block_end, mat, el, u[cur], m.n_pad, f_elem, J);
                return 0;
            });
        }
        const NodeData<T> nd{inc_off, inc_idx, inv_mass, patterns, m.n_load_patterns,
                             pf_off, pf_idx, pnodes, pedges, pvalue, pslot};
        node_kernel<T><<<grid_for(m.n_nodes), kThreads, 0, stream>>>(
            m.n_nodes, nd, f_elem, pf, it, u[cur], u[prev], m.n_pad, u[next], co, cdof, cval, ccurve,
            cnext);
        if (nt) {
            contact_kernel<T><<<grid_for(chunks), kThreads, 0, stream>>>(
                static_cast<index_t>(m.contact_nodes.size()), cnodes, cfree, X, mass, u[cur], m.n_pad,
                tools, nt, pose0, pose1, grid, double(it.g1), u[next], cforce, ctool, chunk);
        }
        finish_step_kernel<<<1, 1, 0, stream>>>(chunks, nt, chunk, hist, step);
        const int p = prev;
        prev = cur;
        cur = next;
        next = p;
    }
};

template <class T>
CudaEngine<T>::CudaEngine(const Model<T>& model, int device) : p_(new Impl(model, device)) {}

template <class T>
CudaEngine<T>::~CudaEngine() = default;

template <class T>
std::size_t CudaEngine<T>::device_bytes() const {
    const std::size_t S = static_cast<std::size_t>(p_->m.n_blocks) * kLanes;
    return p_->m.bytes() + (3 * 3 * static_cast<std::size_t>(p_->m.n_pad) + 13 * S) * sizeof(T);
}

template <class T>
void CudaEngine<T>::upload(const State<T>& s) {
    Impl& d = *p_;
    const std::size_t bytes = s.u.size() * sizeof(T);
    check(cudaMemcpy(d.u[d.cur], s.u.data(), bytes, cudaMemcpyHostToDevice), "upload u");
    check(cudaMemcpy(d.u[d.prev], s.u_prev.data(), bytes, cudaMemcpyHostToDevice), "upload u_prev");
}

template <class T>
void CudaEngine<T>::download(State<T>& s) {
    Impl& d = *p_;
    const std::size_t bytes = s.u.size() * sizeof(T);
    check(cudaMemcpyAsync(s.u.data(), d.u[d.cur], bytes, cudaMemcpyDeviceToHost, d.stream), "download u");
    check(cudaMemcpyAsync(s.u_prev.data(), d.u[d.prev], bytes, cudaMemcpyDeviceToHost, d.stream),
          "download u_prev");
    check(cudaStreamSynchronize(d.stream), "download");
}

template <class T>
RunReport CudaEngine<T>::run(long n, double t_start, double dt, double alpha, int check_every,
                             double blowup) {
    Impl& d = *p_;
    RunReport rep;
    const Integrator<T> it = central_difference<T>(dt, alpha);
    const std::size_t nt = d.m.tools.size();
    const std::size_t row = 6 * (nt ? nt : 1);
    if (d.hist) cudaFree(d.hist);
    check(cudaMalloc(&d.hist, (static_cast<std::size_t>(n) + 1) * row * sizeof(double)), "hist");
    const long zero = 0;
    check(cudaMemcpyAsync(d.t0, &t_start, sizeof(double), cudaMemcpyHostToDevice, d.stream), "t0");
    check(cudaMemcpyAsync(d.step, &zero, sizeof(long), cudaMemcpyHostToDevice, d.stream), "step");
    const long G = check_every > 0 ? check_every : 1;
    // Graphs of k steps, one per buffer phase (the three displacement buffers rotate each step):
    // at most 2 step counts (G and the remainder) × 3 phases, replayed with no host work per step.
    struct Cached { long k; int phase; cudaGraphExec_t exec; };
    std::vector<Cached> cache;
    long done = 0;
    while (done < n) {
        const long k = (n - done) < G ? (n - done) : G;
        const int phase = d.cur;
        cudaGraphExec_t exec = nullptr;
        for (const Cached& c : cache)
            if (c.k == k && c.phase == phase) exec = c.exec;
        if (!exec) {
            cudaGraph_t graph;
            check(cudaStreamBeginCapture(d.stream, cudaStreamCaptureModeThreadLocal), "capture");
            const int c0 = d.cur, p0 = d.prev, n0 = d.next;
            for (long s = 0; s < k; ++s) d.enqueue_step(dt, it);
            check(cudaStreamEndCapture(d.stream, &graph), "end capture");
            check(cudaGraphInstantiate(&exec, graph, 0), "instantiate");
            cudaGraphDestroy(graph);
            d.cur = c0;
            d.prev = p0;
            d.next = n0;
            cache.push_back({k, phase, exec});
        }
        check(cudaGraphLaunch(exec, d.stream), "graph launch");
        for (long s = 0; s < k; ++s) {  // the captured steps rotated the buffers k times
            const int p = d.prev;
            d.prev = d.cur;
            d.cur = d.next;
            d.next = p;
        }
        done += k;
        // Stability check on the newest state (one small copy back).
        const int init[2] = {0x7fffffff, 0x7fffffff};
        check(cudaMemcpyAsync(d.bad, init, sizeof(init), cudaMemcpyHostToDevice, d.stream), "bad");
        const std::size_t S = static_cast<std::size_t>(d.m.n_blocks) * kLanes;
        const long nmax = static_cast<long>(S) > d.m.n_nodes ? static_cast<long>(S) : d.m.n_nodes;
        check_kernel<T><<<grid_for(nmax), kThreads, 0, d.stream>>>(
            static_cast<index_t>(S), d.elem_id, d.J, d.m.n_nodes, d.u[d.cur], d.m.n_pad, blowup,
            d.bad, d.bad + 1);
        int bad[2];
        check(cudaMemcpyAsync(bad, d.bad, sizeof(bad), cudaMemcpyDeviceToHost, d.stream), "bad");
        check(cudaStreamSynchronize(d.stream), "sync");
        if (bad[0] != 0x7fffffff || bad[1] != 0x7fffffff) {
            rep.status = bad[0] != 0x7fffffff ? 2 : 3;
            rep.where = bad[0] != 0x7fffffff ? bad[0] : bad[1];
            rep.t = t_start + done * dt;
            break;
        }
    }
    for (const Cached& c : cache) cudaGraphExecDestroy(c.exec);
    rep.steps = done;
    if (rep.status == 0) rep.t = t_start + done * dt;
    history_.assign(static_cast<std::size_t>(done) * 6 * nt, 0.0);
    if (nt) {
        for (long s = 0; s < done; ++s)
            check(cudaMemcpy(history_.data() + s * 6 * nt, d.hist + s * row, 6 * nt * sizeof(double),
                             cudaMemcpyDeviceToHost), "history");
    }
    return rep;
}

template class CudaEngine<float>;
template class CudaEngine<double>;

}  // namespace pliant::cuda
