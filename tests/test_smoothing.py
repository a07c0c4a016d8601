"""Edge-smoothed strain (ES-FEM-T4, `strain_smoothing = "edge"`) against closed forms: the patch
test, rigid rotation, a bar of two materials in series, and the cantilever against Timoshenko
(its convergence under refinement, and with T4ANP at ν = 0.49); on every backend."""

import math

import numpy as np
import pytest

import pliant as pl
from pliant.mesh.topology import boundary_faces
from pliant.validate.models import cantilever_tip_deflection, tip_loaded_cantilever
from pliant.validate.references import timoshenko_tip_deflection

E, NU = 1.0e4, 0.3  # Pa, 1


def _jittered_cube(backend, material, smoothing="edge", anp=False, dtype="float64"):
    X, T = pl.mesh.box_tets((0.1, 0.1, 0.1), (4, 4, 4), jitter=0.3, seed=3)
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(material, density=1000.0)
    b.strain_smoothing = smoothing
    b.nodal_pressure = anp
    return b.finalize(dtype, backend=backend), X


def _neo_hookean_cauchy(F, mu, K):
    """σ = μ J^(−5/3) dev(F Fᵀ) + K (J − 1) I of the decoupled Neo-Hookean (closed form)."""
    J = np.linalg.det(F)
    b = F @ F.T
    sig = mu * J ** (-5 / 3) * (b - np.trace(b) / 3 * np.eye(3)) + K * (J - 1) * np.eye(3)
    return sig[[0, 1, 2, 0, 1, 0], [0, 1, 2, 1, 2, 2]]


@pytest.mark.parametrize("anp", [False, True])
def test_patch_test_of_a_homogeneous_deformation(backend, anp):
    """u = A X on a jittered mesh: every interior node's internal force vanishes (the smoothed
    gradient of a linear field is exact) and every element's stress is the closed form of F = I + A.
    Tolerances: round-off of sums of O(100) terms of size σ·h² in float64 (1e-10 relative)."""
    material = pl.NeoHookean(E=E, nu=NU)
    model, X = _jittered_cube(backend, material, anp=anp)
    A = np.array([[0.02, 0.01, -0.005], [0.003, -0.01, 0.012], [-0.008, 0.004, 0.015]])
    s = model.state()
    s.set_displacements(X @ A.T)
    f = model.internal_forces(s)
    inner = np.all((X > 1e-9) & (X < 0.1 - 1e-9), axis=1)
    expected = _neo_hookean_cauchy(np.eye(3) + A, material.mu, material.K)
    scale = np.abs(expected).max() * 0.025**2  # σ times a cell face [N]
    assert np.abs(f[inner]).max() < 1e-10 * scale
    assert np.abs(f[~inner]).max() > 1e-3 * scale  # the boundary carries the traction
    sig = model.element_results(s)["cauchy"]
    assert np.abs(sig - expected).max() < 1e-10 * np.abs(expected).max()


def test_rigid_rotation_is_stress_free(backend):
    """A rotation by 50° about a skew axis and a translation: no force, J = 1 (to round-off)."""
    model, X = _jittered_cube(backend, pl.NeoHookean(E=E, nu=0.45))
    k = np.array([1.0, 2.0, -0.5]) / math.sqrt(5.25)
    a = math.radians(50.0)
    Kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    R = np.eye(3) + math.sin(a) * Kx + (1 - math.cos(a)) * Kx @ Kx
    s = model.state()
    s.set_displacements(X @ R.T - X + [0.3, -0.1, 0.2])
    f = model.internal_forces(s)
    assert np.abs(f).max() < 1e-12 * E * 0.025**2
    assert np.abs(model.element_results(s)["J"] - 1).max() < 1e-12


def test_two_materials_in_series_stretch_as_springs(backend):
    """A bar of two halves (E and 4E, ν = 0, linear elasticity) pulled by a uniform traction σ on its
    free end (on rollers at x = 0, y = 0, z = 0): the domains of the interface edges belong to one
    material each, so the stretch is the series-spring closed form σ L/2 (1/E + 1/(4E)). Uniaxial
    stress is exact for linear tets and for edge domains alike; 1e-8: the relaxation tolerance
    (1e-10 relative residual, measured 2.5e-10 off) with margin."""
    L, W, sigma = 0.1, 0.02, 10.0
    X, T = pl.mesh.box_tets((L, W, W), (8, 2, 2))
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    left = np.nonzero(X[T].mean(axis=1)[:, 0] < L / 2)[0]
    right = np.setdiff1d(np.arange(len(T)), left)
    b.set_material(pl.LinearElastic(E=E, nu=0.0), density=1000.0, elements=left, name="soft")
    b.set_material(pl.LinearElastic(E=4 * E, nu=0.0), density=1000.0, elements=right, name="stiff")
    b.strain_smoothing = "edge"
    for d, axis in enumerate("xyz"):
        b.fix(np.nonzero(X[:, d] < 1e-9)[0], axis)
    faces, _ = boundary_faces(T)
    b.add_pressure(faces[np.all(X[faces][:, :, 0] > L - 1e-9, axis=1)], -sigma, pl.Ramp(1.0))
    model = b.finalize("float64", backend=backend)
    sim = pl.Simulation(model)
    sim.relax(at_time=1.0, tol=1e-10, max_steps=200_000)
    end = np.nonzero(X[:, 0] > L - 1e-9)[0]
    expected = sigma * (L / 2) * (1 / E + 1 / (4 * E))
    assert sim.displacements[end, 0] == pytest.approx(np.full(end.size, expected), rel=1e-8)


L, H, P = 1.0, 0.1, 1.0e-2  # the cantilever of tests/test_cantilever.py: m, m, N


def _stiffness(X, T, E, nu, domains="edge"):
    """Global linear-elastic stiffness [N/m] (3N × 3N) assembled directly, K = Σ_k V_k B̄_kᵀ D B̄_k:
    over the edges with B̄_k from the volume-weighted mean shape-function gradients of the edge's
    tets (ES-FEM-T4; Liu, Nguyen-Thoi & Lam 2009, J. Sound Vib. 320:1100, eqs. 14-18), or over
    the elements (plain T4). An assembled stiffness, not the engine's regrouping of forces."""
    import itertools

    import scipy.sparse as sp

    lam, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
    D = np.diag([2 * mu] * 3 + [mu] * 3)  # Voigt, engineering shear strains
    D[:3, :3] += lam
    Dm = X[T[:, :3]] - X[T[:, 3:4]]
    G = np.zeros((len(T), 4, 3))
    G[:, :3] = np.transpose(np.linalg.inv(Dm), (0, 2, 1))
    G[:, 3] = -G[:, :3].sum(axis=1)
    V = np.abs(np.linalg.det(Dm)) / 6
    around: dict = {}
    for e, t in enumerate(T):
        for key in itertools.combinations(sorted(t), 2) if domains == "edge" else [e]:
            around.setdefault(key, []).append(e)
    share = 1 / 6 if domains == "edge" else 1.0  # the fraction of a tet in each of its domains
    rows, cols, vals = [], [], []
    for tets in around.values():
        nodes = np.unique(T[tets])
        g = np.zeros((len(nodes), 3))
        for e in tets:
            g[np.searchsorted(nodes, T[e])] += V[e] * G[e]
        vk = share * V[tets].sum()
        g *= share / vk
        B = np.zeros((6, 3 * len(nodes)))
        for a, (x, y, z) in enumerate(g):
            B[:, 3 * a : 3 * a + 3] = [[x, 0, 0], [0, y, 0], [0, 0, z], [y, x, 0], [0, z, y], [z, 0, x]]
        dof = (3 * nodes[:, None] + np.arange(3)).ravel()
        rows.append(np.repeat(dof, dof.size))
        cols.append(np.tile(dof, dof.size))
        vals.append((vk * B.T @ D @ B).ravel())
    n = 3 * len(X)
    return sp.csr_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n)
    ), V


def _direct_solve(K, fixed, loads):
    """u [m] (N, 3) of K u = f with the nodes ``fixed`` clamped (sparse LU)."""
    import scipy.sparse.linalg as spl

    free = np.ones(K.shape[0], bool)
    free[(3 * fixed[:, None] + np.arange(3)).ravel()] = False
    u = np.zeros(K.shape[0])
    u[free] = spl.spsolve(K[free][:, free].tocsc(), loads.ravel()[free])
    return u.reshape(-1, 3)


def test_engine_matches_a_direct_solve_of_the_smoothed_stiffness():
    """The tip-loaded cantilever (2 elements through the depth) relaxed by the engine against a
    direct solve of the same ES-FEM-T4 stiffness assembled independently: the whole displacement
    field within 1e-6 of its largest value (measured 5e-8: the relaxation's 1e-9 residual tolerance)."""
    model, tip = tip_loaded_cantilever(20, pl.LinearElastic(E=1e6, nu=0.0), P, L, H, smoothing="edge")
    sim = pl.Simulation(model)
    sim.relax(tol=1e-9, max_steps=1_000_000)
    X, T = pl.mesh.box_tets((L, H, H), (20, 2, 2))
    loads = np.zeros_like(X)
    w = np.ones(tip.size)
    for d in (1, 2):
        w[(X[tip, d] < 1e-9) | (X[tip, d] > H - 1e-9)] *= 0.5
    loads[tip, 2] = -P * w / w.sum()
    direct = _direct_solve(_stiffness(X, T, 1e6, 0.0)[0], np.nonzero(X[:, 0] < 1e-9)[0], loads)
    assert np.abs(sim.displacements - direct).max() < 1e-6 * np.abs(direct).max()


def test_smoothing_is_softer_so_the_element_critical_step_holds():
    """K_edge ≤ K_T4 in energy (each edge's strain is a mean of its tets' strains, and the energy is
    convex), so with the same lumped mass the highest frequency does not rise and the elements'
    critical step, which the engine uses, stays safe: the largest eigenvalue of M⁻¹K, computed
    for both assembled stiffnesses on a jittered mesh (ν = 0.45), is lower with edge smoothing."""
    import scipy.sparse.linalg as spl

    X, T = pl.mesh.box_tets((0.1, 0.1, 0.1), (3, 3, 3), jitter=0.3, seed=5)
    top = {}
    for kind in ("element", "edge"):
        K, V = _stiffness(X, T, 1e4, 0.45, kind)
        m = np.zeros(len(X))
        np.add.at(m, T, np.repeat(V[:, None] / 4 * 1000.0, 4, axis=1))
        s = 1 / np.sqrt(np.repeat(m, 3))
        top[kind] = spl.eigsh(K.multiply(s[:, None]).multiply(s[None, :]).tocsc(), k=1, which="LA")[0][0]
    print("largest ω² edge / element", top["edge"] / top["element"])
    assert top["edge"] <= top["element"] * (1 + 1e-9)


def test_cantilever_converges_to_timoshenko_far_faster_than_linear_tets():
    """ν = 0, 1, 2 and 4 elements through the depth. Linear tets are 75.6 %, 45.0 %, 17.6 % off
    (tests/test_cantilever.py); edge smoothing removes most of the shear locking."""
    ref = timoshenko_tip_deflection(P, L, H, 1e6, 0.0)
    le = pl.LinearElastic(E=1e6, nu=0.0)
    d = [cantilever_tip_deflection(n, le, smoothing="edge") / ref for n in (1, 2, 4)]
    print("deflection / Timoshenko", d)
    assert abs(d[1] - 1) < 0.03
    assert abs(d[2] - 1) < 0.015
    assert abs(d[2] - 1) < abs(d[0] - 1) / 10


def test_with_nodal_pressure_nearly_incompressible_bending():
    """ν = 0.49, 2 elements through the depth: edges for the isochoric part, T4ANP's nodal pressure
    for the volumetric part (selective ES/NS-FEM-T4). Measured 11.0 % off Timoshenko, T4ANP 42.1 %
    (docs/engine.md's table: 3.1 % and 17.0 % at 4); bound 15 %, and at most half T4ANP's error."""
    nu = 0.49
    ref = timoshenko_tip_deflection(P, L, H, 1e6, nu)
    material = pl.NeoHookean(E=1e6, nu=nu)
    es = cantilever_tip_deflection(2, material, nodal_pressure=True, smoothing="edge") / ref
    anp = cantilever_tip_deflection(2, material, nodal_pressure=True) / ref
    print("ES/NS", es, "T4ANP", anp)
    assert abs(es - 1) < 0.15
    assert abs(es - 1) < abs(anp - 1) / 2


def test_same_bits_for_any_thread_count():
    def run(threads):
        X, T = pl.mesh.box_tets((0.1, 0.02, 0.02), (10, 2, 2), jitter=0.2)
        b = pl.ModelBuilder()
        b.add_mesh(X, T)
        b.set_material(pl.NeoHookean(E=2e4, nu=0.45), density=1000.0)
        b.strain_smoothing = "edge"
        b.nodal_pressure = True
        b.fix(np.nonzero(X[:, 0] < 1e-9)[0])
        b.set_gravity((0, 0, -9.81))
        sim = pl.Simulation(b.finalize("float32", threads=threads), dt=1e-4)
        sim.run(steps=300)
        return sim.displacements

    one, two = run(1), run(2)
    assert np.abs(one).max() > 1e-5
    assert np.array_equal(one, two)


def test_viscoelastic_edges_on_every_backend(backend):
    """A viscoelastic bar under gravity with edge smoothing: the Prony state lives on the edges; the
    backend runs the same physics as the CPU (tests/test_backends.py's tolerance, float64: 1e-9 of
    the largest displacement) and the state has 6 values per term per edge slot."""
    X, T = pl.mesh.box_tets((0.1, 0.02, 0.02), (10, 2, 2))

    def make(on):
        b = pl.ModelBuilder()
        b.add_mesh(X, T)
        b.set_material(
            pl.Viscoelastic(pl.NeoHookean(E=2e4, nu=0.45), iso=[(0.4, 0.005)], vol=[(0.2, 0.01)]), 1000.0
        )
        b.strain_smoothing = "edge"
        b.fix(np.nonzero(X[:, 0] < 1e-9)[0])
        b.set_gravity((0.0, 0.0, -9.81), curve=pl.SmoothRamp(0.01))
        b.damping = 20.0
        return b.finalize("float64", backend=on)

    ref, other = make("cpu"), make(backend)
    sa, sb = pl.Simulation(ref, dt=1e-4), pl.Simulation(other, dt=1e-4)
    sa.run(steps=400)
    sb.run(steps=400)
    scale = np.abs(sa.displacements).max()
    assert scale > 1e-5
    assert np.abs(sa.displacements - sb.displacements).max() <= 1e-9 * scale
    assert len(sa.state._s.get_q()) == 6 * 2 * ref._engine.n_edges


def test_a_viscoelastic_edge_smoothed_model_is_not_cut():
    """Its Prony state lives on edges, which a cut changes: refused by name, before anything runs."""
    from pliant.cutting.cut import check_cuttable, cut

    X, T = pl.mesh.box_tets((0.1, 0.1, 0.1), (2, 2, 2))
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(
        pl.Viscoelastic(pl.NeoHookean(E=E, nu=NU), iso=[(0.3, 0.1)]), density=1000.0, name="tissue"
    )
    b.strain_smoothing = "edge"
    with pytest.raises(pl.InputError, match="'tissue': a viscoelastic material with edge-smoothed strain"):
        check_cuttable(b)
    model = b.finalize()
    with pytest.raises(pl.InputError, match="cannot be cut yet"):
        cut(model.state(), [[[0.05, -1, -1], [0.05, 2, -1], [0.05, -1, 2]]])


def test_bad_settings_are_refused_by_name():
    X, T = pl.mesh.box_tets((0.1, 0.1, 0.1), (1, 1, 1))
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(pl.NeoHookean(E=E, nu=NU), density=1000.0)
    b.strain_smoothing = "faces"
    with pytest.raises(pl.InputError, match="strain_smoothing = 'faces'; expected one of 'element', 'edge'"):
        b.finalize()
