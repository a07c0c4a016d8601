// pliant — the backends that run on the host: the CPU (OpenMP + SIMD) and the emulated CUDA device.
// Both are the one engine of engine.hpp; only the device differs. Each backend and precision is
// instantiated in its own translation unit (host_cpu_f32.cpp, ...), so that a build compiles them
// in parallel; the CPU's per instruction-set module, the emulated device's once (CMakeLists.txt).
#pragma once

#include "device_emulated.hpp"
#include "device_threads.hpp"
#include "engine.hpp"

namespace pliant {

template <class T>
std::unique_ptr<Backend<T>> make_cpu_backend(const Model<T>& m, int threads) {
    return std::make_unique<Engine<T, ThreadsDevice>>(m, threads);
}

template <class T>
std::unique_ptr<Backend<T>> make_emulated_backend(const Model<T>& m) {
    return std::make_unique<Engine<T, EmulatedDevice>>(m);
}

}  // namespace pliant
