"""Frictional contact with rigid tools against closed-form mechanics."""

import math

import numpy as np
import pytest

import pliant as pl
from pliant.contact import Box, Capsule, Cylinder, Plane, Sphere

G = 9.81


def _block(size, cells, E=2e6, nu=0.3, rho=1000.0, damping=0.0, dtype="float64"):
    X, T = pl.mesh.box_tets(size, cells, origin=(-size[0] / 2, -size[1] / 2, 0.0))
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(pl.NeoHookean(E=E, nu=nu), density=rho)
    b.damping = damping
    return X, b


def _incline(theta, mu_s, mu_k, size=(0.02, 0.02, 0.02), cells=(4, 4, 4)):
    """A block on the plane z = 0 with gravity tilted by θ: the same as a plane inclined by θ
    (down-slope is +x)."""
    X, b = _block(size, cells)
    b.set_gravity((G * math.sin(theta), 0.0, -G * math.cos(theta)))
    b.add_tool(Plane((0, 0, 0), (0, 0, 1), mu_s=mu_s, mu_k=mu_k))
    return X, b.finalize("float64")


def _centroid_track(sim, t_end, frames):
    t, x = [], []
    m = sim.model.mass
    for k in range(frames):
        sim.run(until=t_end * (k + 1) / frames)
        t.append(sim.time)
        x.append(np.sum(m[:, None] * sim.positions, axis=0) / m.sum())
    return np.array(t), np.array(x)


def test_block_sticks_below_the_friction_angle():
    theta = math.atan(0.3)  # tan θ = 0.3 < μs = 0.5
    X, model = _incline(theta, 0.5, 0.4)
    sim = pl.Simulation(model)
    t, x = _centroid_track(sim, 0.3, 10)
    # Sliding at a = g (sin θ − μk cos θ) would cover 0.5 a t² ≈ 2 cm in 0.3 s: the elastic
    # creep allowed here is 1 % of that.
    assert abs(x[-1, 0] - x[0, 0]) < 0.01 * 0.5 * G * (math.sin(theta) - 0.4 * math.cos(theta) + 0.1) * 0.09
    assert sim.positions[:, 2].min() >= -1e-12  # nothing inside the plane


@pytest.mark.parametrize("tan_theta, mu_k", [(0.7, 0.4), (0.5, 0.2), (0.3, 0.0)])
def test_block_slides_with_coulomb_acceleration(tan_theta, mu_k):
    theta = math.atan(tan_theta)
    X, model = _incline(theta, 0.5 if mu_k > 0 else 0.0, mu_k)
    sim = pl.Simulation(model)
    t, x = _centroid_track(sim, 0.3, 30)
    a = 2 * np.polyfit(t[5:], x[5:, 0], 2)[0]  # after the first contact transient
    a_ref = G * (math.sin(theta) - mu_k * math.cos(theta))
    # Elastic vibration of the block rides on the rigid-body motion: 3 %.
    assert a == pytest.approx(a_ref, rel=0.03)
    H = sim.contact_report().tools[0]
    f = H.force[H.time > 0.1].mean(axis=0)  # time average: the block rings on its contact
    W = model.mass.sum() * G
    # The plane feels the normal load W cos θ and the friction μk W cos θ down the slope (+x).
    assert -f[2] == pytest.approx(W * math.cos(theta), rel=0.03)
    assert f[0] == pytest.approx(mu_k * W * math.cos(theta), abs=0.03 * W)


@pytest.mark.parametrize("tan_theta, tips", [(0.15, False), (0.45, True)])
def test_tall_block_tips_when_its_geometry_says(tan_theta, tips):
    """A block of width w and height h on a rough incline (μs = 1, no sliding) tips over when the
    line of gravity through its centre leaves the base: tan θ > w/h = 0.3."""
    theta = math.atan(tan_theta)
    X, b = _block((0.012, 0.012, 0.04), (3, 3, 10))
    b.set_gravity((G * math.sin(theta), 0.0, -G * math.cos(theta)))
    b.add_tool(Plane((0, 0, 0), (0, 0, 1), mu_s=1.0, mu_k=1.0))
    model = b.finalize("float64")
    sim = pl.Simulation(model)
    top = np.nonzero(X[:, 2] > 0.04 - 1e-9)[0]
    sim.run(until=0.25)
    lean = np.degrees(np.arctan2(sim.positions[top, 0].mean(), sim.positions[top, 2].mean()))
    if tips:
        assert lean > 20  # falling over (rotating about the downhill edge)
    else:
        assert abs(lean) < 2  # standing (elastic lean only)
    assert sim.positions[:, 2].min() >= -1e-12


def test_moving_tool_momentum_matches_reported_impulse():
    """A free body (no gravity, no support, no damping) hit by a moving sphere: its momentum
    equals the impulse of the contact forces the tool reports, Σ −F Δt (internal forces cancel)."""
    X, b = _block((0.04, 0.04, 0.04), (4, 4, 4), E=1e5)
    tool = Sphere(0.01, mu_s=0.3, mu_k=0.2)
    tool.at(0.0, (0.0, 0.0, 0.055)).at(0.05, (0.004, 0.0, 0.035))  # down and sideways, 0.4 m/s
    b.add_tool(tool)
    model = b.finalize("float64")
    sim = pl.Simulation(model)
    sim.run(until=0.06)
    H = sim.contact_report().tools[0]
    impulse = -H.force.sum(axis=0) * sim.solver.dt
    p = np.sum(model.mass[:, None] * sim.velocities, axis=0)
    assert np.abs(impulse).max() > 1e-4  # the tool did push
    assert np.allclose(p, impulse, rtol=1e-9, atol=1e-12)
    # and no node is inside the tool at the end
    assert tool.signed_distance(sim.positions, sim.time).min() > -1e-12


@pytest.mark.parametrize(
    "tool",
    [
        Capsule(0.006, 0.03, rotation=(0.7071068, 0.7071068, 0, 0)),
        Cylinder(0.006, 0.012),
        Box((0.03, 0.006, 0.006)),
    ],
    ids=["capsule", "cylinder", "box"],
)
def test_no_node_inside_a_pressing_tool(tool):
    """A tool pressed 2 mm into a block (nodal contact: smaller than the surface spacing): no
    surface node ever lies inside it, and the body pushes back on it."""
    X, b = _block((0.04, 0.04, 0.02), (8, 8, 4), E=3e4)
    b.fix(np.nonzero(X[:, 2] < 1e-9)[0])
    R, p = tool.pose(0.0)
    tool.keys = []
    tool._fixed = False
    tool.at(0.0, (0, 0, 0.02 + 0.0061), R).at(0.1, (0, 0, 0.02 + 0.006 - 0.002), R)
    b.add_tool(tool)
    model = b.finalize("float64")
    sim = pl.Simulation(model)
    for k in range(10):
        sim.run(until=0.01 * (k + 1))
        nodes = sim.contact_report().nodes
        assert tool.signed_distance(sim.positions[nodes], sim.time).min() > -1e-9
    assert sim.tool_force(0)[0][2] > 0  # the body pushes the tool up: force along +z


def test_cylinder_distance_matches_geometry():
    """The engine's flat-ended cylinder: a block pressed by its end face (axis vertical, radius
    6 mm, 2 mm deep) has every node under the face pushed to exactly the face's height, and the
    NumPy signed distance agrees with the closed form at sample points."""
    cyl = Cylinder(0.01, 0.04)
    y = np.array(
        [[0.0, 0.0, 0.0], [0.02, 0.0, 0.0], [0.0, 0.0, 0.03], [0.013, 0.0, 0.024], [0.005, 0.0, 0.019]]
    )
    ref = [-0.01, 0.01, 0.01, 0.005, -0.001]  # inside, beside, above, beyond the rim (3-4-5), inside
    np.testing.assert_allclose(cyl.signed_distance(y), ref, atol=1e-15)
    X, b = _block((0.04, 0.04, 0.02), (8, 8, 4), E=3e4)
    b.fix(np.nonzero(X[:, 2] < 1e-9)[0])
    tool = Cylinder(0.006, 0.02)
    tool.at(0.0, (0, 0, 0.03 + 1e-4)).at(0.1, (0, 0, 0.03 - 0.002))  # end face from z = 0.0201 to 0.018
    b.add_tool(tool)
    sim = pl.Simulation(b.finalize("float64"))
    sim.run(until=0.1)
    under = (np.hypot(X[:, 0], X[:, 1]) < 0.006 - 1e-9) & (X[:, 2] > 0.02 - 1e-9)
    assert under.sum() >= 5
    np.testing.assert_allclose(sim.positions[under, 2], 0.018, atol=1e-12)


def test_tool_restricted_to_a_node_set():
    """Two blocks side by side fall under gravity onto a ground plane that only the first one's
    nodes may touch: the first rests on it, the second falls through in free fall (½ g t²)."""
    X1, T1 = pl.mesh.box_tets((0.01, 0.01, 0.01), (2, 2, 2), origin=(0.0, 0.0, 0.001))
    X2, T2 = pl.mesh.box_tets((0.01, 0.01, 0.01), (2, 2, 2), origin=(0.02, 0.0, 0.001))
    b = pl.ModelBuilder()
    b.add_mesh(np.vstack([X1, X2]), np.vstack([T1, T2 + len(X1)]))
    b.set_material(pl.NeoHookean(E=1e5, nu=0.3), density=1000.0)
    b.set_gravity((0.0, 0.0, -G))
    b.damping = 20.0
    b.add_tool(Plane((0, 0, 0), (0, 0, 1)), nodes=np.arange(len(X1)))
    sim = pl.Simulation(b.finalize("float64"))
    sim.run(until=0.1)
    first, second = sim.positions[: len(X1)], sim.positions[len(X1) :]
    assert first[:, 2].min() >= -1e-12  # the first block rests on the plane
    # The second falls freely; mass-proportional damping α = 20/s slows it: z'' = −g − α z' gives
    # z(t) = z0 − g/α (t − (1 − e^(−αt))/α). Central differences started with u⁻ = u are at rest
    # at t = −Δt/2, hence the shifted time; 1e-6 m covers the scheme's O(Δt²) error.
    t, a = sim.time + sim.solver.dt / 2, 20.0
    drop = G / a * (t - (1 - math.exp(-a * t)) / a)
    np.testing.assert_allclose(second[:, 2] - X2[:, 2], -drop, atol=1e-6)


def _box_distance(p, lo, hi):
    """Closed form: the distance from points p (n, 3) outside an axis-aligned box to it."""
    return np.linalg.norm(np.maximum(np.maximum(lo - p, p - hi), 0.0), axis=1)


def test_a_mesh_tool_is_far_from_points_far_outside_its_grid(backend):
    """A MeshTool's grid covers its surface and 4 cells more. Points beyond it are at least their
    distance to the grid's box away (the engine once extrapolated the trilinear field there, which
    went negative 10 mm out: spurious contact, then a blow-up, then a crash on the NaN); a body
    far from the tool is not touched."""
    from pliant.contact import MeshTool
    from pliant.mesh import box_tets
    from pliant.mesh.topology import boundary_faces

    lo, hi = np.array([0.005, 0.005, 0.011]), np.array([0.015, 0.015, 0.021])
    V, T = box_tets(hi - lo, (1, 1, 1), origin=lo)
    F, _ = boundary_faces(T)
    tool = MeshTool(V, F)
    X, Tb = box_tets((0.02, 0.02, 0.01), (4, 4, 2))
    phi = tool.signed_distance(X)
    exact = _box_distance(X, lo, hi)
    # Never closer than the box really is, up to the grid's own error (a cell on its diagonal).
    assert np.all(phi >= exact - math.sqrt(3) * tool.spacing) and phi.min() > 0
    b = pl.ModelBuilder()
    b.add_mesh(X, Tb)
    b.set_material(pl.NeoHookean(E=1e4, nu=0.4), density=1000.0)
    b.add_tool(tool)
    sim = pl.Simulation(b.finalize("float64", backend=backend))
    sim.run(steps=50)
    assert np.all(sim.displacements == 0.0) and np.all(sim.contact_report().node_tool < 0)


def test_a_tool_that_starts_deep_in_the_body_is_refused_by_name():
    """A 2 cm block of 4 × 4 × 4 cells (smallest altitude 2.9 mm) and a sphere (r = 4 mm) whose
    centre starts on its top face: its top nodes start up to 4 mm inside the sphere, beyond half an
    altitude, and the first step's contact would push them out across their elements (before the
    check: "element inverted; reduce dt", which no dt cures). Refused naming the tool, a node and
    its depth; the same sphere starting 1 mm into the top (half an altitude is 1.44 mm) is pushed out
    and runs; a sphere that closes on what it starts in at t = 0 (a grasp) is not checked."""
    X, b = _block((0.02, 0.02, 0.02), (4, 4, 4))
    b.add_tool(Sphere(0.004, position=(0.0, 0.0, 0.02), name="probe"))
    with pytest.raises(pl.InputError, match=r"tool 0 \('probe'\) starts with node [0-9]+ 0.004 m inside it"):
        b.finalize("float64")
    for tool in (Sphere(0.004, position=(0.0, 0.0, 0.023)), Sphere(0.004, position=(0, 0, 0.02)).grasp(0.0)):
        X, b = _block((0.02, 0.02, 0.02), (4, 4, 4))
        b.add_tool(tool)
        sim = pl.Simulation(b.finalize("float64"))
        sim.run(steps=20)
        assert np.all(np.isfinite(sim.positions))
