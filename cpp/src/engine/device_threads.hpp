// pliant — the CPU executor: host memory, OpenMP threads across items and SIMD across the lanes of
// an element block. The engine's step (engine.hpp) runs inside one parallel region (region());
// every kernel launch is an orphaned `omp for`, so a step costs a few barriers and no thread
// start-up. Every thread count gives the same bits: an item is computed by the same code whatever
// thread runs it, and sums run in a fixed order (chunked, never per thread).
#pragma once

#include <omp.h>
#if defined(__SSE2__)
#include <immintrin.h>
#endif

#include <atomic>
#include <cstdlib>
#include <cstring>
#include <new>
#include <stdexcept>
#include <string>

#include "pliant/config.hpp"

namespace pliant {

/// Most CPU threads a solver accepts: 4 per processor, at least 64 (far more make OpenMP fail to
/// create them: a crash, refused instead).
inline int thread_limit() { return omp_get_num_procs() * 4 > 64 ? omp_get_num_procs() * 4 : 64; }

class ThreadsDevice {
public:
    static constexpr bool kSharesHost = true;  // model arrays are used in place, not copied
    static constexpr const char* kName = "cpu";
    static constexpr bool kLaneLoops = true;  // lanes run in SIMD loops: uniform branches cost vectorization
    static constexpr bool kPrefetch = true;   // kernel 2 prefetches its gathers on large models
    static constexpr bool kKeepsAnpGradient = true;  // T4ANP's pass (3) reads pass (1)'s gradients
    using Team = SerialTeam;                         // the threads of a team launch (each_counted_then_team)
    // Soft contact: a node's thread computes its candidates' closest points itself (soft_detect);
    // a launch of its own per sweep would cost a wait.
    static constexpr bool kSplitsDetection = false;
    static constexpr bool kStreams = true;  // kernel 1 streams its forces past the caches on large models

    // threads: 1 .. thread_limit(), or <= 0 for OpenMP's default.
    explicit ThreadsDevice(int threads) : threads_(threads > 0 ? threads : omp_get_max_threads()) {
        if (threads_ > thread_limit())
            throw std::invalid_argument("threads = " + std::to_string(threads_) + ": expected 1 to " +
                                        std::to_string(thread_limit()));
    }
    int threads() const { return threads_; }

    // --- memory (zeroed allocations, on cache lines: 64 bytes; copies are memcpy) -----------------
    void* allocate(std::size_t bytes) {
        const std::size_t n = ((bytes ? bytes : 1) + 63) / 64 * 64;
        void* p = std::aligned_alloc(64, n);
        if (!p) throw std::bad_alloc();
        std::memset(p, 0, n);
        return p;
    }
    void release(void* p) { std::free(p); }
    void copy_in(void* dst, const void* src, std::size_t bytes) {
        if (bytes) std::memcpy(dst, src, bytes);
    }
    void copy_out(void* dst, const void* src, std::size_t bytes) {
        if (bytes) std::memcpy(dst, src, bytes);
    }

    // --- launches ----------------------------------------------------------------------------------
    /// Runs body on every thread of one parallel region; the launches below bind to it.
    template <class F>
    void region(F&& body) {
#pragma omp parallel num_threads(threads_)
        body();
    }
    /// f(i) for i in [0, n), split statically across threads; all threads wait at the end.
    template <class F>
    void each(index_t n, const F& f) {
#pragma omp for schedule(static)
        for (index_t i = 0; i < n; ++i) f(i);
    }
    /// f(i) for i in [0, min(*count, n_max)): a count an earlier launch wrote before its wait. Every
    /// thread reads it then, so all split the same range; no thread walks the slots past it.
    template <class F>
    void each_counted(index_t n_max, const index_t* count, const F& f) {
        each(*count < n_max ? *count : n_max, f);
    }
    /// each(n, f), then g() once, on the thread that finished its share of f last (an atomic
    /// ticket: it sees every thread's writes); all threads wait at the end. One wait instead of
    /// each's and serial's two: what a small contact pass spends most on.
    template <class F, class G>
    void each_then(index_t n, const F& f, const G& g) {
#pragma omp for schedule(static) nowait
        for (index_t i = 0; i < n; ++i) f(i);
        if (done_.fetch_add(1, std::memory_order_acq_rel) + 1 == omp_get_num_threads()) {
            done_.store(0, std::memory_order_relaxed);  // nobody reads it again before the wait
            g();
        }
#pragma omp barrier
    }
    /// each_counted(n_max, count, f), then g() once, as each_then.
    template <class F, class G>
    void each_counted_then(index_t n_max, const index_t* count, const F& f, const G& g) {
        each_then(*count < n_max ? *count : n_max, f, g);
    }
    /// each_counted_then(n_max, count, f, g) with g(team) for g(): the team is the one thread
    /// (SerialTeam).
    template <class F, class G>
    void each_counted_then_team(index_t n_max, const index_t* count, const F& f, const G& g) {
        each_counted_then(n_max, count, f, [&] { g(SerialTeam{}); });
    }
    /// body()'s launches if *flag, a value an earlier launch wrote before its wait: every thread reads
    /// it once, before body's first launch (body may change it only after that launch's wait), so all
    /// take the same path. The kernels test the flag too: CUDA launches them whatever it holds.
    template <class V, class F>
    void when(const V* flag, F&& body) {
        if (*flag) body();
    }
    /// f(b, l) for the element slots of blocks [b0, b1): blocks across threads, lanes in SIMD. No
    /// wait at the end (a group's blocks are independent of the next group's): call barrier().
    template <class F>
    void blocks(index_t b0, index_t b1, const F& f) {
#pragma omp for schedule(static) nowait
        for (index_t b = b0; b < b1; ++b) {
#pragma omp simd
            for (int l = 0; l < kLanes; ++l) f(b, l);
        }
    }
    /// A phased kernel's slot scratch (SlotScratch): the block's lanes side by side.
    template <class T>
    using Scratch = SlotScratch<T, kLanes>;
    /// One middle phase of blocks_phased over a block's lanes: its uniform part, then a SIMD loop of
    /// mid<K>. Inlined into blocks_phased (PLIANT_HD): as a call, the phases' scratch went through
    /// memory between them (one Prony term's element pass 0.080 → 0.100 ms a step on the 27,648-tet
    /// bench box).
    template <class T, class Mid>
    struct PhaseLanes {
        const Mid& mid;
        template <int K>
        PLIANT_HD void operator()(index_t b, int first, T* sc) const {
            const auto u = mid.template uniform<K>(b, first);  // once a block, not once a lane
#pragma omp simd
            for (int l = 0; l < kLanes; ++l) mid.template operator()<K>(u, b, l, Scratch<T>{sc + l});
        }
    };
    /// For the element slots of blocks [b0, b1): pre(b, l, s), then for each middle phase c of ph
    /// (Phases) its part mid<K> (K = ph.size[c]) over the lanes, its uniform part once, then
    /// post(b, l, s), s the slot's W values of scratch (Scratch<T>, in the L1 cache). Each phase is
    /// its own SIMD loop over the block's lanes, so that a run-time number of phases runs around the
    /// lanes instead of inside each (where its test would stop the vectorizer). No wait at the end:
    /// call barrier().
    template <class T, int W, class Pre, class Mid, class Post>
    void blocks_phased(index_t b0, index_t b1, const Phases& ph, const Pre& pre, const Mid& mid,
                       const Post& post) {
#pragma omp for schedule(static) nowait
        for (index_t b = b0; b < b1; ++b) {
            alignas(64) T sc[W * kLanes];
#pragma omp simd
            for (int l = 0; l < kLanes; ++l) pre(b, l, Scratch<T>{sc + l});
            for (int c = 0; c < ph.n; ++c)
                call_phase(ph.size[c], PhaseLanes<T, Mid>{mid}, b, ph.first[c], sc);
#pragma omp simd
            for (int l = 0; l < kLanes; ++l) post(b, l, Scratch<T>{sc + l});
        }
    }
    /// blocks(b0, b1, f) for a kernel whose outputs are whole blocks of two AoSoA arrays, K1 and K2
    /// values a slot (kernel 1: forces, K = 12, and J, K = 1): f(b, l, o1, o2) writes slot l of block 0
    /// of o1 and o2, a one-block scratch in the L1 cache, which is then copied to block b of out1 and
    /// out2 with streaming stores. A model beyond the caches saves the read of each line before its
    /// write (52 of kernel 1's 160 bytes of memory traffic a tet in float32). The stores are fenced;
    /// no wait at the end: call barrier(). out1 and out2 from allocate() (on cache lines).
    template <int K1, int K2, class T, class F>
    void blocks_streamed(index_t b0, index_t b1, T* out1, T* out2, const F& f) {
#pragma omp for schedule(static) nowait
        for (index_t b = b0; b < b1; ++b) {
            alignas(64) T s1[K1 * kLanes];
            alignas(64) T s2[K2 * kLanes];
#pragma omp simd
            for (int l = 0; l < kLanes; ++l) f(b, l, s1, s2);
            stream(out1 + static_cast<std::size_t>(b) * K1 * kLanes, s1, sizeof s1);
            stream(out2 + static_cast<std::size_t>(b) * K2 * kLanes, s2, sizeof s2);
        }
#if defined(__SSE2__)
        _mm_sfence();  // streaming stores are weakly ordered: they land before the barrier's
#endif
    }
    void barrier() {
#pragma omp barrier
    }
    /// f() on one thread; all threads wait at the end.
    template <class F>
    void serial(const F& f) {
#pragma omp single
        f();
    }
    /// A value the kernels wrote, the same on every thread.
    template <class V>
    V read(const V* p) {
#pragma omp barrier
        const V v = *p;
#pragma omp barrier
        return v;
    }
    /// k repetitions of a step's launches (CUDA: one graph; here simply the launches).
    template <class F>
    void repeat(long k, long /*key*/, F&& body) {
        for (long s = 0; s < k; ++s) body();
    }
    void forget_graphs() {}

    /// Whether this thread keeps the books (timings, reports): thread 0.
    bool lead() const { return omp_get_thread_num() == 0; }
    /// Wall time [s] for the kernel timings.
    double wtime() const { return omp_get_wtime(); }

private:
    /// Copies bytes (a multiple of 64) from src to dst, both on cache lines, with streaming stores
    /// (non-temporal: past the caches) where the instruction set has them.
    static void stream(void* dst, const void* src, std::size_t bytes) {
        char* d = static_cast<char*>(dst);
        const char* s = static_cast<const char*>(src);
#if defined(__AVX512F__)
        for (std::size_t k = 0; k < bytes; k += 64)
            _mm512_stream_si512(reinterpret_cast<__m512i*>(d + k), _mm512_load_si512(s + k));
#elif defined(__AVX__)
        for (std::size_t k = 0; k < bytes; k += 32)
            _mm256_stream_si256(reinterpret_cast<__m256i*>(d + k),
                                _mm256_load_si256(reinterpret_cast<const __m256i*>(s + k)));
#elif defined(__SSE2__)
        for (std::size_t k = 0; k < bytes; k += 16)
            _mm_stream_si128(reinterpret_cast<__m128i*>(d + k),
                             _mm_load_si128(reinterpret_cast<const __m128i*>(s + k)));
#else
        std::memcpy(d, s, bytes);
#endif
    }

    int threads_;
    std::atomic<int> done_{0};  // threads through each_then's items (0 between launches)
};

}  // namespace pliant
