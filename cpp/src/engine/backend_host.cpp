// pliant — what the host side of the engine answers without a backend: the thread limit, and the
// CUDA entry points of a build without nvcc. The host backends are host_cpu_*.cpp and
// host_emulated_*.cpp.
#include <stdexcept>

#include "backend.hpp"
#include "device_threads.hpp"

namespace pliant {

int thread_limit_value() { return thread_limit(); }

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
