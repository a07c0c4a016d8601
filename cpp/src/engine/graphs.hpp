// pliant — replaying a step's launches as a graph (CUDA graphs, or the emulated device's recorded
// launches): the first time a (step count, key) pair is seen, the host runs the step's body with
// the device capturing its launches; afterwards the host runs the body "dry" (only its own book-
// keeping, such as rotating the displacement buffers; launches are skipped) and the device replays
// the captured graph. `key` names what the host bookkeeping bakes into the launches (the buffer
// phase), so one graph serves every repetition with the same key. Graphs live for one engine call.
#pragma once

#include <utility>
#include <vector>

namespace pliant {

template <class Graph>
class GraphCache {
public:
    /// dev: begin_capture(), end_capture() → Graph, launch(const Graph&), set_dry(bool).
    template <class Dev, class F>
    void repeat(Dev& dev, long k, long key, F&& body) {
        for (Entry& e : entries_) {
            if (e.k != k || e.key != key) continue;
            dev.set_dry(true);
            for (long s = 0; s < k; ++s) body();
            dev.set_dry(false);
            dev.launch(e.graph);
            return;
        }
        dev.begin_capture();
        for (long s = 0; s < k; ++s) body();
        entries_.push_back(Entry{k, key, dev.end_capture()});
        dev.launch(entries_.back().graph);
    }
    void clear() { entries_.clear(); }
    std::size_t size() const { return entries_.size(); }

private:
    struct Entry {
        long k, key;
        Graph graph;
    };
    std::vector<Entry> entries_;
};

}  // namespace pliant
