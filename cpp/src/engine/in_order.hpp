// pliant — the fused launches of devices whose launches run one after another in order (CUDA's one
// stream, the emulated device): a launch, then a one-thread step, is simply the two launches. The
// CPU device fuses them into one wait (device_threads.hpp).
#pragma once

#include "pliant/config.hpp"

namespace pliant {

/// each_then, each_counted_then and each_counted_then_team for Device (CRTP), from its each,
/// each_counted, serial and team.
template <class Device>
class InOrderThen {
public:
    /// each(n, f), then g() on one thread.
    template <class F, class G>
    void each_then(index_t n, const F& f, const G& g) {
        self().each(n, f);
        self().serial(g);
    }
    /// each_counted(n_max, count, f), then g() on one thread.
    template <class F, class G>
    void each_counted_then(index_t n_max, const index_t* count, const F& f, const G& g) {
        self().each_counted(n_max, count, f);
        self().serial(g);
    }

    /// each_counted(n_max, count, f), then g(team) on one team (SerialTeam; CUDA: a block).
    template <class F, class G>
    void each_counted_then_team(index_t n_max, const index_t* count, const F& f, const G& g) {
        self().each_counted(n_max, count, f);
        self().team(g);
    }

private:
    Device& self() { return static_cast<Device&>(*this); }
};

}  // namespace pliant
