// pliant — the CUDA device layer: the only code that calls the CUDA runtime (allocation, copies,
// the four launch shapes, one stream, graphs). Everything else the CUDA backend does is the
// engine of engine.hpp, which CI runs on the emulated device (device_emulated.hpp) without a GPU.
// Keep this file small: it is what only a machine with a GPU tests (docs/engine.md lists it).
#pragma once

#include <cuda_runtime.h>

#include <memory>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>

#include "graphs.hpp"
#include "in_order.hpp"
#include "pliant/config.hpp"

namespace pliant {

namespace cuda_detail {

inline void check(cudaError_t e, const char* what) {
    if (e != cudaSuccess)
        throw std::runtime_error(std::string("CUDA error in ") + what + ": " + cudaGetErrorString(e));
}

constexpr int kThreads = 128;
inline unsigned grid_for(long n) { return static_cast<unsigned>((n + kThreads - 1) / kThreads); }

template <class F>
__global__ void each_kernel(index_t n, F f) {
    const long i = static_cast<long>(blockIdx.x) * blockDim.x + threadIdx.x;
    if (i < n) f(static_cast<index_t>(i));
}

template <class F>
__global__ void each_counted_kernel(index_t n, const index_t* count, F f) {
    const long i = static_cast<long>(blockIdx.x) * blockDim.x + threadIdx.x;
    if (i < n && i < *count) f(static_cast<index_t>(i));
}

template <class F>
__global__ void blocks_kernel(index_t b0, index_t b1, F f) {
    const long i = static_cast<long>(blockIdx.x) * blockDim.x + threadIdx.x;
    const index_t b = b0 + static_cast<index_t>(i / kLanes);
    if (b < b1) f(b, static_cast<int>(i % kLanes));
}

template <class T, int W, class Pre, class Mid, class Post>
__global__ void blocks_phased_kernel(index_t b0, index_t b1, Phases ph, Pre pre, Mid mid, Post post) {
    const long i = static_cast<long>(blockIdx.x) * blockDim.x + threadIdx.x;
    const index_t b = b0 + static_cast<index_t>(i / kLanes);
    if (b >= b1) return;
    const int l = static_cast<int>(i % kLanes);
    T sc[W];  // registers: every index into it is a constant once the phases are inlined
    const SlotScratch<T, 1> s{sc};
    pre(b, l, s);
    for (int c = 0; c < ph.n; ++c) call_phase(ph.size[c], PhaseSlot{}, mid, b, l, ph.first[c], s);
    post(b, l, s);
}

template <class F>
__global__ void serial_kernel(F f) {
    f();
}

/// Threads of one team launch: a block of kTeamThreads (SerialTeam's interface, config.hpp).
constexpr int kTeamThreads = 256;
struct BlockTeam {
    template <class F>
    PLIANT_HD void each(index_t n, const F& f) const {
#if defined(__CUDA_ARCH__)
        for (index_t i = threadIdx.x; i < n; i += blockDim.x) f(i);
#endif
    }
    PLIANT_HD void sync() const {
#if defined(__CUDA_ARCH__)
        __syncthreads();
#endif
    }
    template <class F>
    PLIANT_HD void one(const F& f) const {
#if defined(__CUDA_ARCH__)
        if (threadIdx.x == 0) f();
#endif
    }
    template <class V>
    PLIANT_HD V add(V* p, V v) const {
        return atomic_add(p, v);
    }
    PLIANT_HD void max(std::int64_t* p, std::int64_t v) const { atomic_max(p, v); }
};

template <class F>
__global__ void __launch_bounds__(kTeamThreads) team_kernel(F f) {
    f(BlockTeam{});
}

#if CUDART_VERSION >= 13000
/// Sets a graph's IF condition from a flag the kernels before it wrote.
template <class V>
__global__ void condition_kernel(cudaGraphConditionalHandle h, const V* flag) {
    cudaGraphSetConditional(h, *flag ? 1u : 0u);
}
#endif

struct ExecDeleter {
    void operator()(CUgraphExec_st* g) const { cudaGraphExecDestroy(g); }
};

}  // namespace cuda_detail

class CudaDevice : public InOrderThen<CudaDevice> {
public:
    static constexpr bool kSharesHost = false;
    static constexpr const char* kName = "cuda";
    static constexpr bool kLaneLoops = false;         // lanes are threads: uniform branches cost nothing
    static constexpr bool kPrefetch = false;          // the GPU hides memory latency with other warps
    static constexpr bool kStreams = false;           // kernel 1 stores its forces as they come
    static constexpr bool kKeepsAnpGradient = false;  // T4ANP's pass (3) recomputes H (not measured)
    using Team = cuda_detail::BlockTeam;              // the threads of a team launch (each_counted_then_team)
    // Soft contact: one thread per (active node, candidate) computes the closest points a launch
    // ahead of the node's (soft_pass): one thread walking its candidates was the longest chain of loads.
    static constexpr bool kSplitsDetection = true;

    explicit CudaDevice(int device) {
        cuda_detail::check(cudaSetDevice(device), "cudaSetDevice");
        cuda_detail::check(cudaStreamCreateWithFlags(&stream_, cudaStreamNonBlocking), "stream");
        cuda_detail::check(cudaStreamCreateWithFlags(&body_stream_, cudaStreamNonBlocking), "stream");
    }
    ~CudaDevice() {
        graphs_.clear();
        if (stream_) cudaStreamDestroy(stream_);
        if (body_stream_) cudaStreamDestroy(body_stream_);
    }
    CudaDevice(const CudaDevice&) = delete;
    CudaDevice& operator=(const CudaDevice&) = delete;
    int threads() const { return 1; }

    void* allocate(std::size_t bytes) {
        void* p = nullptr;
        cuda_detail::check(cudaMalloc(&p, bytes ? bytes : 1), "cudaMalloc");
        // On this stream (non-blocking: it does not wait for the legacy default stream).
        cuda_detail::check(cudaMemsetAsync(p, 0, bytes ? bytes : 1, stream_), "cudaMemset");
        cuda_detail::check(cudaStreamSynchronize(stream_), "cudaMemset");
        return p;
    }
    void release(void* p) { cudaFree(p); }
    void copy_in(void* dst, const void* src, std::size_t bytes) {
        if (!bytes) return;  // ordered on this stream, complete on return (src may go away)
        cuda_detail::check(cudaMemcpyAsync(dst, src, bytes, cudaMemcpyHostToDevice, stream_), "upload");
        cuda_detail::check(cudaStreamSynchronize(stream_), "upload");
    }
    void copy_out(void* dst, const void* src, std::size_t bytes) {
        if (!bytes) return;
        cuda_detail::check(cudaMemcpyAsync(dst, src, bytes, cudaMemcpyDeviceToHost, stream_), "download");
        cuda_detail::check(cudaStreamSynchronize(stream_), "download");
    }

    template <class F>
    void region(F&& body) {
        body();
    }
    template <class F>
    void each(index_t n, const F& f) {
        if (dry_ || n <= 0) return;
        cuda_detail::each_kernel<<<cuda_detail::grid_for(n), cuda_detail::kThreads, 0, stream_>>>(n, f);
        cuda_detail::check(cudaPeekAtLastError(), "launch");
    }
    /// f(i) for i in [0, *count), a count an earlier kernel wrote: a graph's launch has a fixed
    /// size, so n_max threads start and each tests its index against the count.
    template <class F>
    void each_counted(index_t n_max, const index_t* count, const F& f) {
        if (dry_ || n_max <= 0) return;
        cuda_detail::each_counted_kernel<<<cuda_detail::grid_for(n_max), cuda_detail::kThreads, 0, stream_>>>(
            n_max, count, f);
        cuda_detail::check(cudaPeekAtLastError(), "launch");
    }
    /// body's launches if *flag, a value an earlier kernel wrote. In a graph (CUDA 13 and later):
    /// an IF node (a conditional node) holding them, its condition set from *flag by a kernel, so
    /// that a step without a rebuild launches none of them. Otherwise, and launched one by one,
    /// they always run: the kernels test the flag themselves.
    template <class V, class F>
    void when(const V* flag, F&& body) {
#if CUDART_VERSION >= 13000
        cudaStreamCaptureStatus st = cudaStreamCaptureStatusNone;
        if (!dry_) cuda_detail::check(cudaStreamIsCapturing(stream_, &st), "capture status");
        if (st == cudaStreamCaptureStatusActive) return conditional(flag, body);
#else
        (void)flag;
#endif
        body();
    }
    template <class F>
    void blocks(index_t b0, index_t b1, const F& f) {
        if (dry_ || b1 <= b0) return;
        const long n = static_cast<long>(b1 - b0) * kLanes;
        cuda_detail::blocks_kernel<<<cuda_detail::grid_for(n), cuda_detail::kThreads, 0, stream_>>>(b0, b1,
                                                                                                    f);
        cuda_detail::check(cudaPeekAtLastError(), "launch");
    }
    /// A phased kernel's slot scratch (SlotScratch): each thread's own row.
    template <class T>
    using Scratch = SlotScratch<T, 1>;
    /// pre(b, l, s), the middle phases of ph (Phases), post(b, l, s): one thread per slot, in turn.
    template <class T, int W, class Pre, class Mid, class Post>
    void blocks_phased(index_t b0, index_t b1, const Phases& ph, const Pre& pre, const Mid& mid,
                       const Post& post) {
        if (dry_ || b1 <= b0) return;
        const long m = static_cast<long>(b1 - b0) * kLanes;
        cuda_detail::blocks_phased_kernel<T, W>
            <<<cuda_detail::grid_for(m), cuda_detail::kThreads, 0, stream_>>>(b0, b1, ph, pre, mid, post);
        cuda_detail::check(cudaPeekAtLastError(), "launch");
    }
    void barrier() {}  // one stream: launches run in order
    template <class F>
    void serial(const F& f) {
        if (dry_) return;
        cuda_detail::serial_kernel<<<1, 1, 0, stream_>>>(f);
        cuda_detail::check(cudaPeekAtLastError(), "launch");
    }
    /// g(team) on one block of kTeamThreads threads (BlockTeam).
    template <class G>
    void team(const G& g) {
        if (dry_) return;
        cuda_detail::team_kernel<<<1, cuda_detail::kTeamThreads, 0, stream_>>>(g);
        cuda_detail::check(cudaPeekAtLastError(), "launch");
    }
    template <class V>
    V read(const V* p) {
        V v;
        copy_out(&v, p, sizeof(V));
        return v;
    }
    template <class F>
    void repeat(long k, long key, F&& body) {
        graphs_.repeat(*this, k, key, body);
    }
    void forget_graphs() { graphs_.clear(); }
    bool lead() const { return true; }
    double wtime() const { return 0.0; }

    // The graph interface of GraphCache.
    using Graph = std::unique_ptr<CUgraphExec_st, cuda_detail::ExecDeleter>;
    void begin_capture() {
        cuda_detail::check(cudaStreamBeginCapture(stream_, cudaStreamCaptureModeThreadLocal), "capture");
    }
    Graph end_capture() {
        cudaGraph_t graph;
        cuda_detail::check(cudaStreamEndCapture(stream_, &graph), "end capture");
        cudaGraphExec_t exec;
        const cudaError_t e = cudaGraphInstantiate(&exec, graph, 0);
        cudaGraphDestroy(graph);
        cuda_detail::check(e, "graph instantiate");
        return Graph(exec);
    }
    void launch(const Graph& g) { cuda_detail::check(cudaGraphLaunch(g.get(), stream_), "graph launch"); }
    void set_dry(bool dry) { dry_ = dry; }

    /// Number of usable devices; 0 with the reason in `why` when there is no driver or device.
    static int count(std::string& why) {
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
    static std::string name(int device) {
        cudaDeviceProp p{};
        if (cudaGetDeviceProperties(&p, device) != cudaSuccess) return "unknown";
        return p.name;
    }

private:
#if CUDART_VERSION >= 13000
    /// when() in a capture: the IF node after the launches so far, body captured into its graph
    /// on a second stream (CUDA programming guide, "Conditional graph nodes").
    template <class V, class F>
    void conditional(const V* flag, F&& body) {
        using cuda_detail::check;
        cudaStreamCaptureStatus st;
        cudaGraph_t graph;
        check(cudaStreamGetCaptureInfo(stream_, &st, nullptr, &graph), "capture info");
        cudaGraphConditionalHandle h;
        check(cudaGraphConditionalHandleCreate(&h, graph, 0, 0), "conditional handle");
        cuda_detail::condition_kernel<<<1, 1, 0, stream_>>>(h, flag);
        check(cudaPeekAtLastError(), "launch");
        const cudaGraphNode_t* deps = nullptr;
        const cudaGraphEdgeData* edges = nullptr;
        std::size_t n = 0;
        check(cudaStreamGetCaptureInfo(stream_, &st, nullptr, &graph, &deps, &edges, &n), "capture info");
        cudaGraphNodeParams p{};
        p.type = cudaGraphNodeTypeConditional;
        p.conditional.handle = h;
        p.conditional.type = cudaGraphCondTypeIf;
        p.conditional.size = 1;
        cudaGraphNode_t node;
        check(cudaGraphAddNode(&node, graph, deps, edges, n, &p), "conditional node");
        check(
            cudaStreamUpdateCaptureDependencies(stream_, &node, nullptr, 1, cudaStreamSetCaptureDependencies),
            "capture dependencies");
        std::swap(stream_, body_stream_);  // body's launches go to the IF node's graph
        cudaError_t e = cudaStreamBeginCaptureToGraph(stream_, p.conditional.phGraph_out[0], nullptr, nullptr,
                                                      0, cudaStreamCaptureModeThreadLocal);
        if (e == cudaSuccess) {
            try {
                body();
            } catch (...) {
                cudaGraph_t g;
                cudaStreamEndCapture(stream_, &g);
                std::swap(stream_, body_stream_);
                throw;
            }
            cudaGraph_t g;
            e = cudaStreamEndCapture(stream_, &g);
        }
        std::swap(stream_, body_stream_);
        check(e, "capture of a conditional node");
    }
#endif

    cudaStream_t stream_{}, body_stream_{};
    bool dry_ = false;
    GraphCache<Graph> graphs_;
};

}  // namespace pliant
