// pliant — Python bindings (nanobind) of the CPU backend: module pliant._core.
// Arrays cross the boundary as NumPy arrays in the engine's node/element order; pliant.tled maps
// them to and from the user's numbering.
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/tuple.h>
#include <nanobind/stl/vector.h>

#include <omp.h>

#include <cstdint>
#include <memory>
#include <vector>

#include "engine/backend.hpp"

namespace nb = nanobind;
using namespace nb::literals;
using namespace pliant;

namespace {

template <class T>
using In = nb::ndarray<const T, nb::c_contig, nb::device::cpu>;

template <class T>
nb::ndarray<nb::numpy, T> to_numpy(std::vector<T>&& v, std::initializer_list<size_t> shape) {
    auto* p = new std::vector<T>(std::move(v));
    nb::capsule owner(p, [](void* q) noexcept { delete static_cast<std::vector<T>*>(q); });
    return nb::ndarray<nb::numpy, T>(p->data(), shape, owner);
}

nb::dict report(const RunReport& r) {
    nb::dict d;
    d["steps"] = r.steps;
    d["t"] = r.t;
    d["status"] = r.status;
    d["where"] = r.where;
    d["value"] = r.value;
    d["residual"] = r.residual;
    d["damping"] = r.damping;
    d["elem_seconds"] = r.elem_seconds;
    d["node_seconds"] = r.node_seconds;
    d["contact_seconds"] = r.contact_seconds;
    return d;
}

template <class T>
struct PyState {
    State<T> s;
    index_t n_nodes;
};

/// The static model (built once, immutable) and its CPU thread count.
template <class T>
struct Engine {
    Model<T> model;
    int threads;
    Engine(const ModelInput& in, int threads_) : model(in), threads(threads_) {
        if (threads_ > thread_limit_value())
            throw std::invalid_argument("threads = " + std::to_string(threads_) + ": expected 1 to " +
                                        std::to_string(thread_limit_value()));
    }
};

/// A backend stepping one model (a Solver owns one): "cpu", "cuda-emulated" or "cuda".
template <class T>
struct PyBackend {
    const Engine<T>* engine;
    std::unique_ptr<Backend<T>> backend;
    Backend<T>* operator->() const { return backend.get(); }
};

template <class T>
std::unique_ptr<Backend<T>> make_backend(const Engine<T>& e, const std::string& name, int device,
                                         int threads) {
    if (name == "cpu") return make_cpu_backend(e.model, threads > 0 ? threads : e.threads);
    if (name == "cuda-emulated") return make_emulated_backend(e.model);
    if (name == "cuda") return make_cuda_backend(e.model, device);
    throw std::invalid_argument("backend '" + name + "': expected cpu, cuda-emulated or cuda");
}

// Node field (3, P) in the engine's padded SoA layout ↔ (N, 3) array.
template <class T>
std::vector<T> gather_nodes(const std::vector<T>& soa, index_t n, index_t P) {
    std::vector<T> out(3 * static_cast<std::size_t>(n));
    for (index_t i = 0; i < n; ++i)
        for (int d = 0; d < 3; ++d) out[3 * i + d] = soa[d * P + i];
    return out;
}
// Node field (3, P) → (N, 3) numpy array.
template <class T>
nb::ndarray<nb::numpy, T> node_array(const std::vector<T>& soa, index_t n, index_t P) {
    return to_numpy(gather_nodes(soa, n, P), {size_t(n), 3});
}
template <class T>
void scatter_nodes(const In<double>& a, std::vector<T>& soa, index_t n, index_t P) {
    if (a.ndim() != 2 || a.shape(0) != static_cast<size_t>(n) || a.shape(1) != 3)
        throw nb::value_error("node field must have shape (n_nodes, 3)");
    const double* p = a.data();
    for (index_t i = 0; i < n; ++i)
        for (int d = 0; d < 3; ++d) soa[d * P + i] = T(p[3 * i + d]);
}

template <class T>
void bind_engine(nb::module_& m, const char* engine_name, const char* backend_name, const char* state_name) {
    using E = Engine<T>;
    using B = PyBackend<T>;
    using S = PyState<T>;
    nb::class_<S>(m, state_name)
        .def_prop_ro("n_nodes", [](const S& s) { return s.n_nodes; })
        // Setting t, dt or the step count restarts the run clock there (State::restart_clock).
        .def_prop_rw(
            "t", [](const S& s) { return s.s.t; },
            [](S& s, double t) {
                s.s.t = t;
                s.s.restart_clock();
                s.s.touch();
            })
        .def_prop_rw(
            "dt", [](const S& s) { return s.s.dt; },
            [](S& s, double v) {
                s.s.dt = v;
                s.s.restart_clock();
                s.s.touch();
            })
        .def_prop_rw(
            "step", [](const S& s) { return s.s.step; },
            [](S& s, long v) {
                s.s.step = v;
                s.s.restart_clock();
            })
        // The run clock's epoch (t_epoch [s], step_epoch): saved and restored with the state, so
        // that a restored run meets its curves at the times the run it continues would have.
        .def_prop_rw(
            "epoch", [](const S& s) { return std::make_tuple(s.s.t_epoch, s.s.step_epoch); },
            [](S& s, std::tuple<double, long> e) {
                s.s.t_epoch = std::get<0>(e);
                s.s.step_epoch = std::get<1>(e);
            })
        .def("get_u",
             [](const S& s) {
                 const index_t P = static_cast<index_t>(s.s.u.size() / 3);
                 return node_array(s.s.u, s.n_nodes, P);
             })
        .def("get_u_prev",
             [](const S& s) {
                 const index_t P = static_cast<index_t>(s.s.u.size() / 3);
                 return node_array(s.s.u_prev, s.n_nodes, P);
             })
        .def("get_du",  // the last step's increment before rounding (State::du: velocity × Δt)
             [](const S& s) {
                 const index_t P = static_cast<index_t>(s.s.u.size() / 3);
                 return node_array(s.s.du, s.n_nodes, P);
             })
        .def("set_u",
             [](S& s, In<double> a) {
                 scatter_nodes(a, s.s.u, s.n_nodes, static_cast<index_t>(s.s.u.size() / 3));
                 reset_increment(s.s);
             })
        .def("set_u_prev",
             [](S& s, In<double> a) {
                 scatter_nodes(a, s.s.u_prev, s.n_nodes, static_cast<index_t>(s.s.u.size() / 3));
                 reset_increment(s.s);
             })
        .def("set_du",
             [](S& s, In<double> a) {
                 scatter_nodes(a, s.s.du, s.n_nodes, static_cast<index_t>(s.s.u.size() / 3));
                 s.s.touch();
             })
        .def("get_q",
             [](const S& s) {  // viscoelastic state, raw engine layout (save/restore)
                 std::vector<double> q(s.s.q.begin(), s.s.q.end());
                 return q;
             })
        .def("set_q",
             [](S& s, std::vector<double> q) {
                 if (q.size() != s.s.q.size())
                     throw nb::value_error(("viscoelastic state: " + std::to_string(q.size()) +
                                            " values, expected " + std::to_string(s.s.q.size()))
                                               .c_str());
                 for (std::size_t i = 0; i < q.size(); ++i) s.s.q[i] = T(q[i]);
                 s.s.touch();
             })
        .def("get_grip",
             [](const S& s) {  // grasping, per contact node (engine order): tool, position (n, 3)
                 const size_t n = s.s.grip_tool.size();
                 std::vector<index_t> tool = s.s.grip_tool;
                 std::vector<double> at = s.s.grip_at;
                 return nb::make_tuple(to_numpy(std::move(tool), {n}), to_numpy(std::move(at), {n, 3}));
             })
        .def("set_grip",
             [](S& s, std::vector<index_t> tool, std::vector<double> at) {
                 if (tool.size() != s.s.grip_tool.size() || at.size() != s.s.grip_at.size())
                     throw nb::value_error(("grasp state: " + std::to_string(tool.size()) + " nodes and " +
                                            std::to_string(at.size()) + " coordinates, expected " +
                                            std::to_string(s.s.grip_tool.size()) + " and " +
                                            std::to_string(s.s.grip_at.size()))
                                               .c_str());
                 s.s.grip_tool = std::move(tool);
                 s.s.grip_at = std::move(at);
                 s.s.touch();
             })
        .def("copy",
             [](const S& s) {
                 S c(s);
                 c.s.touch();
                 return c;
             })
        .def("assign", [](S& s, const S& o) {
            s = o;
            s.s.touch();
        });

    nb::class_<E>(m, engine_name, "A model (static, built once) and the backend that steps it.")
        .def(
            "__init__",
            [](E* self, In<double> X, In<index_t> tets, In<double> density, std::vector<index_t> group_end,
               std::vector<int> group_kind, std::vector<double> group_params, In<double> patterns,
               std::vector<index_t> pattern_curve, std::vector<index_t> cons_node, std::vector<int> cons_dim,
               std::vector<double> cons_value, std::vector<index_t> cons_curve, std::vector<int> curve_kind,
               std::vector<double> curve_t0, std::vector<double> curve_t1,
               std::vector<index_t> curve_table_begin, std::vector<index_t> curve_table_count,
               std::vector<double> table_t, std::vector<double> table_v, std::vector<double> gravity,
               index_t gravity_curve, std::vector<index_t> contact_nodes, std::vector<index_t> contact_masks,
               std::vector<int> tool_kind, std::vector<double> tool_params, std::vector<double> tool_mu,
               std::vector<std::vector<double>> tool_keys, std::vector<index_t> tool_grid_dims,
               std::vector<std::vector<double>> tool_grids, std::vector<index_t> press_nodes,
               std::vector<double> press_value, std::vector<index_t> press_curve,
               std::vector<double> press_traction, bool anp, std::vector<double> group_visco,
               double stiffness_damping, double anp_stabilization, bool anp_shear_stabilization,
               std::vector<std::vector<double>> tool_grips, std::vector<double> tool_reach,
               std::vector<index_t> soft_nodes, std::vector<index_t> soft_label,
               std::vector<index_t> soft_tris, std::vector<index_t> soft_pair, index_t soft_labels,
               std::vector<double> soft_mu, double soft_skin, StrainSmoothing smoothing, int threads,
               std::vector<index_t> mem_nodes, std::vector<int> mem_kind, std::vector<double> mem_params,
               std::vector<double> contact_skin, std::vector<double> soft_sheet_h,
               std::vector<index_t> mem_nbrs, std::vector<double> mem_bend) {
                ModelInput in;
                in.X = X.data();
                in.n_nodes = static_cast<index_t>(X.shape(0));
                in.tets = tets.data();
                in.n_elems = static_cast<index_t>(tets.shape(0));
                in.density = density.data();
                in.group_end = std::move(group_end);
                in.group_kind = std::move(group_kind);
                in.group_params = std::move(group_params);
                in.patterns = patterns.data();
                in.n_patterns = static_cast<int>(pattern_curve.size());
                in.pattern_curve = std::move(pattern_curve);
                in.cons_node = std::move(cons_node);
                in.cons_dim = std::move(cons_dim);
                in.cons_value = std::move(cons_value);
                in.cons_curve = std::move(cons_curve);
                for (std::size_t c = 0; c < curve_kind.size(); ++c)
                    in.curves.push_back({static_cast<CurveKind>(curve_kind[c]), curve_t0[c], curve_t1[c],
                                         curve_table_begin[c], curve_table_count[c]});
                in.table_t = std::move(table_t);
                in.table_v = std::move(table_v);
                for (int d = 0; d < 3; ++d) in.gravity[d] = gravity[d];
                in.gravity_curve = gravity_curve;
                in.contact_nodes = std::move(contact_nodes);
                in.contact_masks = std::move(contact_masks);
                in.contact_skin = std::move(contact_skin);
                in.press_nodes = std::move(press_nodes);
                in.press_value = std::move(press_value);
                in.press_curve = std::move(press_curve);
                in.press_traction = std::move(press_traction);
                in.anp = anp;
                in.stiffness_damping = stiffness_damping;
                in.anp_stabilization = anp_stabilization;
                in.anp_shear = anp_shear_stabilization;
                in.smoothing = smoothing;
                in.group_visco = std::move(group_visco);
                in.soft_nodes = std::move(soft_nodes);
                in.soft_label = std::move(soft_label);
                in.soft_tris = std::move(soft_tris);
                in.soft_pair = std::move(soft_pair);
                in.soft_labels = soft_labels;
                in.soft_mu = std::move(soft_mu);
                in.soft_skin = soft_skin;
                in.soft_sheet_h = std::move(soft_sheet_h);
                in.mem_nodes = std::move(mem_nodes);
                in.mem_kind = std::move(mem_kind);
                in.mem_params = std::move(mem_params);
                in.mem_nbrs = std::move(mem_nbrs);
                in.mem_bend = std::move(mem_bend);
                for (std::size_t k = 0; k < tool_kind.size(); ++k) {
                    RigidTool t{};
                    t.kind = static_cast<ToolKind>(tool_kind[k]);
                    for (int c = 0; c < 4; ++c) t.p[c] = tool_params[4 * k + c];
                    t.mu_s = tool_mu[2 * k];
                    t.mu_k = tool_mu[2 * k + 1];
                    t.key_begin = static_cast<index_t>(in.tool_keys.size() / 8);
                    t.key_count = static_cast<index_t>(tool_keys[k].size() / 8);
                    in.tool_keys.insert(in.tool_keys.end(), tool_keys[k].begin(), tool_keys[k].end());
                    t.grid_begin = static_cast<index_t>(in.tool_grid.size());
                    for (int c = 0; c < 3; ++c) t.grid_dims[c] = tool_grid_dims[3 * k + c];
                    t.grip_begin = static_cast<index_t>(in.tool_grips.size());
                    t.grip_count = static_cast<index_t>(tool_grips[k].size());
                    t.reach = tool_reach[k];
                    in.tool_grips.insert(in.tool_grips.end(), tool_grips[k].begin(), tool_grips[k].end());
                    in.tool_grid.insert(in.tool_grid.end(), tool_grids[k].begin(), tool_grids[k].end());
                    in.tools.push_back(t);
                }
                new (self) E(in, threads);
            },
            // The model crosses as named fields (keyword-only): units and layouts as ModelInput.
            nb::kw_only(), "X"_a, "tets"_a, "density"_a, "group_end"_a, "group_kind"_a, "group_params"_a,
            "patterns"_a, "pattern_curve"_a, "cons_node"_a, "cons_dim"_a, "cons_value"_a, "cons_curve"_a,
            "curve_kind"_a, "curve_t0"_a, "curve_t1"_a, "curve_table_begin"_a, "curve_table_count"_a,
            "table_t"_a, "table_v"_a, "gravity"_a, "gravity_curve"_a, "contact_nodes"_a, "contact_masks"_a,
            "tool_kind"_a, "tool_params"_a, "tool_mu"_a, "tool_keys"_a, "tool_grid_dims"_a, "tool_grids"_a,
            "press_nodes"_a, "press_value"_a, "press_curve"_a, "press_traction"_a, "anp"_a, "group_visco"_a,
            "stiffness_damping"_a, "anp_stabilization"_a, "anp_shear_stabilization"_a, "tool_grips"_a,
            "tool_reach"_a, "soft_nodes"_a, "soft_label"_a, "soft_tris"_a, "soft_pair"_a, "soft_labels"_a,
            "soft_mu"_a, "soft_skin"_a, "smoothing"_a, "threads"_a, "mem_nodes"_a = std::vector<index_t>{},
            "mem_kind"_a = std::vector<int>{}, "mem_params"_a = std::vector<double>{},
            "contact_skin"_a = std::vector<double>{}, "soft_sheet_h"_a = std::vector<double>{},
            "mem_nbrs"_a = std::vector<index_t>{}, "mem_bend"_a = std::vector<double>{})
        .def_prop_ro("n_nodes", [](const E& e) { return e.model.n_nodes; })
        .def_prop_ro("n_elems", [](const E& e) { return e.model.n_elems; })
        .def_prop_ro("n_blocks", [](const E& e) { return e.model.n_blocks; })
        .def_prop_ro("n_edges", [](const E& e) { return e.model.n_edges; })
        .def_prop_ro("dt_critical", [](const E& e) { return e.model.dt_critical; })
        .def_prop_ro("dt_critical_element", [](const E& e) { return e.model.dt_critical_elem; })
        .def_prop_ro("dt_critical_membrane", [](const E& e) { return e.model.dt_critical_membrane; })
        .def("membrane_critical_steps", [](const E& e) { return e.model.mem_dt; })
        .def_prop_ro("bytes", [](const E& e) { return e.model.bytes(); })
        .def_prop_ro("threads", [](const E& e) { return e.threads; })
        .def("new_state",
             [](const E& e) {
                 const std::size_t q =
                     e.model.visco_slots() * 6 * static_cast<std::size_t>(e.model.visco_terms);
                 return S{State<T>(e.model.n_pad, q, e.model.contact_nodes.size()), e.model.n_nodes};
             })
        .def("critical_steps",
             [](const E& e) {
                 // Stable step of each element [s] (h_min / c_d), in the order elements were given.
                 const std::size_t n = e.model.elem_dt.size();
                 std::vector<double> dt = e.model.elem_dt;
                 return to_numpy(std::move(dt), {n});
             })
        .def("mass",
             [](const E& e) {
                 std::vector<T> m(e.model.mass.begin(), e.model.mass.begin() + e.model.n_nodes);
                 return to_numpy(std::move(m), {size_t(e.model.n_nodes)});
             })
        .def(
            "make_backend",
            [](const E& e, const std::string& name, int device, int threads) {
                // A new backend for this model (the returned object keeps the model alive).
                try {
                    return PyBackend<T>{&e, make_backend(e, name, device, threads)};
                } catch (const std::invalid_argument& x) {
                    throw nb::value_error(x.what());
                }
            },
            "name"_a, "device"_a = 0, "threads"_a = 0, nb::keep_alive<0, 1>());

    nb::class_<B>(m, backend_name, "A backend stepping one model: run, step, relax, results, tools.")
        .def(
            "step",
            [](B& e, const S& in, S& out, double dt, double alpha) {
                RunReport r;
                {
                    nb::gil_scoped_release g;
                    r = e->step(in.s, out.s, dt, alpha);
                }
                return report(r);
            },
            "state_in"_a, "state_out"_a, "dt"_a, "alpha"_a)
        .def("run",
             [](B& e, S& s, long n, double dt, double alpha, int check_every, double size) {
                 RunReport r;
                 {
                     nb::gil_scoped_release g;
                     r = e->run(s.s, n, dt, alpha, check_every, size);
                 }
                 return report(r);
             })
        .def("relax",
             [](B& e, S& s, double t_eval, double dt, double tol, long max_steps, int check_every,
                double size) {
                 RunReport r;
                 {
                     nb::gil_scoped_release g;
                     r = e->relax(s.s, t_eval, dt, tol, max_steps, check_every, size);
                 }
                 return report(r);
             })
        .def("measures",
             [](B& e, const S& s) {
                 const size_t M = size_t(e.engine->model.n_elems);
                 ElementResults<T> r;
                 {
                     nb::gil_scoped_release g;
                     r = e->measures(s.s);
                 }
                 return nb::make_tuple(to_numpy(std::move(r.J), {M}), to_numpy(std::move(r.W), {M}),
                                       to_numpy(std::move(r.S), {M, 6}), to_numpy(std::move(r.sigma), {M, 6}),
                                       to_numpy(std::move(r.E), {M, 6}));
             })
        .def("set_tool_keys",
             [](B& e, std::vector<std::vector<double>> keys, std::vector<std::vector<double>> grips,
                std::vector<double> reach) {
                 try {
                     e->set_tool_keys(keys, grips, reach);
                 } catch (const std::invalid_argument& x) {
                     throw nb::value_error(x.what());
                 }
             })
        .def("scale_materials",
             [](B& e, double factor) {
                 // Multiply every material's moduli by `factor` relative to the values at build time
                 // (the viewer's stiffness slider). The critical time step scales by 1/sqrt(factor).
                 if (!(factor > 0.0)) throw nb::value_error("factor must be > 0");
                 e->scale_materials(factor);
             })
        .def_prop_ro("name", [](const B& e) { return e->name(); })
        .def_prop_ro("threads", [](const B& e) { return e->threads(); })
        .def("tool_history",
             [](const B& e) {
                 std::vector<double> h = e->tool_history();
                 const size_t nt = e.engine->model.tools.size();
                 const size_t steps = nt ? h.size() / (6 * nt) : 0;
                 return to_numpy(std::move(h), {steps, nt, 6});
             })
        .def("pair_history",
             [](const B& e) {
                 std::vector<double> h = e->pair_history();
                 const size_t np = static_cast<size_t>(e.engine->model.soft_pairs);
                 const size_t steps = np ? h.size() / (3 * np) : 0;
                 return to_numpy(std::move(h), {steps, np, 3});
             })
        .def("contact_state",
             [](const B& e) {
                 // Tool contact nodes, the tool on each and its force; soft-contact surface nodes
                 // (engine numbering) and the force on each [N] (the last step's).
                 std::vector<index_t> nodes = e.engine->model.contact_nodes;
                 std::vector<index_t> soft = e.engine->model.soft_nodes;
                 ContactReport c = e->contact_report();
                 const size_t n = nodes.size(), ns = soft.size();
                 if (c.soft_force.size() != 3 * ns) c.soft_force.assign(3 * ns, 0.0);
                 return nb::make_tuple(to_numpy(std::move(nodes), {n}), to_numpy(std::move(c.tool), {n}),
                                       to_numpy(std::move(c.force), {n, 3}), to_numpy(std::move(soft), {ns}),
                                       to_numpy(std::move(c.soft_force), {ns, 3}));
             })
        .def("membrane_measures",
             [](const B& e, const S& s) {
                 // Per membrane (model order): J_s, the Cauchy resultant and the strain energy
                 // (membrane_measures).
                 const Model<T>& m = e.engine->model;
                 const MembraneData<T> md = m.membranes();
                 const index_t P = static_cast<index_t>(s.s.u.size() / 3);
                 constexpr std::size_t w = kMembraneMeasures;
                 std::vector<T> out(w * static_cast<std::size_t>(md.count));
                 for (index_t k = 0; k < md.count; ++k)
                     membrane_measures(k, md, s.s.u.data(), P, &out[w * k]);
                 return to_numpy(std::move(out), {size_t(md.count), w});
             })
        .def(
            "internal_forces",
            [](B& e, const S& s, bool damped) {
                std::vector<T> f = e->internal_forces(s.s, damped);
                return node_array(f, e.engine->model.n_nodes, e.engine->model.n_pad);
            },
            nb::arg("state"), nb::arg("damped") = false)
        .def("external_forces", [](B& e, const S& s, double t) {
            std::vector<T> f = e->external_forces(s.s, t);
            return node_array(f, e.engine->model.n_nodes, e.engine->model.n_pad);
        });
}

}  // namespace

// One module per instruction set (CMakeLists.txt): its name comes from the build.
#ifndef PLIANT_MODULE_NAME
#define PLIANT_MODULE_NAME _core_generic
#endif
#define PLIANT_NB_MODULE(name, var) NB_MODULE(name, var)

PLIANT_NB_MODULE(PLIANT_MODULE_NAME, m) {
    m.doc() = "pliant engine: TLED on linear tetrahedra; backends cpu (OpenMP + SIMD), cuda, cuda-emulated";
    // Engines can still be referenced at interpreter exit (viewer threads are daemons); nanobind's
    // exit-time leak report is then noise, not a refcounting bug.
    nb::set_leak_warnings(false);
    bind_engine<float>(m, "EngineF32", "BackendF32", "StateF32");
    bind_engine<double>(m, "EngineF64", "BackendF64", "StateF64");
    m.attr("lanes") = kLanes;
    m.attr("free_edge") = kFreeEdge;         // ModelInput::mem_nbrs: no node across a membrane's edge
    m.attr("clamped_edge") = kClampedEdge;   // ... or an edge whose slope is held
    m.attr("blow_up_sizes") = kBlowUpSizes;  // a displacement beyond this many body sizes: a blow-up
    // The backends use_backend accepts: one engine (engine/engine.hpp) on three devices.
    m.attr("backends") = nb::make_tuple("cpu", "cuda-emulated", "cuda");
    // Layout limits of the model description, so that Python restates none of them.
    m.attr("material_params") = kMaterialParams;     // parameters per material group
    m.attr("prony_max") = kPronyMax;                 // Prony terms per group (half isochoric)
    m.attr("masked_tools") = kMaskedTools;           // tools that can be restricted to node sets
    m.attr("soft_band") = kSoftBehind;               // soft contact's band: this × a triangle's mean edge [1]
    m.attr("large_model_bytes") = kLargeModelBytes;  // beyond it the CPU streams and prefetches [bytes]
    // The kinds the engine dispatches on, bound so that Python names them and restates no number.
    nb::enum_<MaterialKind>(m, "MaterialKind", nb::is_arithmetic(), "Hyperelastic material models.")
        .value("NeoHookean", MaterialKind::NeoHookean)
        .value("MooneyRivlin", MaterialKind::MooneyRivlin)
        .value("NeoHookeanCoupled", MaterialKind::NeoHookeanCoupled)
        .value("StVenantKirchhoff", MaterialKind::StVenantKirchhoff)
        .value("LinearElastic", MaterialKind::LinearElastic)
        .value("Polynomial", MaterialKind::Polynomial)
        .value("ArrudaBoyce", MaterialKind::ArrudaBoyce)
        .value("TransverselyIsotropic", MaterialKind::TransverselyIsotropic);
    nb::enum_<MembraneKind>(m, "MembraneKind", nb::is_arithmetic(),
                            "Membrane constitutive models (membrane.hpp).")
        .value("StVenantKirchhoff", MembraneKind::StVenantKirchhoff)
        .value("NeoHookean", MembraneKind::NeoHookean);
    nb::enum_<StrainSmoothing>(m, "StrainSmoothing", nb::is_arithmetic(),
                               "Where the strain of linear tetrahedra is constant.")
        .value("Element", StrainSmoothing::Element, "per element: plain linear tetrahedra (T4)")
        .value("Edge", StrainSmoothing::Edge,
               "per edge domain: edge-based smoothed strain (ES-FEM-T4), far less stiff in bending");
    nb::enum_<CurveKind>(m, "CurveKind", nb::is_arithmetic(), "Load curve shapes.")
        .value("Constant", CurveKind::Constant)
        .value("Step", CurveKind::Step)
        .value("Ramp", CurveKind::Ramp)
        .value("SmoothRamp", CurveKind::SmoothRamp)
        .value("Table", CurveKind::Table)
        .value("Hilly", CurveKind::Hilly);
    nb::enum_<RunStatus>(m, "RunStatus", nb::is_arithmetic(), "How a run or relaxation ended.")
        .value("Ok", RunStatus::Ok)
        .value("NonFinite", RunStatus::NonFinite)
        .value("Inverted", RunStatus::Inverted)
        .value("BlowUp", RunStatus::BlowUp)
        .value("Jump", RunStatus::Jump);
    nb::enum_<ViscoMode>(m, "ViscoMode", nb::is_arithmetic(),
                         "What a viscoelastic element does with its Prony state in a pass.")
        .value("Advance", ViscoMode::Advance)
        .value("Stored", ViscoMode::Stored)
        .value("Relaxed", ViscoMode::Relaxed)
        .value("RelaxedStore", ViscoMode::RelaxedStore);
    nb::enum_<ToolKind>(m, "ToolKind", nb::is_arithmetic(), "Rigid tool shapes.")
        .value("Plane", ToolKind::Plane)
        .value("Sphere", ToolKind::Sphere)
        .value("Capsule", ToolKind::Capsule)
        .value("Box", ToolKind::Box)
        .value("Grid", ToolKind::Grid)
        .value("Cylinder", ToolKind::Cylinder);
    m.def(
        "is_decoupled",
        [](MaterialKind kind) {
            // Whether a material kind splits W into isochoric and volumetric parts (T4ANP and
            // viscoelasticity need it): the engine's own M::decoupled, so Python restates no list.
            const MaterialParams<double> p{kind, {1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0}};
            return with_material(p, [](const auto& mat) { return std::decay_t<decltype(mat)>::decoupled; });
        },
        "kind"_a);
    m.def(
        "log_J",
        [](In<double> x, bool single) {
            // The engine's ln J from J − 1 (materials.hpp, log_J), in float32 or float64, for tests.
            const size_t n = x.size();
            std::vector<double> out(n);
            for (size_t i = 0; i < n; ++i)
                out[i] = single ? double(log_J(float(x.data()[i]))) : log_J(x.data()[i]);
            return to_numpy(std::move(out), {n});
        },
        "jm1"_a, "single"_a);
    m.def("max_threads", []() { return omp_get_max_threads(); });
    m.def("thread_limit", &pliant::thread_limit_value, "Most CPU threads a solver accepts.");
    m.def("cuda_compiled", &pliant::cuda_compiled);
    m.def("cuda_devices", []() {
        // (names of usable devices, reason when there are none)
        std::string why;
        std::vector<std::string> names = cuda_devices(why);
        return nb::make_tuple(names, why);
    });
    m.def("tet_geometry", [](In<double> X, In<index_t> tets) {
        // Reference volume [m³] and smallest altitude [m] per tet, for validation by the builder.
        const size_t M = tets.shape(0), N = X.shape(0);
        std::vector<double> vol(M), alt(M);
        const double* x = X.data();
        const index_t* t = tets.data();
        for (size_t e = 0; e < M; ++e) {
            double P[4][3], g[4][3];
            for (int a = 0; a < 4; ++a) {
                const index_t n = t[4 * e + a];
                if (n < 0 || size_t(n) >= N) throw nb::index_error("node index out of range");
                for (int d = 0; d < 3; ++d) P[a][d] = x[3 * n + d];
            }
            tet_reference(P, g, vol[e], alt[e]);
        }
        return nb::make_tuple(to_numpy(std::move(vol), {M}), to_numpy(std::move(alt), {M}));
    });
}
