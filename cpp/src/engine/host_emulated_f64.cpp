// pliant — the emulated CUDA backend in double precision (see host_backends.hpp).
#include "host_backends.hpp"

namespace pliant {
template std::unique_ptr<Backend<double>> make_emulated_backend(const Model<double>&);
}  // namespace pliant
