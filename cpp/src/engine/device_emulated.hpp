// pliant — the emulated CUDA device: the CUDA backend's engine, built for the host. Memory is
// separate (the model is copied in and state is copied in and out, as to a GPU, so a missing
// upload shows), kernels run as plain loops on one thread, and graphs are recorded launches
// replayed later (with the arguments they had when captured, as a CUDA graph keeps them). For tests
// and debugging on machines without a GPU: `backend="cuda-emulated"`. What it cannot check is the
// CUDA runtime itself (device_cuda.cuh) and device-side arithmetic differences (docs/engine.md).
#pragma once

#include <cstdlib>
#include <cstring>
#include <functional>
#include <new>
#include <stdexcept>
#include <utility>
#include <vector>

#include "graphs.hpp"
#include "in_order.hpp"
#include "pliant/config.hpp"

namespace pliant {

/// The emulated device's team: SerialTeam with each loop run backwards. A CUDA block's threads take
/// a team's items in no set order; running them here in the reverse of the CPU's order lets a test
/// compare the two devices bit for bit (tests/test_soft_contact.py) where order would show.
struct ReversedTeam : SerialTeam {
    template <class F>
    void each(index_t n, const F& f) const {
        for (index_t i = n - 1; i >= 0; --i) f(i);
    }
};

class EmulatedDevice : public InOrderThen<EmulatedDevice> {
public:
    static constexpr bool kSharesHost = false;
    static constexpr const char* kName = "cuda-emulated";
    static constexpr bool kLaneLoops = false;         // lanes are threads, as on CUDA
    static constexpr bool kPrefetch = false;          // as on CUDA
    static constexpr bool kStreams = false;           // kernel 1 stores its forces as they come
    static constexpr bool kKeepsAnpGradient = false;  // as on CUDA
    using Team = ReversedTeam;                        // the threads of a team launch (each_counted_then_team)
    static constexpr bool kSplitsDetection = true;    // as on CUDA

    EmulatedDevice() = default;
    EmulatedDevice(const EmulatedDevice&) = delete;
    EmulatedDevice& operator=(const EmulatedDevice&) = delete;
    int threads() const { return 1; }

    void* allocate(std::size_t bytes) {
        void* p = std::calloc(bytes ? bytes : 1, 1);
        if (!p) throw std::bad_alloc();
        return p;
    }
    void release(void* p) { std::free(p); }
    void copy_in(void* dst, const void* src, std::size_t bytes) {
        no_capture("copy_in");
        if (bytes) std::memcpy(dst, src, bytes);
    }
    void copy_out(void* dst, const void* src, std::size_t bytes) {
        no_capture("copy_out");
        if (bytes) std::memcpy(dst, src, bytes);
    }

    template <class F>
    void region(F&& body) {
        body();
    }
    template <class F>
    void each(index_t n, const F& f) {
        launch_or_record([n, f] {
            for (index_t i = 0; i < n; ++i) f(i);
        });
    }
    /// CUDA's each_counted: the count is read when the launch runs (replays included).
    template <class F>
    void each_counted(index_t n_max, const index_t* count, const F& f) {
        launch_or_record([n_max, count, f] {
            const index_t n = *count < n_max ? *count : n_max;
            for (index_t i = 0; i < n; ++i) f(i);
        });
    }
    /// As on CUDA: body's launches always run (their kernels test the flag).
    template <class V, class F>
    void when(const V* /*flag*/, F&& body) {
        body();
    }
    template <class F>
    void blocks(index_t b0, index_t b1, const F& f) {
        launch_or_record([b0, b1, f] {
            for (index_t b = b0; b < b1; ++b)
                for (int l = 0; l < kLanes; ++l) f(b, l);
        });
    }
    /// A phased kernel's slot scratch (SlotScratch): each thread's own row, as on CUDA.
    template <class T>
    using Scratch = SlotScratch<T, 1>;
    /// As on CUDA: each slot runs pre, the middle phases of ph (Phases) and post in turn on its own
    /// scratch.
    template <class T, int W, class Pre, class Mid, class Post>
    void blocks_phased(index_t b0, index_t b1, const Phases& ph, const Pre& pre, const Mid& mid,
                       const Post& post) {
        launch_or_record([b0, b1, ph, pre, mid, post] {
            for (index_t b = b0; b < b1; ++b)
                for (int l = 0; l < kLanes; ++l) {
                    T sc[W];
                    const Scratch<T> s{sc};
                    pre(b, l, s);
                    for (int c = 0; c < ph.n; ++c)
                        call_phase(ph.size[c], PhaseSlot{}, mid, b, l, ph.first[c], s);
                    post(b, l, s);
                }
        });
    }
    void barrier() {}  // launches run in order, as on one CUDA stream
    template <class F>
    void serial(const F& f) {
        launch_or_record([f] { f(); });
    }
    /// g(team) on one team: here one thread, its loops backwards (ReversedTeam).
    template <class G>
    void team(const G& g) {
        launch_or_record([g] { g(ReversedTeam{}); });
    }
    template <class V>
    V read(const V* p) {
        no_capture("read");
        return *p;
    }
    template <class F>
    void repeat(long k, long key, F&& body) {
        graphs_.repeat(*this, k, key, body);
    }
    void forget_graphs() { graphs_.clear(); }
    bool lead() const { return true; }
    double wtime() const { return 0.0; }

    // The graph interface of GraphCache.
    using Graph = std::vector<std::function<void()>>;
    void begin_capture() {
        capturing_ = true;
        recorded_.clear();
    }
    Graph end_capture() {
        capturing_ = false;
        return std::move(recorded_);
    }
    void launch(const Graph& g) {
        for (const auto& k : g) k();
    }
    void set_dry(bool dry) { dry_ = dry; }

private:
    void launch_or_record(std::function<void()> k) {
        if (dry_) return;
        if (capturing_)
            recorded_.push_back(std::move(k));
        else
            k();
    }
    void no_capture(const char* what) const {
        if (capturing_ || dry_)
            throw std::logic_error(std::string("emulated CUDA device: ") + what +
                                   " inside a graph capture (not allowed on a CUDA stream)");
    }
    bool capturing_ = false, dry_ = false;
    Graph recorded_;
    GraphCache<Graph> graphs_;
};

}  // namespace pliant
