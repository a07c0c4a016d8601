// pliant — the CPU backend in double precision (see host_backends.hpp).
#include "host_backends.hpp"

namespace pliant {
template std::unique_ptr<Backend<double>> make_cpu_backend(const Model<double>&, int);
}  // namespace pliant
