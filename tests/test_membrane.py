"""Membrane triangles (ModelBuilder.add_membrane; cpp/include/pliant/membrane.hpp) against closed
forms: the stress resultants of a homogeneous in-plane stretch (Neo-Hookean membrane: Bonet et al.
2000; plane-stress St Venant–Kirchhoff), zero force under a rigid rotation, the lumped mass ρ h A,
the membrane's own stable step, and a solid bar wrapped in membranes stretched to equilibrium
against the uniaxial closed form of both, on every backend."""

import re

import numpy as np
import pytest

import pliant as pl
from pliant.mesh import grid_tets
from pliant.mesh.topology import boundary_faces
from pliant.runner import body_measures

L, W, H = 0.04, 0.03, 0.02  # box [m]


def _box(n=(4, 3, 2)):
    return grid_tets(np.linspace(0, L, n[0] + 1), np.linspace(0, W, n[1] + 1), np.linspace(0, H, n[2] + 1))


def _faces_on(X, T, axis, value):
    B, _ = boundary_faces(T)
    return B[np.all(np.isclose(X[B][:, :, axis], value), axis=1)]


def _builder(X, T, solid=None):
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(solid or pl.StVenantKirchhoff(E=1e3, nu=0.3), density=1000.0)
    return b


def _membrane_forces(X, T, faces, material, u, backend):
    """Internal forces of the model with membranes less those of the same model without: the
    membranes' own nodal forces [N] (N, 3) at displacement u."""
    out = []
    for with_membrane in (True, False):
        b = _builder(X, T)
        if with_membrane:
            b.add_membrane(faces, material)
        m = b.finalize("float64", backend=backend)
        s = m.state()
        s.set_displacements(u)
        out.append(m.internal_forces(s))
    return out[0] - out[1]


MATERIALS = {
    "neo-hookean": pl.NeoHookeanMembrane(mu=2e3, thickness=1e-3, density=1100.0),
    "stvk": pl.StVKMembrane(E=5e3, nu=0.35, thickness=2e-3, density=900.0),
}


def _resultants(material, l1, l2):
    """1st Piola–Kirchhoff stress resultants P11, P22 [N/m] of the in-plane stretch diag(l1, l2)."""
    h = material.thickness
    if isinstance(material, pl.NeoHookeanMembrane):  # S = μ h (I − C33 C⁻¹), C33 = 1/(l1² l2²)
        c33 = 1.0 / (l1 * l2) ** 2
        S11, S22 = material.mu * h * (1 - c33 / l1**2), material.mu * h * (1 - c33 / l2**2)
    else:  # S = h (λ' tr E I + 2 μ E)
        E, nu = material.E, material.nu
        lam, mu = E * nu / (1 - nu**2), E / (2 * (1 + nu))
        E11, E22 = (l1**2 - 1) / 2, (l2**2 - 1) / 2
        S11, S22 = h * (lam * (E11 + E22) + 2 * mu * E11), h * (lam * (E11 + E22) + 2 * mu * E22)
    return l1 * S11, l2 * S22


@pytest.mark.parametrize("kind", sorted(MATERIALS))
def test_a_homogeneous_stretch_gives_the_closed_form_edge_forces(kind, backend):
    """The top face z = H stretched by diag(1.3, 0.9) in its plane (and the box under it, whose
    forces are subtracted): the membrane's nodes on the edge x = L carry P11 · W in x in all, those
    on y = W carry P22 · L in y, interior nodes nothing (a constant-strain patch). float64: the
    sums agree to round-off (1e-9 of the edge force)."""
    X, T = _box()
    material = MATERIALS[kind]
    l1, l2 = 1.3, 0.9
    u = X * [l1 - 1, l2 - 1, 0.0]
    f = _membrane_forces(X, T, _faces_on(X, T, 2, H), material, u, backend)
    P11, P22 = _resultants(material, l1, l2)
    top = np.isclose(X[:, 2], H)
    right, back = top & np.isclose(X[:, 0], L), top & np.isclose(X[:, 1], W)
    left, front = top & np.isclose(X[:, 0], 0), top & np.isclose(X[:, 1], 0)
    np.testing.assert_allclose(f[right, 0].sum(), P11 * W, rtol=1e-9)
    np.testing.assert_allclose(f[left, 0].sum(), -P11 * W, rtol=1e-9)
    np.testing.assert_allclose(f[back, 1].sum(), P22 * L, rtol=1e-9)
    np.testing.assert_allclose(f[front, 1].sum(), -P22 * L, rtol=1e-9)
    interior = top & ~(right | left | back | front)
    scale = abs(P11) * W
    assert interior.any() and np.abs(f[interior]).max() < 1e-9 * scale
    assert np.abs(f[~top]).max() < 1e-12 * scale  # only the membrane's nodes
    assert np.abs(f[:, 2]).max() < 1e-9 * scale  # in its plane


def _energy_per_area(material, l1, l2):
    """Strain energy per reference area h W [J/m²] of the in-plane stretch diag(l1, l2)."""
    h = material.thickness
    if isinstance(material, pl.NeoHookeanMembrane):  # W = μ/2 (l1² + l2² + 1/(l1 l2)² − 3)
        return 0.5 * material.mu * h * (l1**2 + l2**2 + 1 / (l1 * l2) ** 2 - 3)
    E, nu = material.E, material.nu
    lam, mu = E * nu / (1 - nu**2), E / (2 * (1 + nu))
    E11, E22 = (l1**2 - 1) / 2, (l2**2 - 1) / 2
    return h * (0.5 * lam * (E11 + E22) ** 2 + mu * (E11**2 + E22**2))


@pytest.mark.parametrize("kind", sorted(MATERIALS))
@pytest.mark.parametrize("stretch", [(1.3, 0.9), (1.001, 1.0)])
def test_a_homogeneous_stretch_stores_the_closed_form_energy(kind, stretch, backend):
    """The top face stretched by diag(l1, l2) in its plane: each membrane's strain energy is
    A0 h W of the closed form, and Model.strain_energy (and a run's summary) is the box's plus
    theirs (L W h W). float64
    at 30 % (round-off, 1e-9); float32 at 0.1 % strain, where a W formed from the metrics would
    lose its digits (Neo-Hookean W ~ E² formed as a difference of terms ~ E: 1e3 times float32's
    6e-8), to 1e-5 (a few roundings of terms that are each second order)."""
    X, T = _box()
    material = MATERIALS[kind]
    l1, l2 = stretch
    faces = _faces_on(X, T, 2, H)
    for dtype in ("float64", "float32"):
        b = _builder(X, T)
        b.add_membrane(faces, material)
        m = b.finalize(dtype, backend=backend)
        s = m.state()
        s.set_displacements(X * [l1 - 1, l2 - 1, 0.0])
        e = m.membrane_results(s)["energy"]
        area = 0.5 * np.linalg.norm(
            np.cross(X[faces[:, 1]] - X[faces[:, 0]], X[faces[:, 2]] - X[faces[:, 0]]), axis=1
        )
        want = _energy_per_area(material, l1, l2)
        rtol = 1e-9 if dtype == "float64" else 1e-5
        np.testing.assert_allclose(e, area * want, rtol=rtol)
        tets = float(np.dot(m.element_volumes(), m.element_results(s)["energy_density"]))
        np.testing.assert_allclose(m.strain_energy(s) - tets, L * W * want, rtol=rtol)
        summary = body_measures(m, s, m.element_results(s))  # a run's summary.json figures
        np.testing.assert_allclose(summary["strain_energy"] - tets, L * W * want, rtol=rtol)


@pytest.mark.parametrize("kind", sorted(MATERIALS))
def test_a_rigid_rotation_gives_no_force(kind, backend):
    """Membranes on all six faces of the box rotated 60 degrees about an oblique axis: no strain,
    no force (a geometrically linear membrane, such as NiftySim's "Linear", would push back)."""
    X, T = _box()
    axis = np.array([1.0, 2.0, 2.0]) / 3.0
    a = np.radians(60.0)
    K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    R = np.eye(3) + np.sin(a) * K + (1 - np.cos(a)) * K @ K
    u = X @ R.T - X
    B, _ = boundary_faces(T)
    f = _membrane_forces(X, T, B, MATERIALS[kind], u, backend)
    # float64 round-off of the cancelling stresses: 1e-9 of the forces a 10 % strain would give
    scale = 0.1 * MATERIALS[kind].thickness * 2e3 * L
    assert np.abs(f).max() < 1e-9 * scale


def test_the_membrane_mass_is_rho_h_area():
    """The model's total mass is the solid's ρ V plus each membrane's ρ h A (the box's four side
    faces, two materials); add_gravity's m g uses the same masses."""
    X, T = _box()
    b = _builder(X, T)
    sides = [_faces_on(X, T, 1, 0), _faces_on(X, T, 1, W)]
    ends = [_faces_on(X, T, 0, 0), _faces_on(X, T, 0, L)]
    m1, m2 = MATERIALS["stvk"], MATERIALS["neo-hookean"]
    b.add_membrane(np.vstack(sides), m1)
    b.add_membrane(np.vstack(ends), m2)
    b.add_gravity((0, 0, -9.81), np.arange(len(X)))
    m = b.finalize("float64")
    expected = (
        1000.0 * L * W * H + m1.density * m1.thickness * 2 * L * H + m2.density * m2.thickness * 2 * W * H
    )
    np.testing.assert_allclose(m.mass.sum(), expected, rtol=1e-12)
    assert m.n_membranes == sum(len(F) for F in sides + ends)
    # From rest the first step moves each node by Δt² g (u⁺ = Δt² M⁻¹ m g, no damping): the
    # gravity load is each node's own lumped mass times g.
    dt = 1e-6
    rest, moved = m.state(), m.state()
    pl.Solver(m, dt=dt).step(rest, moved, dt)
    np.testing.assert_allclose(moved.displacements[:, 2], -9.81 * dt**2, rtol=1e-9)


@pytest.mark.parametrize("kind", sorted(MATERIALS))
def test_the_stiffness_scale_reaches_the_membranes(kind, backend):
    """Solver.scale_materials(k), the viewer's stiffness slider, multiplies every material's moduli,
    the membranes' too: the box under a membrane on its top, stretched by diag(1.3, 0.9, 1) and let
    go from rest, first moves so that Σ m Δu_x / Δt² over the nodes on x = L is −k (P11 W H + P11ᵐ W),
    the closed-form resultants of the solid (St Venant–Kirchhoff) and of the membrane, at k = 1 and
    3 (float64, no damping: round-off, 1e-9). Membranes left unscaled would give
    −(3 P11 W H + P11ᵐ W) at k = 3."""
    X, T = _box()
    material = MATERIALS[kind]
    l1, l2 = 1.3, 0.9
    E, nu = 1e3, 0.3  # _builder's solid
    lam, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
    E11, E22 = (l1**2 - 1) / 2, (l2**2 - 1) / 2
    P11_solid = l1 * (lam * (E11 + E22) + 2 * mu * E11)
    P11_membrane = _resultants(material, l1, l2)[0]
    b = _builder(X, T)
    b.add_membrane(_faces_on(X, T, 2, H), material)
    m = b.finalize("float64", backend=backend)
    right = np.isclose(X[:, 0], L)
    dt = 1e-5  # well below the stable step (about 1e-3 s); Δu about 1e-6 m, u 1e-2: 1e-12 round-off
    for k in (1.0, 3.0):
        rest, moved = m.state(), m.state()
        rest.set_displacements(X * [l1 - 1, l2 - 1, 0.0])
        solver = pl.Solver(m, dt=dt, damping=0.0)
        solver.scale_materials(k)
        solver.step(rest, moved, dt)
        du = moved.displacements - rest.displacements
        pull = (m.mass[right] * du[right, 0]).sum() / dt**2
        np.testing.assert_allclose(pull, -k * (P11_solid * W * H + P11_membrane * W), rtol=1e-9)


def test_a_stiff_membrane_sets_the_critical_step():
    """A membrane far stiffer than the solid under it limits the step: its smallest altitude over
    √(E/((1 − ν²) ρ)) (plane stress), named by the model."""
    X, T = _box()
    b = _builder(X, T)
    stiff = pl.StVKMembrane(E=1e9, nu=0.3, thickness=1e-4, density=1000.0)
    faces = _faces_on(X, T, 2, H)
    b.add_membrane(faces, stiff)
    m = b.finalize("float64")
    P = X[faces]
    edges = np.linalg.norm(P - P[:, [1, 2, 0]], axis=2)
    area = 0.5 * np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), axis=1)
    alt = (2 * area / edges.max(axis=1)).min()
    np.testing.assert_allclose(m.dt_critical, alt / np.sqrt(1e9 / (1 - 0.09) / 1000.0), rtol=1e-12)
    assert m.dt_critical_membrane >= 0 and m.dt_critical_limiter.startswith("membrane ")


def test_a_wrapped_bar_stretched_to_equilibrium(backend):
    """A St Venant–Kirchhoff bar wrapped in St Venant–Kirchhoff membranes of the same ν on its four
    long faces, pulled 20 % in x (x = 0 on rollers): both contract alike (E_yy = E_zz = −ν E_xx,
    uniaxial stress in Green strain), so the stretch is homogeneous and the pull is
    λ E_xx (E_s W H + E_m h 2 (W + H)), 57 % of it the membranes'. Relaxed to 1e-8 in float64; the
    pull to 1e-6 (the relaxation's residual), the lateral contraction to 1e-5 of itself."""
    X, T = _box((6, 2, 2))
    Es, nu = 1e3, 0.3
    b = _builder(X, T, pl.StVenantKirchhoff(E=Es, nu=nu))
    mat = pl.StVKMembrane(E=4e3, nu=nu, thickness=2e-3, density=900)
    long_faces = [_faces_on(X, T, 1, 0), _faces_on(X, T, 1, W), _faces_on(X, T, 2, 0), _faces_on(X, T, 2, H)]
    b.add_membrane(np.vstack(long_faces), mat)
    x0, x1 = np.nonzero(np.isclose(X[:, 0], 0))[0], np.nonzero(np.isclose(X[:, 0], L))[0]
    stretch = 1.2
    b.fix(x0, "x")
    b.prescribe(x1, (stretch - 1) * L, "x")
    corner = int(np.argmin(np.linalg.norm(X, axis=1)))
    b.fix([corner], "yz")
    b.fix([int(np.argmin(np.linalg.norm(X - [0, W, 0], axis=1)))], "z")
    m = b.finalize("float64", backend=backend)
    sim = pl.Simulation(m, dt=0.5 * m.dt_critical)
    assert sim.relax(tol=1e-8).converged
    pull = m.internal_forces(sim.state)[x1, 0].sum()  # the bar pulls back on the support: f = r
    Exx = (stretch**2 - 1) / 2
    solid = stretch * Es * Exx * W * H
    membrane = stretch * mat.E * Exx * mat.thickness * 2 * (W + H)
    np.testing.assert_allclose(pull, solid + membrane, rtol=1e-6)
    lateral = np.sqrt(1 - 2 * nu * Exx)  # E_yy = −ν E_xx
    u = sim.displacements
    # the residual 1e-8 leaves about 1e-6 of the lateral displacement (measured 1.2e-6): 1e-5
    tol = 1e-5 * (1 - lateral) * W
    np.testing.assert_allclose(u[:, 1], (lateral - 1) * (X[:, 1] - X[corner, 1]), atol=tol)
    np.testing.assert_allclose(u[:, 2], (lateral - 1) * (X[:, 2] - X[corner, 2]), atol=tol)


SCENE_MEMBRANE = """
[[membrane]]
type = "st-venant-kirchhoff"
E = 5e4
nu = 0.3
thickness = 1e-3
density = 1200.0
nodes = { plane = { point = [0, 0, 0.1], normal = [0, 0, 1] } }
"""


def test_a_scene_lays_membranes_on_the_selected_boundary(tmp_path):
    """[[membrane]] on the tension scene's top face (z = 0.1 of a 0.1 m cube): the triangles whose
    nodes all lie on it, their mass ρ h A added (A = 0.01 m²)."""
    from test_scene import TENSION, _write

    from pliant.scene import load_scene

    sc = load_scene(_write(tmp_path, TENSION + SCENE_MEMBRANE))
    m = sc.builder.finalize("float64")
    X, T = m.reference_positions, m.tets
    top = boundary_faces(T)[0]
    top = top[np.all(np.isclose(X[top][:, :, 2], 0.1), axis=1)]
    assert m.n_membranes == len(top) > 0
    np.testing.assert_allclose(m.mass.sum(), 1000.0 * 1e-3 + 1200.0 * 1e-3 * 0.01, rtol=1e-9)


@pytest.mark.parametrize(
    "patch, key, text",
    [
        (
            ("thickness = 1e-3", "thickness = -1e-3"),
            "membrane[0]",
            "thickness = -0.001; expected a finite value > 0",
        ),
        (("nu = 0.3", "mu = 0.3"), "membrane[0]", "st-venant-kirchhoff takes (E, nu); got (E, mu)"),
        (('"st-venant-kirchhoff"', '"rubber"'), "membrane[0].type", "unknown membrane 'rubber'"),
        (("density = 1200.0", "density = 1200.0\ncolour = 1"), "membrane[0].colour", "unknown key 'colour'"),
        (
            (
                "plane = { point = [0, 0, 0.1], normal = [0, 0, 1] }",
                "box = [[-0.01, -0.01, 0.09], [0.01, 0.01, 0.11]]",
            ),
            "membrane[0].nodes",
            "hold no whole boundary triangle",
        ),
    ],
)
def test_scene_membrane_mistakes_name_key_and_line(tmp_path, patch, key, text):
    from test_scene import TENSION, _write

    from pliant.scene import SceneError, load_scene

    bad = (TENSION + SCENE_MEMBRANE).replace(*patch)
    p = _write(tmp_path, bad)
    with pytest.raises(SceneError) as err:
        load_scene(p)
    assert err.value.key == key and text in str(err.value) and err.value.line is not None


def test_a_batch_keeps_each_bodys_membranes(backend):
    """Batch.replicate of a box with a stretched membrane on its top: each body's membrane forces
    are the single model's (the membranes move with their body's node offset), bit for bit."""
    X, T = _box()
    b = _builder(X, T)
    b.add_membrane(_faces_on(X, T, 2, H), MATERIALS["neo-hookean"])
    single = b.finalize("float64", backend=backend)
    from pliant.tled.batch import Batch

    batch = Batch.replicate(b, [pl.StVenantKirchhoff(E=1e3, nu=0.3)] * 3, "float64", backend=backend)
    m = batch.model
    assert m.n_membranes == 3 * single.n_membranes
    u = X * [0.3, -0.1, 0.0]
    s1 = single.state()
    s1.set_displacements(u)
    sb = m.state()
    sb.set_displacements(np.vstack([u] * 3))
    f1, fb = single.internal_forces(s1), m.internal_forces(sb)
    for k in range(3):
        np.testing.assert_array_equal(batch.nodes(fb, k), f1)


def test_a_capsule_on_a_solid_steps_at_the_whole_models_stable_step():
    """A stiff capsule (μ = 3 MPa, 0.1 mm) on a soft box (E = 4 kPa): the membrane's own estimate
    (its altitude over √(4μ/ρ), its mass alone) is several times below the step the model takes,
    whose corners carry the box's mass. The solver's default step is 0.8 × 0.99 of 2/ω_max, checked
    here against ω_max of M⁻¹K with K assembled by central differences of the internal forces
    (another method: numpy's dense eigenvalues; to 1 %, the engine's Lanczos tolerance), and a run
    of 500 steps at it stays put under gravity (bounded by the static sag's order)."""
    X, T = grid_tets(np.linspace(0, 0.03, 4), np.linspace(0, 0.02, 3), np.linspace(0, 0.02, 3))
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(pl.NeoHookean(E=4e3, nu=0.45), 1050.0)
    b.add_membrane(boundary_faces(T)[0], pl.NeoHookeanMembrane(mu=3e6, thickness=1e-4, density=1100.0))
    base = np.nonzero(X[:, 2] == 0)[0]
    b.fix(base)
    b.set_gravity()
    m = b.finalize("float64")
    assert m.dt_critical_membrane >= 0
    free = np.setdiff1d(np.arange(len(X)), base)
    dofs = [(n, d) for n in free for d in range(3)]
    K = np.zeros((len(dofs), len(dofs)))
    h = 1e-7
    for j, (n, d) in enumerate(dofs):
        cols = []
        for sign in (1, -1):
            u = np.zeros_like(X)
            u[n, d] = sign * h
            s = m.state()
            s.set_displacements(u)
            cols.append(m.internal_forces(s)[free].ravel())
        K[:, j] = (cols[0] - cols[1]) / (2 * h)
    mass = np.repeat(m.mass[free], 3)
    w2 = np.linalg.eigvals(K / mass[:, None]).real.max()
    exact = 2 / np.sqrt(w2)
    solver = pl.Solver(m)
    np.testing.assert_allclose(solver.dt, 0.8 * 0.99 * exact, rtol=1e-2)
    assert solver.dt > 3 * m.dt_critical
    s = m.state()
    solver.run(s, steps=500)
    assert np.abs(s.displacements).max() < 0.02


@pytest.mark.parametrize(
    "faces, material, error, text",
    [
        ([[0, 1, 2.5]], MATERIALS["stvk"], pl.InputError, "expected (F, 3) integer node ids"),
        ([[0, 1, 999]], MATERIALS["stvk"], pl.InputError, "node 999 out of range"),
        (
            [[0, 1, 1]],
            MATERIALS["stvk"],
            pl.DegenerateElementError,
            "membrane 0 (nodes [0, 1, 1]) is degenerate",
        ),
        (
            [[0, 1, 5]],
            "rubber",
            pl.MaterialError,
            "expected pliant.StVKMembrane or pliant.NeoHookeanMembrane",
        ),
        (
            [[0, 1, 5]],
            pl.StVKMembrane(E=1e300, nu=0.3, thickness=1e300, density=1e300),
            pl.MaterialError,
            "mass or stiffness overflows",
        ),
    ],
)
def test_add_membrane_mistakes_are_named(faces, material, error, text):
    X, T = _box()
    b = _builder(X, T)
    with pytest.raises(error) as e:
        b.add_membrane(faces, material)
    assert text in str(e.value)


@pytest.mark.parametrize(
    "cls, kwargs, text",
    [
        (pl.NeoHookeanMembrane, dict(mu=float("nan"), thickness=1e-3, density=1e3), "mu = nan"),
        (pl.StVKMembrane, dict(E=1e3, nu=0.6, thickness=1e-3, density=1e3), "expected -1 < nu <= 0.5"),
        (pl.StVKMembrane, dict(E=1e3, nu=0.3, thickness=0, density=1e3), "thickness = 0"),
        (pl.NeoHookeanMembrane, dict(mu=1e3, thickness=1e-3, density="x"), "density = 'x'"),
    ],
)
def test_membrane_material_mistakes_are_named(cls, kwargs, text):
    with pytest.raises(pl.MaterialError, match=re.escape(text)):
        cls(**kwargs)


def _sheet(n=4):
    """A 1 m square sheet in the plane z = 0 of n × n squares, each cut into two triangles."""
    xs = np.linspace(0, 1, n + 1)
    X = np.array([[x, y, 0.0] for x in xs for y in xs])
    idx = lambda i, j: i * (n + 1) + j  # noqa: E731
    F = []
    for i in range(n):
        for j in range(n):
            F += [
                [idx(i, j), idx(i + 1, j), idx(i + 1, j + 1)],
                [idx(i, j), idx(i + 1, j + 1), idx(i, j + 1)],
            ]
    return X, np.array(F)


@pytest.mark.parametrize("kind", sorted(MATERIALS))
def test_a_sheet_of_membranes_alone_stretches_as_its_closed_form(kind, backend):
    """Membranes without a solid (add_mesh with no tets): a square sheet on rollers at x = 0, its
    edge x = 1 moved 30 %, sides free, held in its plane: uniaxial membrane stress, so the width
    contracts to √(1 − 2 ν E_xx) (plane-stress St Venant–Kirchhoff) or λ^(−1/2) (incompressible
    Neo-Hookean), and the pull is W P11 (P11 = λ S11: h E E_xx, or μ h (λ − λ⁻²)). Relaxed to 1e-10 in
    float64, the stretch in ten increments: 1e-6. Model.membrane_results: the area ratio λ × width and
    the Cauchy resultant pull / width along x, to 1e-6."""
    X, F = _sheet()
    material = MATERIALS[kind]
    b = pl.ModelBuilder()
    b.add_mesh(X, np.zeros((0, 4), int))
    b.add_membrane(F, material)
    left, right = np.nonzero(X[:, 0] == 0)[0], np.nonzero(X[:, 0] == 1)[0]
    lam = 1.3
    b.fix(left, "x")
    b.fix([0], "y")
    b.fix(np.arange(len(X)), "z")
    b.prescribe(right, lam - 1, "x", curve=pl.Ramp(1.0))
    m = b.finalize("float64", backend=backend)
    assert m.n_elements == 0 and m.dt_critical_element == -1 and m.dt_critical_membrane >= 0
    sim = pl.Simulation(m)
    assert sim.relax(tol=1e-10, increments=10).converged  # the edge moved in ten loads
    Exx = (lam**2 - 1) / 2
    if kind == "stvk":
        width, pull = np.sqrt(1 - 2 * material.nu * Exx), lam * material.thickness * material.E * Exx
    else:
        width, pull = lam**-0.5, material.mu * material.thickness * (lam - lam**-2)
    u = sim.displacements
    np.testing.assert_allclose(u[:, 1], (width - 1) * X[:, 1], atol=1e-6 * (1 - width))
    np.testing.assert_allclose(m.internal_forces(sim.state)[right, 0].sum(), pull, rtol=1e-6)
    # Every membrane's area grows by λ × width; its Cauchy resultant is the pull over the current
    # width (force per current length), along x alone.
    r = m.membrane_results(sim.state)
    np.testing.assert_allclose(r["area_ratio"], lam * width, rtol=1e-6)
    np.testing.assert_allclose(r["tension"][:, 0], pull / width, rtol=1e-6)
    np.testing.assert_allclose(r["max_tension"], pull / width, rtol=1e-6)
    assert np.abs(r["tension"][:, 1:]).max() < 1e-6 * pull


def test_a_tool_meets_a_sheet_of_membranes_alone():
    """A rigid sphere pushed down through a sheet of membranes alone (pinned at its four corners):
    the sheet's nodes are contact nodes as a solid's boundary nodes are, kept half the sheet's
    thickness h from the tool (its face meets the sphere), so none ends up nearer the centre than
    r + h/2 (within the contact's tolerance, 1e-6 of it) and the sheet is carried down."""
    X, F = _sheet(8)
    b = pl.ModelBuilder()
    b.add_mesh(X, np.zeros((0, 4), int))
    b.add_membrane(F, pl.NeoHookeanMembrane(mu=1e4, thickness=1e-3, density=1e3))
    corners = np.nonzero(np.isin(X[:, 0], (0, 1)) & np.isin(X[:, 1], (0, 1)))[0]
    b.fix(corners)
    r = 0.15
    b.add_tool(pl.contact.Sphere(radius=r).at(0.0, (0.5, 0.5, r + 0.01)).at(0.5, (0.5, 0.5, r - 0.1)))
    b.damping = 20.0
    m = b.finalize("float64")
    sim = pl.Simulation(m)
    sim.run(until=0.5)
    x = sim.state.positions
    centre = np.array([0.5, 0.5, r - 0.1])
    near = np.linalg.norm(x - centre, axis=1).min()
    assert near > (r + 0.5e-3) * (1 - 1e-6) and near < r + 0.5e-3 + 1e-3  # in contact, at h/2
    assert x[:, 2].min() < -0.05  # carried down, not passed through
