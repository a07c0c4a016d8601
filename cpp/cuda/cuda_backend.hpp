// pliant — CUDA backend interface (no CUDA types: included by the C++ bindings). The device code in
// cuda_backend.cu launches the very kernels of tled.hpp / contact.hpp that the CPU backend runs.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "cpu_solver.hpp"  // RunReport
#include "model.hpp"

namespace pliant::cuda {

/// Number of usable CUDA devices; 0 with the reason in `why` when there is no driver or device.
int device_count(std::string& why);
std::string device_name(int device);

/// Device-resident model and state. The state is uploaded when the host copy changed and
/// downloaded on demand; steps run as CUDA graphs of `graph_steps` steps each.
template <class T>
class CudaEngine {
public:
    CudaEngine(const Model<T>& model, int device);
    ~CudaEngine();
    CudaEngine(const CudaEngine&) = delete;
    CudaEngine& operator=(const CudaEngine&) = delete;

    void upload(const State<T>& s);
    void download(State<T>& s);
    /// n steps on the device state from time t0 [s] (graph-captured), stability checks every
    /// check_every steps (one small device→host copy each).
    RunReport run(long n, double t0, double dt, double alpha, int check_every, double blowup);
    std::vector<double> tool_history() const { return history_; }
    std::size_t device_bytes() const;

private:
    struct Impl;
    std::unique_ptr<Impl> p_;
    std::vector<double> history_;
};

}  // namespace pliant::cuda
