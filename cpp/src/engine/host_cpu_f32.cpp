// pliant — the CPU backend in single precision (see host_backends.hpp).
#include "host_backends.hpp"

namespace pliant {
template std::unique_ptr<Backend<float>> make_cpu_backend(const Model<float>&, int);
}  // namespace pliant
