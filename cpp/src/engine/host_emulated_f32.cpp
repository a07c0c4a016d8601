// pliant — the emulated CUDA backend in single precision (see host_backends.hpp).
#include "host_backends.hpp"

namespace pliant {
template std::unique_ptr<Backend<float>> make_emulated_backend(const Model<float>&);
}  // namespace pliant
