"""Sheets that bend (``bending`` on a membrane material: rotation-free shell triangles,
cpp/include/pliant/membrane.hpp ``membrane_bending_forces``, cpp/src/model_bending.cpp) against
Kirchhoff plate theory: the bending energy of quadratic shapes (cylinder, saddle, dome) on regular
and irregular meshes, no force inside a sheet under a constant moment (the patch test), forces that
are the energy's gradient, no force or energy under a rigid motion of a curved sheet, a cantilever
strip against Euler–Bernoulli (statics on every backend, its convergence, its first bending
frequency), square plates under pressure against Navier's series and Timoshenko's clamped plate,
the critical step against the Lanczos stable step, NiftySim's LinearShell and scenes."""

import json
import math
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spl
from scipy.spatial import Delaunay

import pliant as pl
from pliant.tled.patches import across_edges, patch_nodes


def _sheet(nx, ny, lx, ly, jitter=0.0, seed=2):
    """A flat lx × ly sheet [m] in z = 0: the Delaunay triangles of an (nx + 1) × (ny + 1) grid,
    its inner points moved by up to ``jitter`` of a cell (an irregular mesh). X (N, 3), F (K, 3)."""
    xs, ys = np.linspace(0, lx, nx + 1), np.linspace(0, ly, ny + 1)
    P = np.array([[x, y] for x in xs for y in ys])
    inner = (P[:, 0] > 0) & (P[:, 0] < lx) & (P[:, 1] > 0) & (P[:, 1] < ly)
    rng = np.random.default_rng(seed)
    P[inner] += jitter * min(lx / nx, ly / ny) * rng.uniform(-1, 1, (inner.sum(), 2))
    return np.c_[P, np.zeros(len(P))], Delaunay(P).simplices


def _model(X, F, material, fixed=None, dofs="xyz", clamped=None, backend="cpu"):
    b = pl.ModelBuilder()
    b.add_mesh(X, np.zeros((0, 4), int))
    b.add_membrane(F, material, clamped=clamped)
    if fixed is not None:
        b.fix(fixed, dofs)
    return b.finalize("float64", backend=backend)


def _energies(X, F, material, u):
    """Each membrane's strain energy [J] at displacements u, and the same without bending: their
    difference is the bending energy alone."""
    out = []
    for m in (material, pl.StVKMembrane(material.E, material.nu, material.thickness, material.density)):
        model = _model(X, F, m)
        s = model.state()
        s.set_displacements(u)
        out.append(model.membrane_results(s)["energy"])
    return out[0], out[1]


def _areas(X, F):
    return 0.5 * np.linalg.norm(np.cross(X[F[:, 1]] - X[F[:, 0]], X[F[:, 2]] - X[F[:, 0]]), axis=1)


SHAPES = {  # w(x, y) and its curvatures (w_xx, w_yy, w_xy)
    "cylinder": (lambda x, y: 0.5 * x**2, (1.0, 0.0, 0.0)),
    "saddle": (lambda x, y: x * y, (0.0, 0.0, 1.0)),
    "dome": (lambda x, y: 0.5 * (x**2 + y**2), (1.0, 1.0, 0.0)),
}


@pytest.mark.parametrize("jitter", [0.0, 0.3])
@pytest.mark.parametrize("shape", sorted(SHAPES))
def test_quadratic_shapes_have_the_plates_bending_energy(shape, jitter):
    """A flat sheet bent into a quadratic shape w = a f(x, y) of small slope: each triangle away
    from the boundary (a node across each edge) holds Kirchhoff's bending energy A D/2 ((1 − ν)
    κ:κ + ν tr(κ)²), κ = a ∇∇f, on a regular and an irregular mesh. 1e-8: the shape's curvature is
    ∇∇w / √(1 + |∇w|²), and the slopes here are below 1e-4 (the rest is round-off)."""
    mat = pl.StVKMembrane(E=1e6, nu=0.3, thickness=1e-3, density=1000.0, bending=True)
    X, F = _sheet(16, 16, 0.1, 0.1, jitter)
    f, (kxx, kyy, kxy) = SHAPES[shape]
    a = 1e-3
    u = np.zeros_like(X)
    u[:, 2] = a * f(X[:, 0] - 0.05, X[:, 1] - 0.05)
    with_bending, without = _energies(X, F, mat, u)
    inside = (across_edges(F) >= 0).all(axis=1)
    D, nu = mat.bending_stiffness, mat.bending_nu
    k = a * np.array([[kxx, kxy], [kxy, kyy]])
    density = 0.5 * D * ((1 - nu) * np.sum(k * k) + nu * np.trace(k) ** 2)
    got = (with_bending - without)[inside]
    np.testing.assert_allclose(got, density * _areas(X, F)[inside], rtol=1e-8)


@pytest.mark.parametrize("jitter", [0.0, 0.25])
def test_a_constant_moment_gives_no_force_inside_the_sheet(jitter):
    """The patch test: a sheet bent into w = a (x²/2 + 0.3 x y + 0.2 y²) carries one constant
    moment, which nodes three or more cells from its edge do not feel (their forces are round-off,
    1e-9 of the edge nodes'), on a regular and an irregular mesh."""
    mat = pl.StVKMembrane(E=1e6, nu=0.3, thickness=1e-3, density=1000.0, bending=True)
    X, F = _sheet(20, 20, 0.1, 0.1, jitter)
    model = _model(X, F, mat)
    s = model.state()
    x, y = X[:, 0] - 0.05, X[:, 1] - 0.05
    u = np.zeros_like(X)
    u[:, 2] = 1e-6 * (0.5 * x**2 + 0.3 * x * y + 0.2 * y**2)
    s.set_displacements(u)
    fz = model.internal_forces(s)[:, 2]
    deep = (np.abs(x) < 0.05 - 0.0151) & (np.abs(y) < 0.05 - 0.0151)
    assert np.abs(fz[deep]).max() < 1e-9 * np.abs(fz[~deep]).max()


def test_bending_forces_are_the_gradient_of_the_bending_energy():
    """Internal forces at a large random deformation of an irregular sheet with free and clamped
    edges equal the central differences of its total strain energy (h = 1e-7 m: truncation and
    round-off near 1e-9 of the largest force; tolerance 1e-7)."""
    mat = pl.StVKMembrane(E=1e6, nu=0.3, thickness=5e-3, density=1000.0, bending=2e6, bending_nu=0.2)
    X, F = _sheet(4, 4, 0.1, 0.1, 0.3)
    left = np.flatnonzero(np.isclose(X[:, 0], 0.0))
    model = _model(X, F, mat, fixed=left)
    s = model.state()
    u = 0.01 * np.random.default_rng(3).normal(size=X.shape)
    u[left] = 0.0
    s.set_displacements(u)
    f = model.internal_forces(s)

    def energy(v):
        s.set_displacements(v)
        return model.membrane_results(s)["energy"].sum()

    h = 1e-7
    fd = np.zeros_like(u)
    for n in np.setdiff1d(np.arange(len(X)), left):
        for d in range(3):
            e = np.zeros_like(u)
            e[n, d] = h
            fd[n, d] = (energy(u + e) - energy(u - e)) / (2 * h)
    free = np.setdiff1d(np.arange(len(X)), left)
    assert np.abs(f[free] - fd[free]).max() < 1e-7 * np.abs(f[free]).max()


def test_a_rigid_motion_of_a_curved_sheet_costs_nothing(backend):
    """A sheet whose reference shape is a dome, rotated and moved as a whole: no energy (1e-12 of
    a 1 % bend's) and forces at round-off: below 1e-9 of its bending force scale D / l (measured
    4e-11 of it: each curvature is a least-squares fit over an edge's stencil, whose coefficients
    carry double's round-off)."""
    mat = pl.StVKMembrane(E=1e6, nu=0.3, thickness=5e-3, density=1000.0, bending=True)
    X, F = _sheet(6, 6, 0.1, 0.1, 0.3)
    X[:, 2] = 2.0 * ((X[:, 0] - 0.05) ** 2 + (X[:, 1] - 0.05) ** 2)
    model = _model(X, F, mat, backend=backend)
    s = model.state()
    a, b = 0.7, 1.1
    Rz = np.array([[math.cos(a), -math.sin(a), 0], [math.sin(a), math.cos(a), 0], [0, 0, 1]])
    Rx = np.array([[1, 0, 0], [0, math.cos(b), -math.sin(b)], [0, math.sin(b), math.cos(b)]])
    s.set_displacements(X @ (Rz @ Rx).T + 0.3 - X)
    rigid = np.abs(model.internal_forces(s)).max()
    energy = model.membrane_results(s)["energy"].sum()
    bend = np.zeros_like(X)
    bend[:, 2] = 0.01 * (X[:, 0] - 0.05) ** 2 / 0.1
    s.set_displacements(bend)
    assert rigid < 1e-9 * mat.bending_stiffness / model.min_altitude
    assert abs(energy) < 1e-12 * model.membrane_results(s)["energy"].sum()


L, W, H, E = 0.1, 0.02, 1e-3, 1e6  # the cantilever strip [m], [Pa]


def _tip_line_load(X, total):
    """Forces [N] (N,) on the strip's tip nodes (x = L): ``total`` spread along the tip's width
    as a uniform line load (trapezoid weights)."""
    tip = np.flatnonzero(np.isclose(X[:, 0], L))
    order = tip[np.argsort(X[tip, 1])]
    w = np.zeros(len(X))
    gaps = np.diff(X[order, 1])
    np.add.at(w, order[:-1], gaps / 2)
    np.add.at(w, order[1:], gaps / 2)
    return total * w / W


def _strip(nx, ny, jitter=0.0, backend="cpu", P=0.0, E_m=E):
    """The strip's model (ν = 0: a beam; in-plane modulus ``E_m`` [Pa], bending modulus E) with a
    tip load P [N] (``_tip_line_load``), its root (x = 0) held and so clamped; its nodes X and root."""
    X, F = _sheet(nx, ny, L, W, jitter)
    b = pl.ModelBuilder()
    b.add_mesh(X, np.zeros((0, 4), int))
    b.add_membrane(F, pl.StVKMembrane(E=E_m, nu=0.0, thickness=H, density=1000.0, bending=E))
    root = np.flatnonzero(np.isclose(X[:, 0], 0.0))
    b.fix(root)
    f = _tip_line_load(X, P)
    for n in np.flatnonzero(f):
        b.add_force([int(n)], [0.0, 0.0, float(f[n])])
    return b.finalize("float64", backend=backend), X, root


def _linear_tip_deflection(nx, ny, jitter, P):
    """The strip's tip deflection [m] under a tip load P [N], from the linear system of its
    out-of-plane stiffness (linear_solve, in-plane motion held: at small deflection the in-plane
    and out-of-plane motions decouple, and the membrane's force, cubic in the deflection and 1e5
    times stiffer than the bending, stays at 1e-8 of it)."""
    X, F = _sheet(nx, ny, L, W, jitter)
    held = np.zeros(X.shape, bool)
    held[:, :2] = True
    held[np.isclose(X[:, 0], 0.0)] = True
    forces = np.zeros(X.shape)
    forces[:, 2] = _tip_line_load(X, P)
    mat = pl.StVKMembrane(E=E, nu=0.0, thickness=H, density=1000.0, bending=True)
    return linear_solve(X, F, mat, held, forces)[np.isclose(X[:, 0], L), 2].mean()


def linear_solve(X, F, material, held, forces, h=1e-9):
    """Displacements [m] (N, 3) of a sheet (nodes X (N, 3) [m], triangles F (K, 3)) under nodal
    forces [N] (N, 3), its DOFs held where ``held`` (N, 3) is True, from the linear system of its
    stiffness at the reference shape: central differences of the internal forces over h [m],
    perturbing at once the nodes that no node's forces couple (a greedy colouring of the square of
    the graph of nodes sharing a membrane's patch, membrane.hpp's kMembraneSlots), so that each
    response belongs to one perturbed node."""
    N = len(X)
    b = pl.ModelBuilder()
    b.add_mesh(X, np.zeros((0, 4), int))
    b.add_membrane(F, material)
    for d, name in enumerate("xyz"):
        if held[:, d].any():
            b.fix(np.flatnonzero(held[:, d]), name)
    model = b.finalize("float64")
    patch = np.c_[F, patch_nodes(F, across_edges(F))]
    pairs = [(patch[:, i], patch[:, j]) for i in range(12) for j in range(12)]
    rows = np.concatenate([p[(p >= 0) & (q >= 0)] for p, q in pairs])
    cols = np.concatenate([q[(p >= 0) & (q >= 0)] for p, q in pairs])
    couple = sp.csr_matrix((np.ones(len(rows)), (rows, cols)), shape=(N, N))
    near = (couple @ couple).tocsr()
    colour = np.full(N, -1)
    for i in range(N):
        taken = set(colour[near.indices[near.indptr[i] : near.indptr[i + 1]]].tolist())
        colour[i] = next(c for c in range(N) if c not in taken)
    free = np.flatnonzero(~held.ravel())
    dof = np.full(3 * N, -1)
    dof[free] = np.arange(len(free))
    s = model.state()
    R, C, V = [], [], []
    for c in range(colour.max() + 1):
        nodes = np.flatnonzero(colour == c)
        owner = np.full(N, -1)
        for i in nodes:
            owner[couple.indices[couple.indptr[i] : couple.indptr[i + 1]]] = i
        j = np.flatnonzero(owner >= 0)
        for d in range(3):
            r = np.zeros((N, 3))
            for sign in (1.0, -1.0):
                u = np.zeros((N, 3))
                u[nodes, d] = sign * h
                s.set_displacements(u)
                r += sign * model.internal_forces(s) / (2 * h)
            for e in range(3):
                rr, cc = dof[3 * j + e], dof[3 * owner[j] + d]
                ok = (rr >= 0) & (cc >= 0)
                R.append(rr[ok]), C.append(cc[ok]), V.append(r[j[ok], e])
    n = len(free)
    K = sp.csc_matrix((np.concatenate(V), (np.concatenate(R), np.concatenate(C))), shape=(n, n))
    u = np.zeros(3 * N)
    u[free] = spl.spsolve(K, forces.ravel()[free])
    return u.reshape(N, 3)


def test_a_cantilever_strip_bends_as_euler_bernoulli(backend):
    """A clamped strip (10 × 2 cm, 1 mm thick, ν = 0) under a tip load, relaxed to equilibrium: its
    tip deflects P L³ / (3 E I), I = W h³/12, to 0.5 % (the 20 × 4 mesh's error, measured 0.2 %
    (docs/engine.md, "Bending"); the deflection is 2 % of L, so the large-deflection correction is
    below 1e-4)."""
    P = 1e-5
    model, X, _ = _strip(20, 4, backend=backend, P=P)
    s = model.state()
    pl.Solver(model).relax(s, tol=1e-9, max_steps=400_000)
    tip = s.displacements[np.isclose(X[:, 0], L), 2].mean()
    exact = P * L**3 / (3 * E * W * H**3 / 12)
    assert tip == pytest.approx(exact, rel=5e-3)


def test_a_batch_of_strips_bends_as_each_alone():
    """Two bodies in one Batch (pliant.tled.batch; a batch needs tets: each body a fixed 1 cm cube
    of 6 tets beside the cantilever strip), the second's clamp listed by add_membrane's
    ``clamped``: each strip relaxes to the strip's deflection alone (1e-9 of it: the same forces,
    summed in another order)."""
    from pliant.mesh import grid_tets
    from pliant.tled.batch import Batch

    P = 1e-5
    alone, X, root = _strip(10, 2, P=P)
    s = alone.state()
    pl.Solver(alone).relax(s, tol=1e-10, max_steps=200_000)
    bodies = []
    for clamped in (None, root):
        Xc, Tc = grid_tets(*[np.linspace(0.0, 0.01, 2)] * 3)
        Xc = Xc - [0.02, 0.0, 0.0]
        b = pl.ModelBuilder()
        b.add_mesh(Xc, Tc)
        b.set_material(pl.NeoHookean(E=1e4, nu=0.3), density=1000.0)
        b.fix(np.arange(len(Xc)))
        Xs, F = _sheet(10, 2, L, W)
        b.add_mesh(Xs, np.zeros((0, 4), int))
        n0 = len(Xc)
        mat = pl.StVKMembrane(E=E, nu=0.0, thickness=H, density=1000.0, bending=True)
        b.add_membrane(F + n0, mat, clamped=None if clamped is None else clamped + n0)
        b.fix(root + n0)
        f = _tip_line_load(Xs, P)
        for n in np.flatnonzero(f):
            b.add_force([int(n + n0)], [0.0, 0.0, float(f[n])])
        bodies.append(b)
    batch = Batch(bodies, dtype="float64")
    sb = batch.model.state()
    pl.Solver(batch.model).relax(sb, tol=1e-10, max_steps=200_000)
    both = batch.stack(sb.displacements)
    scale = np.abs(s.displacements).max()
    for k in range(2):
        np.testing.assert_allclose(both[k][len(Xc) :], s.displacements, atol=1e-9 * scale)


def test_the_cantilever_converges_at_second_order():
    """The strip's tip deflection on 10 × 2, 20 × 4 and 40 × 8 regular meshes: errors against
    Euler–Bernoulli fall at an observed order between 1.5 and 2.5 (second order expected of a
    curvature exact for quadratics); on irregular meshes (a quarter cell of jitter) the finest is
    within 0.3 % (measured 0.11 %)."""
    P = 1e-5
    exact = P * L**3 / (3 * E * W * H**3 / 12)
    err = [abs(_linear_tip_deflection(n, n // 5, 0.0, P) / exact - 1) for n in (10, 20, 40)]
    orders = np.log2(np.array(err[:-1]) / np.array(err[1:]))
    assert np.all((orders > 1.5) & (orders < 2.5)), (err, orders)
    assert abs(_linear_tip_deflection(40, 8, 0.25, P) / exact - 1) < 3e-3


def test_a_cantilever_strip_vibrates_at_its_first_bending_frequency(backend):
    """The clamped strip (20 × 4 regular mesh), released from the Euler–Bernoulli static shape
    without damping and stepped at the default step, vibrates at f1 = 1.8751² / (2π L²)
    √(E h² / (12 ρ)): the period between its tip's zero crossings over three cycles agrees to 1 %
    (measured −0.49 %, the discretization's: −1.08 % on 10 × 2 cells, −0.17 % on 40 × 8; the
    static shape's little energy in higher modes averages out at the crossings)."""
    model, X, root = _strip(20, 4, backend=backend)
    s = model.state()
    x = X[:, 0]
    u = np.zeros_like(X)
    u[:, 2] = 1e-4 * x**2 * (3 * L - x) / (2 * L**3)
    s.set_displacements(u)
    solver = pl.Solver(model)
    f1 = 1.875104**2 / (2 * math.pi * L**2) * math.sqrt(E * H**2 / (12 * 1000.0))
    tip = np.isclose(x, L)
    chunk = max(1, int(round(0.01 / f1 / solver.dt)))  # 100 samples a period
    t, w = [0.0], [s.displacements[tip, 2].mean()]
    while t[-1] < 3.3 / f1:
        solver.run(s, steps=chunk)
        t.append(s.time)
        w.append(s.displacements[tip, 2].mean())
    t, w = np.array(t), np.array(w)
    k = np.flatnonzero(np.sign(w[1:]) != np.sign(w[:-1]))
    crossings = t[k] - w[k] * (t[k + 1] - t[k]) / (w[k + 1] - w[k])  # linear interpolation
    period = 2 * (crossings[-1] - crossings[0]) / (len(crossings) - 1)
    assert 1.0 / period == pytest.approx(f1, rel=1e-2)


def _navier_center(nu):
    """w_max D / (q a⁴) of a simply supported square plate under uniform pressure (Navier's double
    sine series, Timoshenko & Woinowsky-Krieger §30, summed to 1e-12)."""
    m = np.arange(1, 400, 2)
    M, N = np.meshgrid(m, m)
    sign = (-1.0) ** ((M + N) // 2 - 1)
    return float(16 / math.pi**6 * np.sum(sign / (M * N * (M**2 + N**2) ** 2)))


def _plate_center(n, jitter, clamped):
    """w_max D / (q a⁴) of a square plate (a = 10 cm, h = 1 mm, ν = 0.3) of n × n cells under a
    uniform pressure (lumped at the nodes), its edge held in all directions (clamped) or only in
    z (simply supported: a boundary edge turns freely); the linear system as _linear_tip_deflection."""
    a, nu, q = 0.1, 0.3, 1.0
    X, F = _sheet(n, n, a, a, jitter)
    mat = pl.StVKMembrane(E=E, nu=nu, thickness=H, density=1000.0, bending=True)
    edge = np.flatnonzero(np.isclose(X[:, 0] % a, 0.0) | np.isclose(X[:, 1] % a, 0.0))
    held = np.zeros(X.shape, bool)
    held[:, :2] = True  # in-plane motion decouples at small deflection (_linear_tip_deflection)
    held[edge, 2] = True
    if not clamped:  # an edge held in all three directions is clamped (add_membrane)
        held[edge, :2] = False
    forces = np.zeros(X.shape)
    np.add.at(forces[:, 2], F.ravel(), np.repeat(_areas(X, F) * q / 3, 3))
    w = linear_solve(X, F, mat, held, forces)[:, 2]
    center = np.argmin(np.linalg.norm(X[:, :2] - a / 2, axis=1))
    return w[center] * mat.bending_stiffness / (q * a**4)


@pytest.mark.parametrize("clamped", [False, True])
def test_square_plates_under_pressure_converge_to_kirchhoffs(clamped):
    """The centre deflection of a square plate under uniform pressure on 8, 16 and 32 cells a side:
    simply supported (an irregular mesh) against Navier's series (0.0040624 q a⁴ / D at ν = 0.3),
    clamped (a regular mesh) against 0.00126532 q a⁴ / D (Taylor & Govindjee 2004, Commun. Numer.
    Meth. Engng 20:757; Timoshenko & Woinowsky-Krieger's Table 35 gives 0.00126). Errors fall at an
    observed order above 1.5 (measured 1.8–2.0) to within 1 % and 3 % on 32 cells (measured 0.6 %
    and 2.1 %);
    the simply supported plate on a regular 32-cell mesh within 3 % (measured 2.1 %: Delaunay's
    diagonals on a square grid follow no pattern, 0.9–2.6 % from 16 to 48 cells)."""
    ref = 0.00126532 if clamped else _navier_center(0.3)
    err = [abs(_plate_center(n, 0.0 if clamped else 0.25, clamped) / ref - 1) for n in (8, 16, 32)]
    orders = np.log2(np.array(err[:-1]) / np.array(err[1:]))
    assert np.all(orders > 1.5), (err, orders)
    assert err[-1] < (3e-2 if clamped else 1e-2), err
    if not clamped:
        assert abs(_plate_center(32, 0.0, False) / ref - 1) < 3e-2


@pytest.mark.parametrize("thickness", [1e-4, 2e-3, 2e-2])
def test_the_critical_step_stays_below_the_stable_step(thickness):
    """A sheet's critical step (the membranes' own estimates, bending added as ω = 4 √(D / ρh) /
    alt²) lies below the Lanczos stable step 2 / ω_max of its assembled forces, within a factor of
    two, from membranes 1/170 of their cells thick (in-plane waves set it) to ones 2.4 times
    thicker (bending sets it), on an irregular mesh."""
    X, F = _sheet(12, 12, 0.1, 0.1, 0.25)
    mat = pl.StVKMembrane(E=1e6, nu=0.3, thickness=thickness, density=1000.0, bending=True)
    model = _model(X, F, mat)
    assert 0.5 * model.stable_step() < model.dt_critical <= model.stable_step()


def _niftysim_strip(tmp_path, clamped: bool, E_m: float = 1e6, P: float = 1e-5, damping: float = 0.0) -> Path:
    """A NiftySim model of the strip (10 × 2 cells, 1 mm LinearShell, E = ``E_m`` [Pa], ν = 0, its
    bending E_b = 2 MPa, ν_b = 0), its root fixed and listed as <ClampedNodes> (or not), a load P [N]
    at its tip in z, mass damping ``damping`` [1/s]."""
    X, F = _sheet(10, 2, L, W)
    root = np.flatnonzero(np.isclose(X[:, 0], 0.0))
    f = _tip_line_load(X, P)
    tip = np.flatnonzero(f)
    nodes = "\n".join(" ".join(f"{v:.17g}" for v in x) for x in X)
    tris = "\n".join(" ".join(str(v) for v in t) for t in F)
    held, loaded = " ".join(map(str, root)), " ".join(map(str, tip))
    forces = " ".join(f"{v:.17g}" for v in f[tip])
    clamp = f"<ClampedNodes>{held}</ClampedNodes>" if clamped else ""
    xml = f"""<Model>
  <Nodes NumNodes="{len(X)}" DOF="3">{nodes}</Nodes>
  <Elements NumEls="0" Type="T4" />
  <ShellElements NumEls="{len(F)}" Type="T3">{tris}</ShellElements>
  <ShellElementSet Size="all">
    <Material Type="LinearShell">{E_m:g} 0 2e6 0<Density>1000</Density><Thickness>1e-3</Thickness></Material>
    {clamp}
  </ShellElementSet>
  <Constraint DOF="all" Type="Fix" NumNodes="{len(root)}"><Nodes>{held}</Nodes></Constraint>
  <Constraint DOF="2" Type="Force" NumNodes="{len(tip)}" LoadShape="STEP">
    <Nodes>{loaded}</Nodes><Magnitudes Type="DIFFORM">{forces}</Magnitudes>
  </Constraint>
  <SystemParams><TimeStep>1e-5</TimeStep><TotalTime>1</TotalTime><DampingCoeff>{damping:g}</DampingCoeff>
    <Density>1000</Density></SystemParams>
</Model>"""
    p = tmp_path / ("clamped.xml" if clamped else "hinged.xml")
    p.write_text(xml)
    return p


def test_niftysims_linear_shell_bends_with_its_own_modulus_and_clamps(tmp_path):
    """NiftySim's LinearShell (E ν E_b ν_b) bends with E_b, ν_b, and <ClampedNodes> clamps the
    boundary edges between its nodes: the strip's tip deflects P L³ / (3 E_b I) (to 2 %, the 10 × 2
    mesh's error, measured 0.8 %); without <ClampedNodes> its fixed root only hinges (NiftySim
    clamps no edge it is not told to) and the strip, held at three collinear nodes, has no
    stiffness to turn about them: it swings down (measured 100 times the clamped deflection when
    the relaxation stops)."""
    from pliant.io.niftysim import load_niftysim

    deflections = {}
    for clamped in (True, False):
        sc = load_niftysim(_niftysim_strip(tmp_path, clamped))
        model = sc.builder.finalize("float64")
        s = model.state()
        pl.Solver(model).relax(s, tol=1e-9, max_steps=200_000, strict=False)
        X = model.reference_positions
        deflections[clamped] = s.displacements[np.isclose(X[:, 0], L), 2].mean()
    exact = 1e-5 * L**3 / (3 * 2e6 * W * H**3 / 12)
    assert deflections[True] == pytest.approx(exact, rel=2e-2)
    assert deflections[False] > 10 * deflections[True]


def test_a_sheet_that_only_bends_deflects_as_the_beam_at_small_slopes(tmp_path):
    """NiftySim's LinearShell "0 0 E_b ν_b" (in-plane E = 0: a sheet that only bends) runs. At a
    small tip load (α = P L² / (E_b I) = 3e-4) its strip, damped near critically for its first
    mode (ω1 = 3.516 √(E_b I / (ρ A)) / L² = 4.5 rad/s, α = 9/s) for 10 s, deflects P L³ / (3 E_b I)
    (to 2 %, the 10 × 2 mesh's error with stretching, measured 0.8 %; nothing holds the sheet in its
    plane, and its in-plane drift, second order in the slope, adds about 2 % at α = 0.01 and 0.02 %
    at 1e-3, measured on 20 × 4). Relaxing it cannot converge (no unique rest shape in its plane),
    and the error says why, naming a loose node."""
    from pliant.io.niftysim import load_niftysim

    P = 1e-7
    sc = load_niftysim(_niftysim_strip(tmp_path, True, E_m=0.0, P=P, damping=9.0))
    assert any("only bends" in w for w in sc.warnings)
    model = sc.builder.finalize("float64")
    s = model.state()
    solver = pl.Solver(model)
    solver.run(s, steps=round(10.0 / solver.dt))
    X = model.reference_positions
    exact = P * L**3 / (3 * 2e6 * W * H**3 / 12)
    assert s.displacements[np.isclose(X[:, 0], L), 2].mean() == pytest.approx(exact, rel=2e-2)
    with pytest.raises(pl.ConvergenceError, match="lies on a sheet that only bends"):
        pl.Solver(model).relax(model.state(), tol=1e-9, max_steps=20_000)


def test_a_sheet_that_only_bends_folds_up_under_large_slopes_and_says_why():
    """The strip of 20 × 4 cells that only bends, its tip loaded at α = 1 (a slope of about 0.5)
    without damping: nothing holds it in its plane, it shrinks there and folds up (measured: at
    0.35 s; at α = 0.1 at 1.4 s), and the instability's error names a node nothing holds; the same
    strip with E = E_b sways and stays below its elastica's tip deflection (0.30 L at α = 1) twice
    over (its dynamic overshoot of a suddenly applied load)."""
    P = E * W * H**3 / 12 / L**2
    model, X, _ = _strip(20, 4, P=P, E_m=0.0)
    with pytest.raises(pl.InstabilityError, match="node [0-9]+ lies on a sheet that only bends"):
        pl.Solver(model).run(model.state(), until=1.0)
    model = _strip(20, 4, P=P)[0]
    s = model.state()
    pl.Solver(model).run(s, until=1.0)
    assert np.abs(s.displacements).max() < 2 * 0.30 * L


def test_a_sheet_that_only_bends_is_at_rest_unloaded_and_needs_bending_without_stretching():
    """NiftySim's membrane_static_shell_1x1.xml (two LinearShell triangles "0 0 5000 0.3", no load,
    no tets) stays exactly at rest (a sheet at its reference shape carries no force); an in-plane
    modulus 0 without a bending modulus is refused, naming the material."""
    X = np.array([[0.0, 0, 0], [0, 1, 0], [1, 0, 0], [1, 1, 0]])
    mat = pl.StVKMembrane(E=0.0, nu=0.0, thickness=1.0, density=10.0, bending=5000.0, bending_nu=0.3)
    b = pl.ModelBuilder()
    b.add_mesh(X, np.zeros((0, 4), int))
    b.add_membrane([[0, 2, 1], [2, 3, 1]], mat)
    model = b.finalize("float64")
    s = model.state()
    pl.Solver(model).run(s, steps=100)
    assert not np.any(s.displacements)
    for cls, kwargs in ((pl.StVKMembrane, dict(E=0.0, nu=0.3)), (pl.NeoHookeanMembrane, dict(mu=0.0))):
        with pytest.raises(pl.MaterialError, match="= 0; expected .* or 0 with a bending modulus"):
            cls(**kwargs, thickness=1.0, density=10.0, bending=True)


PLATE = """
title = "a plastic strip cantilevered under its own weight"
[[sheet]]
name = "strip"
primitive = "rectangle"
size = [0.1, 0.02]
cells = [20, 4]
translate = [0.05, 0.01, 0.0]   # x from 0 to 0.1 m
type = "st-venant-kirchhoff"
E = 1e9
nu = 0.0
thickness = 1e-3
density = 1000.0
bending = true
[[constraint]]
type = "fix"
nodes = { box = [[-0.001, -1, -1], [0.001, 1, 1]] }
[[load]]
type = "gravity"
g = [0.0, 0.0, -9.81]
[solver]
static = true
dtype = "float64"
"""


def test_a_scenes_sheet_that_bends_sags_as_a_cantilever(tmp_path, pliant_cli):
    """End to end: a [[sheet]] with ``bending = true`` (a 10 × 2 cm plastic strip, 1 mm, E = 1 GPa,
    ν = 0), its edge x = 0 fixed (and so clamped), under its own weight, relaxed by `pliant run`:
    its tip sags q L⁴ / (8 E I), q = ρ g h W, to 1 % (the 20 × 4 mesh's error, measured 0.3 %; the
    sag is 1.5 % of L). Without ``bending`` the same scene is a membrane hanging from one edge."""
    import meshio

    (tmp_path / "plate.toml").write_text(PLATE)
    r = pliant_cli("run", tmp_path / "plate.toml", "-o", tmp_path / "out", "--no-progress")
    assert r.returncode == 0, r.stdout + r.stderr
    m = meshio.read(tmp_path / "out" / "frame_00001.vtu")
    X, u = m.points, m.point_data["displacement"]
    tip = np.isclose(X[:, 0], L)
    exact = 1000.0 * 9.81 * H * W * L**4 / (8 * 1e9 * W * H**3 / 12)
    assert -u[tip, 2].mean() == pytest.approx(exact, rel=1e-2)


def test_a_static_scene_that_stops_short_exits_1_after_writing_its_files(tmp_path, pliant_cli):
    """The scene's strip made a sheet that only bends (E = 0, bending = 1 GPa): relaxed, it has no
    unique rest shape in its plane, so `pliant run` stops short of its tolerance: exit 1 with the
    relaxation's error (naming a node nothing holds in its plane, and where the results are), no
    traceback, every file written and summary.json saying ``converged: false``."""
    (tmp_path / "only.toml").write_text(
        PLATE.replace("E = 1e9", "E = 0.0").replace("bending = true", "bending = 1e9")
    )
    out = tmp_path / "out"
    r = pliant_cli("run", tmp_path / "only.toml", "-o", out, "--no-progress")
    assert r.returncode == 1 and "Traceback" not in r.stderr, r.stdout + r.stderr
    assert "lies on a sheet that only bends" in r.stderr and str(out) in r.stderr, r.stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["converged"] is False and summary["error"]
    assert {"result.pvd", "frame_00001.vtu", "result.png"} <= {p.name for p in out.iterdir()}


def test_a_scenes_bending_keys_are_checked(tmp_path, pliant_cli):
    """``bending_nu`` without ``bending``, and a ``bending`` that is neither true, false nor a
    modulus, are refused naming the key (exit 2, no traceback)."""
    for new in ("bending_nu = 0.3", 'bending = "yes"', "bending = -5.0"):
        old = "bending = true"
        (tmp_path / "bad.toml").write_text(PLATE.replace(old, new))
        r = pliant_cli("run", tmp_path / "bad.toml", "-o", tmp_path / "bad", "--no-progress")
        assert r.returncode == 2 and "Traceback" not in r.stderr, r.stderr
        assert "bending" in r.stderr, r.stderr


@pytest.mark.parametrize("bending", [True, False])
def test_a_sheets_jump_says_what_to_try(bending):
    """A sheet that carries compression and jumps (here stepped at 1.6 times its stable step,
    allow_unstable) is told what to try: a bending one to wrinkle or halve dt (a bending drape
    over a ball snaps element by element at the automatic step: docs/engine.md, "Bending"), a
    plain one to wrinkle; with ``wrinkling`` the hint is not given."""
    X, F = _sheet(10, 10, 0.1, 0.1, 0.2)
    for wrinkling in (False, True):
        b = pl.ModelBuilder()
        b.add_mesh(X, np.zeros((0, 4), int))
        mat = pl.StVKMembrane(
            E=1e6, nu=0.3, thickness=1e-3, density=1000.0, bending=bending, wrinkling=wrinkling
        )
        b.add_membrane(F, mat)
        b.fix(np.flatnonzero(X[:, 0] == 0))
        b.set_gravity()
        model = b.finalize("float64")
        sim = pl.Simulation(model, dt=1.6 * model.stable_step(), allow_unstable=True)
        with pytest.raises(pl.InstabilityError, match="unstable at") as err:
            sim.run(until=0.5)
        hint = "halve dt" if bending else "a free sheet should wrinkle"
        assert (hint in str(err.value)) != wrinkling, str(err.value)
