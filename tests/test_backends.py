"""Every feature of a step on every backend: cpu, cuda-emulated (the CUDA engine on the host) and
cuda where a device exists, each compared with the CPU run of the same model.

The CPU results are themselves checked against closed forms elsewhere (uniaxial, cantilever,
Hertz, pressure, dynamics); here the question is whether each backend runs the same physics.
Tolerances: all backends run one engine source, so they differ only in floating-point contraction
and vectorization (the CPU evaluates lanes in SIMD with fused multiply-adds where the compiler
chose them, the emulated device one lane at a time, a GPU with its own FMA choices). Those
last-bit differences (~1e-16 relative in float64, ~1e-7 in float32) are carried along by a
damped, stable dynamics for at most a few hundred steps: 1e-9 (float64) and 2e-4 (float32) of the
largest displacement bound that growth with a wide margin, while any missing feature, stale
upload or wrong buffer changes results by percents."""

import math

import numpy as np
import pytest

import pliant as pl
from pliant.contact import Box, Capsule, Cylinder, MeshTool, Plane, Sphere
from pliant.mesh.topology import boundary_faces

REL = {"float64": 1e-9, "float32": 2e-4}
L, W = 0.1, 0.02  # a 10 cm × 2 cm × 2 cm bar [m]
DT, T_END = 1e-4, 0.04  # [s]: 400 steps at an eighth of the critical step (8.1e-4 s)


def bar(backend, material=None, dtype="float64", cells=(10, 2, 2), anp=False, damping=20.0):
    """A bar clamped at x = 0 under gravity: the builder, to be finalized on a backend."""
    X, T = pl.mesh.box_tets((L, W, W), cells)
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(material or pl.NeoHookean(E=2e4, nu=0.45), density=1000.0)
    b.fix(np.nonzero(X[:, 0] < 1e-9)[0])
    b.set_gravity((0.0, 0.0, -9.81), curve=pl.SmoothRamp(0.01))
    b.nodal_pressure = anp
    b.damping = damping
    return b, X, T


def close(a, b, dtype, what):
    scale = max(np.abs(a).max(), 1e-30)
    err = np.abs(np.asarray(a) - np.asarray(b)).max()
    assert err <= REL[dtype] * scale, f"{what}: differs by {err:.3g} (scale {scale:.3g})"


def pair(make, backend, dtype="float64"):
    """The same model on the CPU and on `backend`."""
    return make().finalize(dtype, backend="cpu"), make().finalize(dtype, backend=backend)


MATERIALS = {
    "NeoHookean": pl.NeoHookean(E=2e4, nu=0.45),
    "MooneyRivlin": pl.MooneyRivlin(2e3, 1e3, 5e4),
    "NeoHookeanCoupled": pl.NeoHookeanCoupled(E=2e4, nu=0.45),
    "StVenantKirchhoff": pl.StVenantKirchhoff(E=2e4, nu=0.45),
    "LinearElastic": pl.LinearElastic(E=2e4, nu=0.45),
    "Polynomial": pl.Polynomial(3e3, 500.0, 200.0, K=5e4),
    "ArrudaBoyce": pl.ArrudaBoyce(6e3, 2.0, 5e4),
    "TransverselyIsotropic": pl.TransverselyIsotropic(6e3, 5e4, 3.0, (1.0, 0.0, 0.0)),
    "Viscoelastic": pl.Viscoelastic(pl.NeoHookean(E=2e4, nu=0.45), iso=[(0.4, 0.005)], vol=[(0.2, 0.01)]),
    # the most terms a material takes, each its own (α, τ): every term's phase on every device
    "Viscoelastic 4+4": pl.Viscoelastic(
        pl.MooneyRivlin(2e3, 1e3, 5e4),
        iso=[(0.1, 0.002), (0.1, 0.005), (0.1, 0.01), (0.1, 0.03)],
        vol=[(0.05, 0.002), (0.05, 0.005), (0.05, 0.01), (0.05, 0.03)],
    ),
}


@pytest.mark.parametrize("dtype", ["float32", "float64"])
@pytest.mark.parametrize("name", list(MATERIALS))
def test_materials_under_gravity(backend, name, dtype):
    a, b = pair(lambda: bar(backend, MATERIALS[name])[0], backend, dtype)
    sa, sb = pl.Simulation(a, dt=DT), pl.Simulation(b, dt=DT)
    sa.run(steps=400)
    sb.run(steps=400)
    assert b.backend == backend
    assert np.abs(sa.displacements).max() > 1e-5  # it sagged
    close(sa.displacements, sb.displacements, dtype, name)
    close(sa.velocities, sb.velocities, dtype, name + " velocity")
    ra, rb = a.element_results(sa.state), b.element_results(sb.state)
    for key in ("J", "cauchy", "green_strain", "energy_density"):
        close(
            ra[key] - (1.0 if key == "J" else 0.0),
            rb[key] - (1.0 if key == "J" else 0.0),
            dtype,
            f"{name} {key}",
        )
    close(a.internal_forces(sa.state), b.internal_forces(sb.state), dtype, name + " f(u)")


def test_t4anp_pressure_and_load_curves(backend):
    """T4ANP, a follower pressure on the top faces (Hilly curve), a prescribed end displacement
    (Table curve) and a point-load pattern (Step curve), with gravity."""

    def make():
        b, X, T = bar(backend, pl.NeoHookean(E=2e4, nu=0.49), anp=True)
        B, _ = boundary_faces(T)
        top = B[np.all(X[B][:, :, 2] > W - 1e-9, axis=1)]
        b.add_pressure(top, 300.0, pl.Hilly(T_END))
        tip = np.nonzero(X[:, 0] > L - 1e-9)[0]
        b.prescribe(tip, 0.002, "y", curve=pl.Table([0.0, 0.01, 0.03], [0.0, 1.0, 0.5]))
        mid = np.nonzero(np.isclose(X[:, 0], L / 2))[0]
        b.add_force(mid, (0.0, 0.0, -1e-3), curve=pl.Step(0.01))
        return b

    a, b = pair(make, backend)
    sa, sb = pl.Simulation(a, dt=DT), pl.Simulation(b, dt=DT)
    sa.run(until=T_END)
    sb.run(until=T_END)
    close(sa.displacements, sb.displacements, "float64", "T4ANP + pressure + curves")
    close(
        a.element_results(sa.state)["cauchy"],
        b.element_results(sb.state)["cauchy"],
        "float64",
        "T4ANP stresses",
    )


def _tool(kind):
    if kind == "plane":  # tilted floor rising into the bar's underside
        return Plane((0.0, 0.0, -0.004), (0.0, 0.3, 1.0), mu_s=0.3)
    if kind == "sphere":
        return Sphere(0.01, mu_s=0.2)
    if kind == "capsule":
        return Capsule(0.005, 0.03, mu_s=0.2)
    if kind == "cylinder":
        return Cylinder(0.005, 0.03)
    if kind == "box":
        return Box((0.01, 0.02, 0.005), mu_s=0.5, mu_k=0.3)
    import trimesh

    ico = trimesh.creation.icosphere(subdivisions=2, radius=0.008)
    return MeshTool(ico.vertices, ico.faces, spacing=0.002)


def _poke(tool, kind):
    """Keyframes: from below the bar's middle up 3 mm into it over 40 ms (the plane rises 6 mm)."""
    if kind == "plane":
        tool.at(0.0, (0.0, 0.0, -0.004)).at(T_END, (0.0, 0.0, 0.002))
        return tool
    r = {"sphere": 0.01, "capsule": 0.005, "cylinder": 0.005, "box": 0.005, "mesh": 0.008}[kind]
    q = (math.cos(math.pi / 4), math.sin(math.pi / 4), 0.0, 0.0)  # axis along y
    rot = q if kind in ("capsule", "cylinder") else (1.0, 0.0, 0.0, 0.0)
    tool.at(0.0, (0.06, 0.01, -r - 1e-4), rot).at(T_END, (0.06, 0.01, 0.003 - r), rot)
    return tool


@pytest.mark.parametrize("kind", ["plane", "sphere", "capsule", "cylinder", "box", "mesh"])
def test_tools_forces_and_contact_report(backend, kind):
    def make():
        b = bar(backend)[0]
        b.add_tool(_poke(_tool(kind), kind))
        return b

    a, b = pair(make, backend)
    sa, sb = pl.Simulation(a, dt=DT), pl.Simulation(b, dt=DT)
    sa.run(until=T_END)
    sb.run(until=T_END)
    close(sa.displacements, sb.displacements, "float64", kind)
    fa, fb = (s.contact_report().tools[0].force for s in (sa, sb))
    assert len(fa) == len(fb) == 400
    assert np.abs(fa[-1]).max() > 1e-4, "the tool should push on the bar"
    close(fa, fb, "float64", kind + " tool force history")
    ra, rb = sa.contact_report(), sb.contact_report()
    na, ta, ca = ra.nodes, ra.node_tool, ra.node_force
    nb, tb, cb = rb.nodes, rb.node_tool, rb.node_force
    assert (ta >= 0).any(), "some nodes touch the tool"
    np.testing.assert_array_equal(na, nb)
    np.testing.assert_array_equal(ta, tb)
    close(ca, cb, "float64", kind + " contact forces")
    # The report balances the history: the tool receives minus the sum of the node forces.
    np.testing.assert_allclose(-ca.sum(axis=0), fb[-1], atol=1e-9 * np.abs(fb[-1]).max())


def test_set_tool_pose_mid_run_reaches_the_device(backend):
    """The viewer's tool dragging: a pose set between runs must move the tool on every backend
    (the old CUDA backend kept the keyframes it uploaded first)."""

    def make():
        b = bar(backend)[0]
        b.add_tool(Sphere(0.01, position=(0.06, 0.01, -0.0102)))
        return b

    a, b = pair(make, backend)
    sims = [pl.Simulation(m, dt=DT) for m in (a, b)]
    for s in sims:
        s.run(steps=100)
        s.set_tool_pose(0, (0.06, 0.01, -0.007))  # 3 mm up into the bar
        s.run(steps=300)
    close(sims[0].displacements, sims[1].displacements, "float64", "after set_tool_pose")
    f = sims[1].tool_force(0)[0]
    assert f[2] < -1e-3, f"the raised tool must feel the bar pushing down, got {f}"


def test_relax_with_a_tool(backend):
    def make():
        b = bar(backend)[0]
        b.add_tool(_poke(Sphere(0.01), "sphere"))
        return b

    a, b = pair(make, backend)
    sa, sb = pl.Simulation(a, dt=DT), pl.Simulation(b, dt=DT)
    # load-stepped: the sphere's 3 mm indentation applied at once inverts elements
    ia = sa.relax(at_time=T_END, tol=1e-7, increments=4)
    ib = sb.relax(at_time=T_END, tol=1e-7, increments=4)
    assert ia.converged and ib.converged
    assert ia.steps == ib.steps  # the same decisions
    close(sa.displacements, sb.displacements, "float64", "relaxed")
    close(
        sa.contact_report().relaxed[0][0], sb.contact_report().relaxed[0][0], "float64", "relaxed tool force"
    )


def test_relax_viscoelastic_stores_the_relaxed_state(backend):
    mat = MATERIALS["Viscoelastic"]
    a, b = pair(lambda: bar(backend, mat)[0], backend)
    sims = [pl.Simulation(m, dt=DT) for m in (a, b)]
    for s in sims:
        s.relax(tol=1e-7)
        s.run(steps=200)  # continues from the relaxed viscous state: stays at rest
    close(sims[0].displacements, sims[1].displacements, "float64", "visco relaxed")
    v = np.abs(sims[1].velocities).max()
    assert v < 1e-3 * np.abs(sims[1].displacements).max() / 1e-3, "relaxed state must be at rest"


def test_save_restore_across_backends(backend, tmp_path):
    """A state saved on one backend continues on another to the same bits as an uninterrupted run
    on that backend (states are host objects; the device copy follows them)."""
    mat = MATERIALS["Viscoelastic"]
    cpu, dev = pair(lambda: bar(backend, mat)[0], backend)
    ref = pl.Simulation(dev, dt=DT)
    ref.run(steps=300)
    first = pl.Simulation(cpu, dt=DT)
    first.run(steps=150)
    first.save(tmp_path / "s.npz")
    second = pl.Simulation(dev, dt=DT)
    second.load(tmp_path / "s.npz")
    second.run(steps=150)
    close(ref.displacements, second.displacements, "float64", "restored on " + backend)
    # Two states on one backend, stepped alternately, do not mix (the device copy is per state).
    s1, s2 = dev.state(), dev.state()
    solver = pl.Solver(dev, dt=DT)
    solver.run(s1, steps=150)
    solver.run(s2, steps=10)
    solver.run(s1, steps=150)
    close(ref.displacements, s1.displacements, "float64", "interleaved states")


def test_step_in_out_matches_run(backend):
    m = bar(backend)[0].finalize("float64", backend=backend)
    solver = pl.Solver(m, dt=DT)
    a, b = m.state(), m.state()
    solver.run(a, steps=50)
    s_in, s_out = m.state(), m.state()
    for _ in range(50):
        solver.step(s_in, s_out)
        s_in, s_out = s_out, s_in
    # Both take their steps' times from the state's run clock (t_epoch + kΔt): the same bits.
    np.testing.assert_array_equal(a.displacements, s_in.displacements)
    np.testing.assert_array_equal(b.displacements, 0.0)  # an untouched state stays untouched


def test_a_model_beyond_the_caches_runs_as_a_small_one():
    """Beyond _core.large_model_bytes the CPU writes kernel 1's forces through a one-block scratch
    and streams them past the caches, and kernel 2 prefetches its gathers; the emulated CUDA device
    does neither. The module's bar in 288,000 tets (float64), 30 steps on both: the same motion to
    the module's float64 tolerance (a wrong block or lane would be off by the whole force), and the
    same bits on one and two CPU threads."""
    b = bar("cpu", cells=(80, 40, 15))[0]
    runs = {}
    for name, on in {
        "cpu 1": dict(threads=1),
        "cpu 2": dict(threads=2),
        "emulated": dict(backend="cuda-emulated"),
    }.items():
        m = b.finalize("float64", **on)
        assert m.memory_bytes > pl._core.large_model_bytes
        sim = pl.Simulation(m, dt=1e-5)
        sim.run(steps=30)
        runs[name] = sim.displacements
    assert np.abs(runs["cpu 2"]).max() > 0.0  # gravity has begun to ramp up
    np.testing.assert_array_equal(runs["cpu 1"], runs["cpu 2"])
    close(runs["emulated"], runs["cpu 2"], "float64", "streamed vs stored forces")


@pytest.mark.parametrize("how", ["inverted", "nan"])
def test_instability_names_element_and_quantity(backend, how):
    """A crushing prescribed displacement inverts elements; a NaN load makes every J NaN. Both
    backends report the same element, quantity and a real value (the old CUDA check reported
    'displacement 0 m' for a NaN)."""

    def make():
        b, X, T = bar(backend)
        tip = np.nonzero(X[:, 0] > L - 1e-9)[0]
        value = -0.2 if how == "inverted" else float("nan")
        if how == "nan":
            b.add_force(tip, (0.0, 0.0, 1e30), curve=pl.Step(0.0))  # overflows float32 → inf/NaN
        else:
            b.prescribe(tip, value, "x", curve=pl.Ramp(0.02))
        return b

    dtype = "float32" if how == "nan" else "float64"
    errs = []
    for backend_ in ("cpu", backend):
        m = make().finalize(dtype, backend=backend_)
        with pytest.raises(pl.InstabilityError) as e:
            pl.Simulation(m, dt=DT).run(until=0.1)
        errs.append(e.value)
    a, b = errs
    assert (a.quantity, a.element, a.node) == (b.quantity, b.element, b.node)
    assert a.time == pytest.approx(b.time)
    if how == "inverted":  # J <= 0, or NaN once the inverted element has blown up before a check
        assert a.quantity == "J" and not a.value > 0 and not b.value > 0
    else:
        assert not math.isfinite(b.value) or abs(b.value) > 0, b
        assert "0 m" not in str(b)


def test_cli_runs_a_scene_on_the_backend(backend, tmp_path):
    """`pliant run --backend NAME` (and a scene's [solver] backend): the same final field as the
    CPU run, and the summary names the backend."""
    import json

    import meshio
    from typer.testing import CliRunner

    from pliant.cli import app

    scene = tmp_path / "bar.toml"
    scene.write_text("""title = "bar"
[mesh]
primitive = "box"
size = [0.10, 0.02, 0.02]
cells = [10, 2, 2]
[[material]]
type = "neo-hookean"
E = 2.0e4
nu = 0.45
density = 1000.0
[solver]
duration = 0.05
damping = 20.0
[[constraint]]
type = "fix"
nodes = { plane = { point = [-0.05, 0.0, 0.0], normal = [1.0, 0.0, 0.0] } }
[[load]]
type = "gravity"
[output]
frames = 1
""")
    fields = {}
    for name in ("cpu", backend):
        out = tmp_path / name
        r = CliRunner().invoke(app, ["run", str(scene), "-o", str(out), "--backend", name, "--no-progress"])
        assert r.exit_code == 0, r.output
        assert json.loads((out / "summary.json").read_text())["backend"] == name
        last = sorted(out.glob("*.vtu"))[-1]
        fields[name] = meshio.read(last).point_data["displacement"]
    close(fields["cpu"], fields[backend], "float32", "CLI run")


def test_unknown_backend_is_refused_by_name():
    b = bar("cpu")[0]
    with pytest.raises(pl.InputError, match="cuda-emulated"):
        b.finalize(backend="gpu")
