"""One vocabulary: the same verbs on Solver and Simulation, old names still working with a
DeprecationWarning, and the one contact report."""

import numpy as np
import pytest

import pliant as pl
from pliant.contact import Sphere


def _builder():
    """A 10 × 2 × 2 cm bar, its end x = 0 held, under gravity."""
    X, T = pl.mesh.box_tets((0.1, 0.02, 0.02), (10, 2, 2))
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(pl.NeoHookean(E=2e4, nu=0.45), density=1000.0)
    b.fix(np.nonzero(X[:, 0] < 1e-9)[0])
    b.set_gravity((0.0, 0.0, -9.81))
    return b


def _model(backend="cpu"):
    b = _builder()
    b.add_tool(Sphere(0.01).at(0.0, (0.06, 0.01, -0.0101)).at(0.02, (0.06, 0.01, -0.008)))
    return b.finalize("float64", backend=backend)


def test_simulation_verbs_match_the_solver():
    m = _model()
    sim = pl.Simulation(m, dt=1e-4)
    assert sim.dt == sim.solver.dt == 1e-4
    sim.step()
    assert sim.time == pytest.approx(1e-4)
    sim.run(steps=9)
    sim.run(until=0.002)
    assert sim.time == pytest.approx(0.002)
    ref = m.state()
    solver = pl.Solver(m, dt=1e-4)
    solver.run(ref, until=0.002)
    # three calls restart the time as t0 + kΔt from different t0: the tool's keyframed pose sees
    # times a few ulps apart, so equal to round-off, not bitwise
    np.testing.assert_allclose(sim.displacements, ref.displacements, rtol=1e-9, atol=1e-18)
    info = sim.relax(tol=1e-6)
    assert isinstance(info, pl.RelaxInfo) and info.converged


@pytest.mark.parametrize(
    "call, new",
    [
        (lambda s: s.run_to(0.001), "run(until=t)"),
        (lambda s: s.solve_static(tol=1e-3), "relax()"),
        (lambda s: s.step(3), "run(steps=n)"),
        (lambda s: s.solver.tool_histories, "contact_report().tools"),
        (lambda s: s.model.use_cuda(0), "Solver(model, backend='cuda'"),
    ],
)
def test_old_names_warn_and_still_work(call, new):
    sim = pl.Simulation(_model(), dt=1e-4)
    with pytest.warns(DeprecationWarning, match=new.replace("(", r"\(").replace(")", r"\)")):
        try:
            call(sim)
        except pl.BackendError:  # use_cuda without a GPU: warned first, then refused by name
            pass


def test_contact_report_is_one_object():
    sim = pl.Simulation(_model(), dt=1e-4)
    sim.run(until=0.02)
    r = sim.contact_report()
    assert isinstance(r, pl.ContactReport) and r.relaxed is None
    H = r.tools[0]
    assert len(H.time) == 200 and H.force.shape == (200, 3)
    f, m = r.force(0)
    np.testing.assert_array_equal(f, H.force[-1])
    np.testing.assert_array_equal(sim.tool_force(0)[0], f)
    touching = r.node_tool >= 0
    assert touching.any()
    # The tool receives the opposite of what it exerts on the nodes (Newton's third law).
    np.testing.assert_allclose(-r.node_force[touching].sum(axis=0), f, rtol=1e-12, atol=1e-15)
    sim.relax(at_time=0.02, tol=1e-7)
    r = sim.contact_report()
    assert r.relaxed is not None
    np.testing.assert_array_equal(r.force(0)[0], r.relaxed[0][0])


def test_history_steps_keeps_the_last_steps_of_the_full_history():
    """A bounded history (for hours-long interactive sessions) is the tail of the unbounded one,
    over several runs; a bound below one step is refused by name."""
    full, short = pl.Simulation(_model(), dt=1e-4), pl.Simulation(_model(), dt=1e-4, history_steps=30)
    for s in (full, short):
        for _ in range(5):
            s.run(steps=17)
    F, S = full.contact_report().tools[0], short.contact_report().tools[0]
    assert len(F.time) == 85 and len(S.time) == 30
    np.testing.assert_array_equal(S.time, F.time[-30:])
    np.testing.assert_array_equal(S.force, F.force[-30:])
    np.testing.assert_array_equal(S.torque, F.torque[-30:])
    with pytest.raises(pl.InputError, match="history_steps"):
        pl.Solver(_model(), history_steps=0)


def test_solvers_own_their_backends_and_tool_trajectories():
    """Two solvers of one (static) model: different backends, one tool moved in one of them only."""
    m = _model()
    a, b = pl.Simulation(m, dt=1e-4), pl.Simulation(m, dt=1e-4, backend="cuda-emulated")
    assert (a.solver.backend, b.solver.backend, m.backend) == ("cpu", "cuda-emulated", "cpu")
    b.set_tool_pose(0, (0.06, 0.01, -0.006))
    a.run(until=0.02)
    b.run(until=0.02)
    assert m.tools[0].keys[-1][0] == 0.02  # the model's trajectory is untouched
    peak = [np.abs(s.contact_report().tools[0].force[:, 2]).max() for s in (a, b)]
    assert peak[1] > peak[0] > 0  # the deeper tool pushed harder


def test_scene_key_lambda_is_deprecated_for_lam(tmp_path):
    from pliant.scene import load_scene

    text = """[mesh]
primitive = "box"
size = [0.1, 0.02, 0.02]
cells = [4, 1, 1]
[[material]]
type = "st-venant-kirchhoff"
mu = 1000.0
{key} = 2000.0
density = 1000.0
[solver]
duration = 0.01
"""
    for key, warns in (("lam", False), ("lambda", True)):
        p = tmp_path / f"{key}.toml"
        p.write_text(text.format(key=key))
        with pytest.warns(pl.PliantWarning, match="'lam'") if warns else _no_warning():
            scene = load_scene(p)
        assert scene.builder.sets[0].material.lam == 2000.0


class _no_warning:
    def __enter__(self):
        import warnings

        self._w = warnings.catch_warnings()
        self._w.__enter__()
        warnings.simplefilter("error")

    def __exit__(self, *exc):
        self._w.__exit__(*exc)
        return False


E_NU = {"NeoHookean", "NeoHookeanCoupled", "StVenantKirchhoff", "LinearElastic"}  # docs/engine.md


@pytest.mark.parametrize(
    "cls, native",
    [
        (pl.NeoHookean, dict(mu=1e3, K=1e4)),
        (pl.MooneyRivlin, dict(C10=400.0, C01=100.0, K=1e4)),
        (pl.NeoHookeanCoupled, dict(mu=1e3, lam=5e3)),
        (pl.StVenantKirchhoff, dict(mu=1e3, lam=5e3)),
        (pl.LinearElastic, dict(mu=1e3, lam=5e3)),
        (pl.Polynomial, dict(C10=400.0, C01=100.0, K=1e4)),
        (pl.ArrudaBoyce, dict(mu=1e3, lambda_m=2.0, K=1e4)),
        (pl.TransverselyIsotropic, dict(mu=1e3, K=1e4, eta=500.0, direction=(1.0, 0.0, 0.0))),
    ],
    ids=lambda v: getattr(v, "__name__", ""),
)
def test_material_constructors_do_what_the_docs_say(cls, native):
    """Native constants by keyword (K= everywhere it exists, lam for the Lamé constant), and
    E=, nu= exactly where docs/engine.md says so; the small-strain moduli agree with E, ν."""
    m = cls(**native)
    assert m.mu > 0
    if cls.__name__ in E_NU:
        m = cls(E=3e3, nu=0.4)
        assert m.young == pytest.approx(3e3) and m.poisson == pytest.approx(0.4)
    else:
        with pytest.raises((TypeError, pl.MaterialError)):
            cls(E=3e3, nu=0.4)


@pytest.mark.parametrize("single", [False, True], ids=["float64", "float32"])
def test_engine_log_matches_libm(single):
    """The engine's ln J (plain arithmetic, so that it vectorizes) against NumPy's log1p over
    J − 1 from −0.99 to 1e3 (down to 1e-12 on both sides of J = 1): relative error within 3 ulps
    of the type (log_plain's truncation < ½ ulp, the rounding-of-(1 + x) correction, and the
    rounding of a dozen operations; measured 1.5–1.7 ulps)."""
    x = np.concatenate(
        [
            -np.logspace(-12, np.log10(0.99), 400),
            np.logspace(-12, 3, 400),
            [-1e-2, 1e-2, np.nextafter(1e-2, 0), np.nextafter(-1e-2, 0), 0.0],
        ]
    )
    dt = np.float32 if single else np.float64
    xs = x.astype(dt).astype(float)  # what the engine receives
    got = np.asarray(pl._core.log_J(np.ascontiguousarray(xs), single))
    want = np.log1p(xs)
    eps = np.finfo(dt).eps
    assert got[xs == 0.0].tolist() == [0.0]
    nz = xs != 0.0
    err = np.abs(got[nz] - want[nz]) / np.abs(want[nz])
    assert err.max() <= 3 * eps, f"worst at J - 1 = {xs[nz][np.argmax(err)]:.3g}: {err.max():.3g}"


def test_a_model_rebuilt_at_another_dtype_is_that_build():
    # Model.rebuilt(dtype) is the builder's finalize at that dtype: the same masses (float32 holds
    # them to 1e-7 relative), the same step over the same 20 steps of gravity to float32's 1e-6
    # of the largest displacement, and the T4ANP settings as the builder had them.
    b = _builder()
    b.nodal_pressure = True
    b.nodal_pressure_stabilization = "shear"
    single = b.finalize("float32")
    double = single.rebuilt("float64")
    direct = b.finalize("float64")
    assert (
        double.dtype == np.float64
        and double.nodal_pressure
        and double.nodal_pressure_stabilization == "shear"
    )
    np.testing.assert_array_equal(double.mass, direct.mass)
    np.testing.assert_allclose(single.mass, direct.mass, rtol=1e-7)
    runs = [pl.Simulation(m, dt=1e-4) for m in (single, double, direct)]
    for sim in runs:
        sim.run(steps=20)
    np.testing.assert_array_equal(runs[1].state.displacements, runs[2].state.displacements)
    scale = np.abs(runs[2].state.displacements).max()
    assert np.abs(runs[0].state.displacements - runs[2].state.displacements).max() < 1e-6 * scale + 1e-12
