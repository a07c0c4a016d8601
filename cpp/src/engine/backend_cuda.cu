// pliant — the CUDA backend: the one engine of engine.hpp on the CUDA device layer.
#include "device_cuda.cuh"
#include "engine.hpp"

namespace pliant {

bool cuda_compiled() { return true; }

std::vector<std::string> cuda_devices(std::string& why) {
    std::vector<std::string> names;
    const int n = CudaDevice::count(why);
    for (int i = 0; i < n; ++i) names.push_back(CudaDevice::name(i));
    return names;
}

template <class T>
std::unique_ptr<Backend<T>> make_cuda_backend(const Model<T>& m, int device) {
    std::string why;
    const int n = CudaDevice::count(why);
    if (n == 0) throw std::invalid_argument("no usable CUDA device: " + why);
    if (device < 0 || device >= n)
        throw std::invalid_argument("CUDA device " + std::to_string(device) + " does not exist (" +
                                    std::to_string(n) + " present)");
    return std::make_unique<Engine<T, CudaDevice>>(m, device);
}

template std::unique_ptr<Backend<float>> make_cuda_backend(const Model<float>&, int);
template std::unique_ptr<Backend<double>> make_cuda_backend(const Model<double>&, int);

}  // namespace pliant
