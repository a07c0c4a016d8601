// pliant — the backends that run on the host: the CPU (OpenMP + SIMD) and the emulated CUDA device.
// Both are the one engine of engine.hpp; only the device differs.
#include "device_emulated.hpp"
#include "device_threads.hpp"
#include "engine.hpp"

namespace pliant {

int thread_limit_value() { return thread_limit(); }

template <class T>
std::unique_ptr<Backend<T>> make_cpu_backend(const Model<T>& m, int threads) {
    return std::make_unique<Engine<T, ThreadsDevice>>(m, threads);
}

template <class T>
std::unique_ptr<Backend<T>> make_emulated_backend(const Model<T>& m) {
    return std::make_unique<Engine<T, EmulatedDevice>>(m);
}

template std::unique_ptr<Backend<float>> make_cpu_backend(const Model<float>&, int);
template std::unique_ptr<Backend<double>> make_cpu_backend(const Model<double>&, int);
template std::unique_ptr<Backend<float>> make_emulated_backend(const Model<float>&);
template std::unique_ptr<Backend<double>> make_emulated_backend(const Model<double>&);

#ifndef PLIANT_WITH_CUDA
bool cuda_compiled() { return false; }
std::vector<std::string> cuda_devices(std::string& why) {
    why = "the CUDA backend is not compiled in this build (nvcc was not found when it was built)";
    return {};
}
template <class T>
std::unique_ptr<Backend<T>> make_cuda_backend(const Model<T>&, int) {
    std::string why;
    cuda_devices(why);
    throw std::invalid_argument(why);
}
template std::unique_ptr<Backend<float>> make_cuda_backend(const Model<float>&, int);
template std::unique_ptr<Backend<double>> make_cuda_backend(const Model<double>&, int);
#endif

}  // namespace pliant
