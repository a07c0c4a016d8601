// pliant — the engine interface: what every backend does, and all that the Python bindings see.
// One implementation exists, Engine<T, Device> (engine.hpp), built for three devices: the CPU
// (OpenMP + SIMD), the CUDA runtime, and the emulated CUDA device (host loops, for tests).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "../model.hpp"

namespace pliant {

/// Model size [bytes] beyond which the CPU's kernel 2 prefetches its gathers (prefetch_incidences,
/// Dev::kPrefetch) and kernel 1 streams its forces past the caches (Dev::kStreams): a typical
/// last-level cache, 32 MiB (the OS's figure is not used: on a virtual machine it names the host's).
/// Below it the data stay in the caches and the prefetches only cost instructions (27,918 tets: 1.0
/// → 1.26 s for 8,000 steps with them), and kernel 2 reads the forces from the caches.
constexpr std::size_t kLargeModelBytes = std::size_t(32) << 20;

/// A displacement beyond this many times the body's size is a blow-up (Engine::check).
constexpr double kBlowUpSizes = 100.0;

/// What a run or relaxation ended with (bound to Python as RunStatus): a node moving more than the
/// body's size in one step is a Jump (Engine::check).
enum class RunStatus : int { Ok = 0, NonFinite = 1, Inverted = 2, BlowUp = 3, Jump = 4 };

/// Outcome of a run: `where` is the builder's element (Inverted; also a NaN J) or the engine's
/// node (NonFinite, BlowUp, Jump), `value` the offending quantity (J, a displacement or, for a
/// Jump, one step's displacement [m]), `t` the time [s] at which it was found.
struct RunReport {
    long steps = 0;
    double t = 0.0;
    RunStatus status = RunStatus::Ok;
    index_t where = -1;
    double value = 0.0;
    double residual = 0.0;  // relax: relative out-of-balance force at the end
    double damping = 0.0;   // relax: last adaptive damping coefficient α [1/s]
    double elem_seconds = 0.0, node_seconds = 0.0, contact_seconds = 0.0;  // run, CPU only
};

/// Per element (builder order): J, energy density W [Pa], S and σ [Pa] and Green strain E, each
/// as (xx, yy, zz, xy, yz, xz).
template <class T>
struct ElementResults {
    std::vector<T> J, W, S, sigma, E;
};

/// Per contact node (the model's contact-node order) after the last step: the tool touching it
/// (−1: none) and the force the tool exerts on it [N], (n, 3).
struct ContactReport {
    std::vector<index_t> tool;
    std::vector<double> force;
    std::vector<double> soft_force;  // per soft-contact surface node (3): the last step's force [N]
};

template <class T>
class Backend {
public:
    virtual ~Backend() = default;
    /// n central-difference steps of s in place (Δt [s], mass damping α [1/s]), checking stability
    /// every check_every steps and at the end (Engine::check: size [m] is the body's size).
    virtual RunReport run(State<T>& s, long n, double dt, double alpha, int check_every, double size) = 0;
    /// One step from `in` to `out` (distinct states).
    virtual RunReport step(const State<T>& in, State<T>& out, double dt, double alpha) = 0;
    /// Dynamic relaxation to the static equilibrium of the loads at time t_eval [s].
    virtual RunReport relax(State<T>& s, double t_eval, double dt, double tol, long max_steps,
                            int check_every, double size) = 0;
    virtual ElementResults<T> measures(const State<T>& s) = 0;
    /// Internal nodal forces f(u) [N], SoA (3, P); damped: plus stiffness-proportional damping's
    /// viscous forces from the state's last increment du and step Δt (what that step drove the
    /// nodes with; none where the model has no β or the state no step).
    virtual std::vector<T> internal_forces(const State<T>& s, bool damped) = 0;
    /// External loads [N] on the nodes at the state's displacements and the load curves at t [s]
    /// (load patterns, gravity, follower pressure and traction; not contact), SoA (3, P).
    virtual std::vector<T> external_forces(const State<T>& s, double t) = 0;
    /// Force [N] and torque [N·m] each tool received at each step of the last run, (steps, tools, 6);
    /// after a relaxation, the last step's only.
    virtual std::vector<double> tool_history() = 0;
    /// Force [N] the first body of each soft-contact pair received from the second at each step of
    /// the last run, (steps, pairs, 3) (a self-contact pair: the sum over its slave nodes).
    virtual std::vector<double> pair_history() = 0;
    virtual ContactReport contact_report() = 0;
    /// Replace every tool's keyframes (8 numbers each: t, position (3), quaternion w x y z)
    /// and every tool's grip times (closes, opens, closes…: times [s], ascending; empty: never)
    /// and grasping reach [m].
    virtual void set_tool_keys(const std::vector<std::vector<double>>& keys,
                               const std::vector<std::vector<double>>& grips,
                               const std::vector<double>& reach) = 0;
    /// Multiply every material's moduli by factor, relative to the model's.
    virtual void scale_materials(double factor) = 0;
    virtual std::string name() const = 0;
    virtual int threads() const = 0;
};

/// The backends. cpu: threads 1 .. thread_limit() or <= 0 for OpenMP's default.
template <class T>
std::unique_ptr<Backend<T>> make_cpu_backend(const Model<T>& m, int threads);
template <class T>
std::unique_ptr<Backend<T>> make_emulated_backend(const Model<T>& m);
/// Throws std::invalid_argument with the reason when CUDA is not compiled in or has no such device.
template <class T>
std::unique_ptr<Backend<T>> make_cuda_backend(const Model<T>& m, int device);

/// CUDA devices: their names, or none and the reason (also when CUDA is not compiled in).
std::vector<std::string> cuda_devices(std::string& why);
bool cuda_compiled();
int thread_limit_value();

}  // namespace pliant
