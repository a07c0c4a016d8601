"""The verification models: small bodies whose answers the closed forms of
:mod:`pliant.validate.references` give. Each returns what a check compares; used by
``pliant validate`` and by the test suite."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from .. import mesh
from ..tled import ModelBuilder, Ramp, Simulation, Solver, Table
from .references import lame_radial_displacement

__all__ = [
    "cube_with_symmetry_bcs",
    "twisted_cylinder",
    "tip_loaded_cantilever",
    "cantilever_tip_deflection",
    "sampled_displacement",
    "hollow_sphere",
    "lame_solve",
    "ringing_cantilever",
    "decay_of_first_mode",
    "free_block",
    "bend",
    "energy_history",
    "hertz_indentation",
    "paraboloid_block",
    "hertz_two_bodies",
    "energy_decay_rate",
    "wave_arrival",
    "bent_beam_tip",
]


def cube_with_symmetry_bcs(material, stretch, cells=3, jitter=0.25, dtype="float32", L=1.0):
    """Unstructured tet cube [0, L]³ under uniaxial stretch along x with symmetry planes x=0, y=0,
    z=0 and free lateral faces: the exact solution is homogeneous, so linear tets represent it.
    Returns (nodes [m] (N, 3), model, ids of the loaded face's nodes)."""
    X, T = mesh.box_tets((L, L, L), (cells,) * 3, jitter=jitter, seed=1)
    b = ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(material, density=1000.0)
    tol = 1e-9 * L
    b.fix(np.nonzero(X[:, 0] < tol)[0], "x")
    b.fix(np.nonzero(X[:, 1] < tol)[0], "y")
    b.fix(np.nonzero(X[:, 2] < tol)[0], "z")
    right = np.nonzero(X[:, 0] > L - tol)[0]
    b.prescribe(right, (stretch - 1.0) * L, "x", curve=Ramp(1.0))
    return X, b.finalize(dtype), right


def tip_loaded_cantilever(cells, material, P, L=1.0, H=0.1, nodal_pressure=False, smoothing="element"):
    """An L × H × H cantilever of (cells × n × n) cells, n = cells·H/L, clamped at x = 0, under a
    uniform transverse traction of resultant P [N] along −z on its tip face, ramped over 1 s
    (float64; ``smoothing``: ModelBuilder.strain_smoothing): (model, tip node ids)."""
    n = max(1, round(cells * H / L))
    X, T = mesh.box_tets((L, H, H), (cells, n, n))
    b = ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(material, density=1000.0)
    b.nodal_pressure = nodal_pressure
    b.strain_smoothing = smoothing
    b.fix(np.nonzero(X[:, 0] < 1e-9)[0])
    tip = np.nonzero(X[:, 0] > L - 1e-9)[0]
    w = np.ones(tip.size)  # trapezoid-rule nodal weights: the resultant is exactly P
    for d in (1, 2):
        w[(X[tip, d] < 1e-9) | (X[tip, d] > H - 1e-9)] *= 0.5
    b.add_force(tip, np.outer(-P * w / w.sum(), [0, 0, 1]), curve=Ramp(1.0))
    return b.finalize("float64"), tip


def cantilever_tip_deflection(n, material, nodal_pressure=False, L=1.0, H=0.1, P=1.0e-2, smoothing="element"):
    """Tip deflection [m] of an L × H × H cantilever (10n × n × n cells) clamped at x = 0 under a
    uniform shear traction of resultant P [N] on its tip face, quasi-static (float64)."""
    model, tip = tip_loaded_cantilever(10 * n, material, P, L, H, nodal_pressure, smoothing)
    sim = Simulation(model)
    sim.relax(tol=1e-9, max_steps=1_000_000)
    return -sim.displacements[tip, 2].mean()


def sampled_displacement(sim, nodes, axis, until, every):
    """Run ``sim`` to time ``until`` [s], sampling the mean displacement [m] of ``nodes`` along
    ``axis`` every ``every`` steps: (times [s], displacements [m])."""
    t, u = [], []
    while sim.time < until:
        sim.run(steps=every)
        t.append(sim.time)
        u.append(sim.displacements[nodes, axis].mean())
    return np.array(t), np.array(u)


def hollow_sphere(a=0.02, b=0.04, edge_length=0.006):
    """A hollow sphere (radii a < b [m]) meshed by fTetWild from an outer icosphere and an inner one
    reversed: (nodes [m], tets, inner boundary faces)."""
    import trimesh

    from ..mesh.topology import boundary_faces

    o = trimesh.creation.icosphere(subdivisions=4, radius=b)
    i = trimesh.creation.icosphere(subdivisions=3, radius=a)
    V = np.vstack([o.vertices, i.vertices])
    F = np.vstack([o.faces, i.faces[:, ::-1] + len(o.vertices)])
    X, T = mesh.tetrahedralize(V, F, edge_length=edge_length)
    faces, _ = boundary_faces(T)
    inner = faces[np.linalg.norm(X[faces].mean(axis=1), axis=1) < (a + b) / 2]
    return X, T, inner


def lame_solve(shell, nu, anp, gamma=0.0, a=0.02, b=0.04, E=3e3, p=30.0, smoothing="element"):
    """Lamé's sphere under internal pressure p [Pa], quasi-static (``smoothing``:
    ModelBuilder.strain_smoothing): (RMS error of u_r over the nodes relative to the largest exact
    u_r, element J − 1)."""
    from ..materials import NeoHookean

    X, T, inner = shell
    bl = ModelBuilder()
    bl.add_mesh(X, T)
    bl.set_material(NeoHookean(E=E, nu=nu), density=1000.0)
    bl.nodal_pressure, bl.nodal_pressure_stabilization = anp, gamma
    bl.strain_smoothing = smoothing
    near = [int(np.argmin(np.linalg.norm(X - c, axis=1))) for c in ((b, 0, 0), (0, b, 0), (0, 0, b))]
    bl.fix(near[:1], "yz")  # 3-2-1: rigid motion only, no stress
    bl.fix(near[1:2], "xz")
    bl.fix(near[2:], "x")
    bl.add_pressure(inner, p)
    sim = Simulation(bl.finalize("float64"))
    sim.relax(tol=1e-6)
    r = np.linalg.norm(X, axis=1)
    exact = lame_radial_displacement(r, a, b, p, E, nu)
    ur = np.einsum("ij,ij->i", sim.displacements, X / r[:, None])
    return np.sqrt(np.mean((ur - exact) ** 2)) / exact.max(), sim.element_results()["J"] - 1


def ringing_cantilever(alpha=0.0, beta=0.0):
    """A 10 × 2 × 1 cm Neo-Hookean cantilever (E = 1 MPa) clamped at x = 0, bent by a 2 mN tip
    load removed at t = 0⁺, with damping α [1/s] and β [s]: (model, tip node ids). Not square:
    the tets' split couples bending in y and z a little, and equal frequencies would beat."""
    from ..materials import NeoHookean

    X, T = mesh.box_tets((0.1, 0.02, 0.01), (20, 4, 2))
    b = ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(NeoHookean(E=1e6, nu=0.3), density=1000.0)
    b.fix(np.nonzero(X[:, 0] < 1e-9)[0])
    tip = np.nonzero(X[:, 0] > 0.1 - 1e-9)[0]
    b.add_force(tip, (0.0, 0.0, -2e-3 / len(tip)), curve=Table([0.0, 1e-9], [1.0, 0.0]))
    b.damping, b.stiffness_damping = alpha, beta
    return b.finalize("float64"), tip


def decay_of_first_mode(model, tip, duration=1.0):
    """Release the cantilever from its static deflection and follow its tip: (undamped natural
    frequency ω_n [rad/s], decay rate σ [1/s]). ω_d from the mean interval of upward zero crossings,
    σ from a log fit of the peaks after the first two periods (higher modes are gone by then),
    ω_n² = ω_d² + σ²."""
    sim = Simulation(model)
    sim.relax(at_time=0.0, tol=1e-10)
    t, z = sampled_displacement(sim, tip, 2, duration, 40)
    up = np.nonzero((z[:-1] < 0) & (z[1:] >= 0))[0]
    tc = t[up] - z[up] * (t[up + 1] - t[up]) / (z[up + 1] - z[up])
    Td = float(np.mean(np.diff(tc)))
    peaks = [k for k in range(1, len(z) - 1) if z[k] < z[k - 1] and z[k] <= z[k + 1] and t[k] > 2 * Td]
    if len(peaks) < 4:
        raise RuntimeError(f"only {len(peaks)} peaks after two periods in {duration} s")
    sigma = float(-np.polyfit(t[peaks], np.log(-z[peaks]), 1)[0])
    return math.sqrt((2 * math.pi / Td) ** 2 + sigma**2), sigma


def free_block(dtype="float64", damping=0.0, threads=None, cells=(6, 3, 3)):
    """A free 20 × 10 × 10 cm jittered Neo-Hookean block (E = 50 kPa, ν = 0.4), damping α [1/s]:
    (nodes [m], model)."""
    from ..materials import NeoHookean

    X, T = mesh.box_tets((0.2, 0.1, 0.1), cells, jitter=0.2, seed=5)
    b = ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(NeoHookean(E=5e4, nu=0.4), density=1000.0)
    b.damping = damping
    return X, b.finalize(dtype, threads=threads)


def bend(X):
    """A smooth initial displacement [m] of the free block (bending-like), exciting mainly low modes."""
    x = X[:, 0] / 0.2
    return np.stack([np.zeros_like(x), 0.01 * np.sin(np.pi * x), np.zeros_like(x)], axis=1)


def energy_history(sim, n_frames, steps_per_frame):
    """(times [s], total energies [J]) ½ v_nᵀ M v_n + U(u_n) with the centred velocity
    v_n = (u_{n+1} − u_{n−1})/2Δt, every ``steps_per_frame`` steps."""
    E, t = [], []
    model, s = sim.model, sim.state
    for _ in range(n_frames):
        sim.run(steps=steps_per_frame)
        nxt = model.state()
        sim.solver.step(s, nxt)
        u_prev = s.displacements - s.velocities * s.dt
        v = (nxt.displacements - u_prev) / (2 * s.dt)
        E.append(0.5 * np.sum(model.mass[:, None] * v * v) + model.strain_energy(s))
        t.append(sim.time)
    return np.array(t), np.array(E)


def hertz_indentation(depths, R=0.01, E=1e4, nu=0.3):
    """A rigid frictionless sphere (radius R [m]) pressed into a thick linear-elastic block, quarter
    model (symmetry planes x = 0, y = 0; roller at the bottom), float64, quasi-static at each depth
    δ of ``depths`` [m] (the sphere's keyframes are the load steps). Cells of R/100 over the contact
    zone growing by 1.3 per cell to a block of 8.3 R each way (196,608 tets).
    Returns (tool forces [N], support reactions [N], whole-model), and checks on the way that no
    node left its symmetry plane or entered the sphere (RuntimeError otherwise)."""
    from ..contact import Sphere
    from ..materials import LinearElastic

    xs = mesh.graded_coordinates(R / 100, 0.12 * R, 1.3, 8 * R)
    X, T = mesh.grid_tets(xs, xs, -xs[::-1])
    b = ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(LinearElastic(E=E, nu=nu), density=1000.0)
    b.fix(np.nonzero(X[:, 0] == 0.0)[0], "x")
    b.fix(np.nonzero(X[:, 1] == 0.0)[0], "y")
    bottom = np.nonzero(X[:, 2] == X[:, 2].min())[0]
    b.fix(bottom, "z")  # roller: closer to a half-space than clamped
    tool = Sphere(R)
    tool.at(0.0, (0.0, 0.0, R))  # touching the top face z = 0 at the origin
    for k, d in enumerate(depths):
        tool.at(k + 1.0, (0.0, 0.0, R - d))  # keyframe k + 1: depth δ_k
    b.add_tool(tool)
    sim = Simulation(b.finalize("float64"))
    forces, reactions = [], []
    for k in range(len(depths)):
        # tol: relative out-of-balance force; 1e-4 and 1e-6 gave the same force to 5 digits.
        sim.solver.relax(sim.state, at_time=k + 1.0, tol=1e-5)
        forces.append(4 * sim.contact_report().relaxed[0][0][2])  # quarter model → whole
        reactions.append(4 * sim.model.internal_forces(sim.state)[bottom, 2].sum())
        u = sim.displacements
        if not (np.all(u[X[:, 0] == 0.0, 0] == 0.0) and np.all(u[X[:, 1] == 0.0, 1] == 0.0)):
            raise RuntimeError("contact moved a node off its symmetry plane")
        c = sim.positions - np.array([0.0, 0.0, R - depths[k]])
        if np.linalg.norm(c, axis=1).min() < R - 1e-9:
            raise RuntimeError(f"a node is inside the sphere at depth {depths[k]:g} m")
    return np.array(forces), np.array(reactions)


def paraboloid_block(R, L, h, ratio=1.3, r1=None):
    """A quarter block [0, L']² × [−L', 0] [m] (L' ≥ L: the last graded cell is kept whole) whose
    top face is bent down into Hertz's profile of a sphere of radius R [m], the paraboloid
    z = −r²/(2R), out to r1 [m] (default 12 h), and its tangent cone beyond (so that the bend
    stays within the block); the bend fades linearly to nothing at the bottom z = −L'. Cells of
    h [m] over r < 12 h, growing by ``ratio`` beyond.
    Returns (nodes [m] (N, 3), tets (M, 4))."""
    r1 = 12 * h if r1 is None else r1
    xs = mesh.graded_coordinates(h, 12 * h, ratio, L)
    X, T = mesh.grid_tets(xs, xs, -xs[::-1])
    r = np.hypot(X[:, 0], X[:, 1])
    bend = np.where(r < r1, r**2 / (2 * R), r1**2 / (2 * R) + r1 / R * (r - r1))
    X[:, 2] -= bend * (1 + X[:, 2] / xs[-1])
    return X, T


def hertz_two_bodies(depths, R=0.02, E=1e4, nu=0.3, h=None, soft=True):
    """Two identical elastic paraboloids (radius R [m], linear elastic E [Pa], ν) pressed together
    frictionlessly, quarter models (symmetry planes x = 0, y = 0), quasi-static (dynamic
    relaxation) at each total approach δ of ``depths`` [m]: the lower body's bottom on rollers, the
    upper body (the lower one mirrored in z = 0) moved down by δ at its top. ``soft``: the two
    bodies in soft contact; otherwise the lower body alone against a rigid frictionless plane at
    z = −δ/2, which by symmetry is the same problem (the contact plane of two identical bodies stays
    flat and carries no shear). Cells of h [m] (default R/60) over the contact. Returns the contact
    force [N] at each δ (from the lower body's support reaction, whole model)."""
    from ..contact import Plane
    from ..contact.tools import quat_align_z
    from ..materials import LinearElastic

    L = 2 * R
    X, T = paraboloid_block(R, L, h or R / 60)
    b = ModelBuilder()
    b.add_mesh(X, T)
    Y = X
    if soft:
        b.add_mesh(X * (1, 1, -1), T[:, [0, 2, 1, 3]])  # mirrored: swapping two nodes keeps J > 0
        Y = np.vstack([X, X * (1, 1, -1)])
    b.set_material(LinearElastic(E=E, nu=nu), density=1000.0)
    b.fix(np.nonzero(Y[:, 0] == 0.0)[0], "x")
    b.fix(np.nonzero(Y[:, 1] == 0.0)[0], "y")
    bottom = np.nonzero(Y[:, 2] == Y[:, 2].min())[0]
    b.fix(bottom, "z")
    steps = Table([0.0] + [k + 1.0 for k in range(len(depths))], [0.0, *depths])
    if soft:
        top = np.nonzero(Y[:, 2] == Y[:, 2].max())[0]
        b.prescribe(top, -1.0, "z", curve=steps)
        b.set_soft_contact(friction=0.0)
    else:
        down = quat_align_z((0.0, 0.0, -1.0))  # the plane's solid side is above it
        plane = Plane((0.0, 0.0, 0.0), normal=(0.0, 0.0, -1.0))
        plane.at(0.0, (0.0, 0.0, 0.0), down)
        for k, d in enumerate(depths):
            plane.at(k + 1.0, (0.0, 0.0, -d / 2), down)
        b.add_tool(plane)
    sim = Simulation(b.finalize("float64"))
    forces = []
    for k in range(len(depths)):
        # tol 1e-4: the rigid indentation's force agrees to 5 digits between 1e-4 and 1e-6.
        sim.solver.relax(sim.state, at_time=k + 1.0, tol=1e-4)
        forces.append(4 * sim.model.internal_forces(sim.state)[bottom, 2].sum())
    return np.array(forces)


def energy_decay_rate(alpha: float) -> float:
    """The bent free block released with mass-proportional damping α [1/s]: its total energy's
    decay rate [1/s], a log-linear fit over 0.5 s (the energy falls by e^-10)."""
    X, model = free_block(damping=alpha)
    sim = Simulation(model)
    sim.state.set_displacements(bend(X))
    t, E = energy_history(sim, 100, 5)
    return float(-np.polyfit(t, np.log(E), 1)[0])


def wave_arrival(constrained=True, cells=100, L=1.0, E=1e5, nu=0.3, rho=1000.0, v0=1e-3, material="linear"):
    """A longitudinal wave along x in a body of length L [m] (``cells`` cells, 2 × 2 across) whose
    end x = 0 is pushed at the constant speed v0 [m/s] from t = 0: ``constrained``, a column with
    every node held laterally (uniaxial strain: the P wave, c_p); otherwise a free slender bar
    (width L/50: the bar wave, c_0 = √(E/ρ)). Before the reflection returns, the 1D solution at a
    section x is u = v0 (t − x/c) once the front has passed (d'Alembert). The displacement of the
    section x = L/2 is fitted by a line over t ∈ [0.7, 1.4] L/c (after the front, before the
    reflection from the far end at 1.5 L/c): (measured speed [m/s], x over the time where the
    line crosses zero; the line's slope [m/s], v0 exactly). ``material``: "linear" (small
    strain) or "neo-hookean"."""
    from ..materials import LinearElastic, NeoHookean
    from .references import p_wave_speed

    if cells < 2 or cells % 2:
        raise ValueError(f"wave_arrival: cells = {cells}; expected an even number (a section at L/2)")
    width = 2 * L / cells if constrained else L / 50
    X, T = mesh.box_tets((L, width, width), (cells, 2, 2))
    b = ModelBuilder()
    b.add_mesh(X, T)
    law = LinearElastic(E=E, nu=nu) if material == "linear" else NeoHookean(E=E, nu=nu)
    b.set_material(law, density=rho)
    if constrained:
        b.fix(np.arange(len(X)), "yz")
    c = p_wave_speed(E, nu, rho) if constrained else math.sqrt(E / rho)
    duration = 1.45 * L / c
    b.prescribe(np.nonzero(X[:, 0] < 1e-12)[0], v0 * duration, "x", curve=Ramp(duration))
    model = b.finalize("float64")
    probe = np.nonzero(np.abs(X[:, 0] - L / 2) < 1e-9)[0]
    t, u = sampled_displacement(Simulation(model), probe, 0, duration, 5)
    window = (t > 0.7 * L / c) & (t < 1.4 * L / c)
    slope, intercept = np.polyfit(t[window], u[window], 1)
    return float((L / 2) / (-intercept / slope)), float(slope)


def bent_beam_tip(alpha, n=4, slenderness=20, nodal_pressure=False, increments=10, smoothing="element"):
    """A slender cantilever (L = 1 m, square section L/slenderness, 20n × n × n cells, clamped at
    x = 0; Neo-Hookean, E = 1 MPa, ν = 0) bent by a dead load P = α EI/L² along −z on its tip
    face, relaxed in ``increments`` load steps (float64): (tip deflection / L, tip shortening / L)
    of the tip face's nodes, averaged."""
    from ..materials import NeoHookean

    L, E = 1.0, 1.0e6
    H = L / slenderness
    P = alpha * E * H**4 / 12 / L**2
    model, tip = tip_loaded_cantilever(20 * n, NeoHookean(E=E, nu=0.0), P, L, H, nodal_pressure, smoothing)
    sim = Simulation(model)
    sim.relax(at_time=1.0, tol=1e-8, increments=increments, max_steps=2_000_000)
    u = sim.displacements[tip]
    return float(-u[:, 2].mean() / L), float(-u[:, 0].mean() / L)


def sheared_unit_cube(X: np.ndarray, T: np.ndarray, gamma: float, mu: float):
    """Simple shear u = γ Y e_x prescribed on the boundary of a unit-cube mesh (nodes X [m], tets
    T), decoupled Neo-Hookean (μ [Pa], K = 50 μ), relaxed in float64: (model, simulation, the
    largest interior displacement error [m] from the affine field)."""
    from ..materials import NeoHookean

    u_exact = np.zeros_like(X)
    u_exact[:, 0] = gamma * X[:, 1]
    b = ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(NeoHookean(mu=mu, K=50 * mu), density=1000.0)
    boundary = np.nonzero(np.any((X < 1e-9) | (X > 1 - 1e-9), axis=1))[0]
    b.prescribe(boundary, u_exact[boundary], "xyz", curve=Ramp(1.0))
    model = b.finalize("float64")
    sim = Simulation(model)
    sim.relax(tol=1e-10, increments=2)
    inside = np.setdiff1d(np.arange(len(X)), boundary)
    return model, sim, float(np.abs(sim.displacements[inside] - u_exact[inside]).max())


# The NiftySim user guide's first model (§3.1): one H8 cube of 0.1 m, NH (μ = 1052, K = 52249 Pa),
# its x = 0.1 face pulled 0.03 m along x (POLY345 over 1 s) with x held at x = 0 and y, z held at
# every node; damping 5, density 1000, Δt = 0.01 s.
GUIDE_H8 = """<?xml version="1.0" encoding="utf-8"?>
<Model>
  <Nodes DOF="3" NumNodes="8">0 0 0 0.1 0 0 0.1 0.1 0 0 0.1 0 0 0 0.1 0.1 0 0.1 0.1 0.1 0.1 0 0.1 0.1</Nodes>
  <Elements NumEls="1" Type="H8">0 1 2 3 4 5 6 7</Elements>
  <ElementSet Size="1"><Material Type="NH"><ElasticParams NumParams="2">1052 52249</ElasticParams>
    </Material>0</ElementSet>
  <Constraint DOF="0" LoadShape="POLY345" NumNodes="4" Type="Disp"><Nodes>1 2 5 6</Nodes>
    <Magnitudes Type="UNIFORM">0.03</Magnitudes></Constraint>
  <Constraint DOF="0" NumNodes="4" Type="Fix"><Nodes>0 3 4 7</Nodes></Constraint>
  <Constraint DOF="1" NumNodes="8" Type="Fix"><Nodes>0 1 2 3 4 5 6 7</Nodes></Constraint>
  <Constraint DOF="2" NumNodes="8" Type="Fix"><Nodes>0 1 2 3 4 5 6 7</Nodes></Constraint>
  <SystemParams><TimeStep>0.01</TimeStep><TotalTime>1</TotalTime><DampingCoeff>5</DampingCoeff>
    <HGKappa>0.075</HGKappa><Density>1000</Density></SystemParams>
</Model>
"""


def guide_h8_stress() -> np.ndarray:
    """σ_xx [Pa] of each tet (6,) of GUIDE_H8 imported (split into tetrahedra) and run to its end."""
    import tempfile

    from ..io.niftysim import load_niftysim

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "guide_h8.xml"
        path.write_text(GUIDE_H8)
        scene = load_niftysim(path)
    model = scene.builder.finalize("float64")
    sim = Simulation(model, dt=scene.dt)
    sim.run(until=scene.duration)
    return model.element_results(sim.state)["cauchy"][:, 0]


def membrane_sheet(kind: str, stretch: float, n: int = 6) -> tuple[float, float]:
    """A 1 m square sheet of membrane triangles alone (n × n squares, each cut in two), in the plane
    z = 0: x = 0 on rollers, the edge x = 1 moved to ``stretch`` in ten increments, the sides free,
    held in its plane, relaxed (float64). ``kind``: "neo-hookean" (μ = 1 kPa) or
    "st-venant-kirchhoff" (E = 3 kPa, ν = 0.3), h = 1 mm. Returns the width's stretch (at the side
    y = 1, mean) and the pull on the moved edge [N]."""
    from .. import NeoHookeanMembrane, StVKMembrane
    from ..tled import ModelBuilder, Ramp

    xs = np.linspace(0.0, 1.0, n + 1)
    X = np.array([[x, y, 0.0] for x in xs for y in xs])
    node = lambda i, j: i * (n + 1) + j  # noqa: E731
    F = [
        tri
        for i in range(n)
        for j in range(n)
        for tri in (
            [node(i, j), node(i + 1, j), node(i + 1, j + 1)],
            [node(i, j), node(i + 1, j + 1), node(i, j + 1)],
        )
    ]
    material = (
        NeoHookeanMembrane(1e3, 1e-3, 1e3) if kind == "neo-hookean" else StVKMembrane(3e3, 0.3, 1e-3, 1e3)
    )
    b = ModelBuilder()
    b.add_mesh(X, np.zeros((0, 4), np.int64), source=f"membrane sheet ({kind})")
    b.add_membrane(np.array(F), material)
    left, right = np.nonzero(X[:, 0] == 0)[0], np.nonzero(X[:, 0] == 1)[0]
    b.fix(left, "x")
    b.fix([0], "y")
    b.fix(np.arange(len(X)), "z")
    b.prescribe(right, stretch - 1.0, "x", curve=Ramp(1.0))
    model = b.finalize("float64")
    sim = Simulation(model)
    sim.relax(tol=1e-10, increments=10)
    side = X[:, 1] == 1
    width = 1.0 + float(sim.displacements[side, 1].mean())
    return width, float(model.internal_forces(sim.state)[right, 0].sum())


def membrane_balloon(kind: str, pressure: float, subdivisions: int = 3) -> float:
    """A spherical balloon of membranes alone (an icosphere of radius 5 cm, its triangles wound
    outward; 642 nodes at 3 subdivisions), h = 1 mm, "neo-hookean" (μ = 10 kPa) or
    "st-venant-kirchhoff" (E = 30 kPa, ν = 0.3), inflated by an internal pressure [Pa] (a follower
    pressure against its outward normals) and relaxed. Returns its mean radius [m]."""
    import trimesh

    from .. import NeoHookeanMembrane, StVKMembrane

    ball = trimesh.creation.icosphere(subdivisions=subdivisions, radius=0.05)
    F = np.asarray(ball.faces, np.int64)
    material = (
        NeoHookeanMembrane(1e4, 1e-3, 1e3) if kind == "neo-hookean" else StVKMembrane(3e4, 0.3, 1e-3, 1e3)
    )
    b = ModelBuilder()
    b.add_mesh(np.asarray(ball.vertices), np.zeros((0, 4), np.int64), source=f"membrane balloon ({kind})")
    b.add_membrane(F, material)
    b.add_pressure(F, -pressure, orient=False)
    sim = Simulation(b.finalize("float64"))
    sim.relax(tol=1e-9, increments=4)
    x = sim.state.positions
    return float(np.linalg.norm(x - x.mean(axis=0), axis=1).mean())


def wrinkled_shear(gamma: float) -> float:
    """A sheet of membranes alone that wrinkles (plane-stress St Venant–Kirchhoff, E = 3 kPa,
    ν = 0.3, h = 1 mm) in simple shear x += γ y: the Cauchy shear resultant t_xy [N/m] of its
    membranes (their mean; homogeneous)."""
    from .. import StVKMembrane
    from ..scene.sheets import rectangle

    V, F = rectangle(1.0, 1.0, 4, 4)
    b = ModelBuilder()
    b.add_mesh(V, np.zeros((0, 4), np.int64), source="wrinkling sheet")
    b.add_membrane(F, StVKMembrane(3e3, 0.3, 1e-3, 1e3, wrinkling=True))
    model = b.finalize("float64")
    s = model.state()
    u = np.zeros_like(V)
    u[:, 0] = gamma * V[:, 1]
    s.set_displacements(u)
    return float(model.membrane_results(s)["tension"][:, 3].mean())


def bending_strip_tip(alpha: float, nx: int = 20, ny: int = 4) -> tuple[float, float]:
    """A strip of bending membranes alone (10 × 2 cm, 1 mm thick, StVKMembrane E = 1 MPa, ν = 0 and
    bending: a beam; nx × ny squares, each cut in two along alternating diagonals), its edge x = 0
    held and so clamped, bent by a dead load P = α E I / L² along +z spread along its tip edge,
    relaxed (float64, residual 1e-8 of the load): (tip deflection / L, tip shortening / L) of the tip
    edge's nodes, averaged."""
    from .. import StVKMembrane

    L, W, h, E = 0.1, 0.02, 1e-3, 1e6
    P = alpha * E * W * h**3 / 12 / L**2
    x, y = np.meshgrid(np.linspace(0, L, nx + 1), np.linspace(0, W, ny + 1), indexing="ij")
    X = np.c_[x.ravel(), y.ravel(), np.zeros(x.size)]
    node = lambda i, j: i * (ny + 1) + j  # noqa: E731
    F = []
    for i in range(nx):
        for j in range(ny):
            a, b, c, d = node(i, j), node(i + 1, j), node(i + 1, j + 1), node(i, j + 1)
            F += [[a, b, c], [a, c, d]] if (i + j) % 2 else [[a, b, d], [b, c, d]]
    b = ModelBuilder()
    b.add_mesh(X, np.zeros((0, 4), np.int64), source="bending strip")
    b.add_membrane(np.array(F), StVKMembrane(E=E, nu=0.0, thickness=h, density=1000.0, bending=True))
    b.fix(np.flatnonzero(X[:, 0] == 0))
    tip = np.flatnonzero(X[:, 0] == L)
    share = np.where((X[tip, 1] == 0) | (X[tip, 1] == W), 0.5, 1.0) / ny  # a uniform line load
    for n, s in zip(tip, share):
        b.add_force([int(n)], [0.0, 0.0, P * s])
    sim = Simulation(b.finalize("float64"))
    sim.relax(tol=1e-8, max_steps=2_000_000)
    u = sim.displacements[tip]
    return float(u[:, 2].mean() / L), float(-u[:, 0].mean() / L)


def twisted_cylinder(n: int, psi: float, mu: float = 1e4, nu: float = 0.499) -> tuple[float, float]:
    """A solid cylinder (radius a = 1 cm, length L = 4 cm; n × n × 2n Kuhn-split cells of a square
    mapped onto the disk, (x, y) → a (x √(1 − y²/2), y √(1 − x²/2)); Neo-Hookean μ [Pa], ν, T4ANP,
    float64), its base fixed and its top turned rigidly by ψ L about the axis at fixed length (the
    exact field's own end conditions), relaxed in 8 increments to 1e-6: (torque [N·m], axial force
    [N]) the top's support exerts, from the nodal reactions at the deformed positions."""
    from .. import NeoHookean

    a, L = 0.01, 0.04
    X, T = mesh.box_tets((2.0, 2.0, L), (n, n, 2 * n), origin=(-1.0, -1.0, 0.0))
    x, y = X[:, 0].copy(), X[:, 1].copy()
    X[:, 0], X[:, 1] = a * x * np.sqrt(1 - y**2 / 2), a * y * np.sqrt(1 - x**2 / 2)
    b = ModelBuilder()
    b.add_mesh(X, T, source="twisted cylinder")
    b.set_material(NeoHookean(E=2 * mu * (1 + nu), nu=nu), density=1000.0)
    b.nodal_pressure = True
    b.fix(np.flatnonzero(X[:, 2] == 0.0))
    top = np.flatnonzero(X[:, 2] == L)
    c, s = math.cos(psi * L), math.sin(psi * L)
    Xt = X[top]
    turn = np.c_[(c - 1) * Xt[:, 0] - s * Xt[:, 1], s * Xt[:, 0] + (c - 1) * Xt[:, 1], np.zeros(len(top))]
    b.prescribe(top, turn, curve=Ramp(1.0))
    model = b.finalize("float64")
    state = model.state()
    Solver(model).relax(state, tol=1e-6, increments=8, max_steps=2_000_000)
    f = (model.internal_forces(state) - model.external_forces(state))[top]
    x = state.positions[top]
    return float(np.sum(x[:, 0] * f[:, 1] - x[:, 1] * f[:, 0])), float(f[:, 2].sum())


def deformed_cube(material, deformations) -> list[tuple[np.ndarray, np.ndarray]]:
    """A jittered 1 m cube of 3 × 3 × 3 cells (162 tets, float64, unconstrained), built once and
    given each homogeneous deformation x = F X of ``deformations`` (each (3, 3); no solve): for each,
    its internal forces [N] (N, 3) and its elements' Cauchy stresses [Pa] (M, 6) as xx, yy, zz, xy,
    yz, xz."""
    X, T = mesh.box_tets((1.0, 1.0, 1.0), (3, 3, 3), jitter=0.25, seed=1)
    b = ModelBuilder()
    b.add_mesh(X, T, source="deformed cube")
    b.set_material(material, density=1000.0)
    model = b.finalize("float64")
    state = model.state()
    out = []
    for F in deformations:
        state.set_displacements(X @ (np.asarray(F, float) - np.eye(3)).T)
        out.append((model.internal_forces(state), model.element_results(state)["cauchy"]))
    return out


def rotation(axis, angle: float) -> np.ndarray:
    """The rotation [1] (3, 3) by ``angle`` [rad] about ``axis`` (3,) (Rodrigues' formula)."""
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    K = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
    return np.eye(3) + math.sin(angle) * K + (1.0 - math.cos(angle)) * K @ K
