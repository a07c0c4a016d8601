"""Two identical elastic bodies pressed together through soft contact, against Hertz: equal
paraboloids (Hertz's profile of spheres of radius R), F = 4/3 E* √R* δ^1.5 with E* = E / (2(1 − ν²)),
R* = R/2 (Johnson, Contact Mechanics, 1985, §4.2, eq. 4.22-4.23), and against the same body pressed
onto a rigid frictionless plane by δ/2, which by symmetry is the same problem (the contact plane of
two identical bodies stays flat and carries no shear) solved by another contact method (the rigid
tools', tests/test_hertz.py).

Quarter models (symmetry planes x = 0 and y = 0), frictionless, small-strain linear elasticity,
float64, quasi-static (dynamic relaxation at each total approach δ in turn)."""

import numpy as np
import pytest

from pliant.validate.models import hertz_two_bodies
from pliant.validate.references import hertz_force

R, E, NU = 0.02, 1e4, 0.3  # paraboloid radius [m], Young's modulus [Pa], Poisson ratio
DEPTHS = np.array([0.005, 0.01, 0.02]) * R  # total approach δ [m]: contact radius a = 0.05-0.1 R
H = R / 40  # cells over the contact [m]: 2-4 across the contact radius (146,004 tets in all)


@pytest.fixture(scope="module")
def forces():
    """(soft contact, rigid-plane mirror) contact forces [N] at DEPTHS."""
    soft = hertz_two_bodies(DEPTHS, R, E, NU, h=H, soft=True)
    plane = hertz_two_bodies(DEPTHS, R, E, NU, h=H, soft=False)
    return soft, plane


def _hertz(delta):
    # Two equal bodies: E* = E/(2(1 − ν²)), R* = R/2; hertz_force takes E/(1 − ν²) and R.
    return hertz_force(delta, R / 2, E / 2, NU)


def test_soft_contact_matches_the_mirrored_rigid_plane(forces):
    soft, plane = forces
    # Same mesh, same problem: what differs is the contact method (two soft surfaces meeting
    # halfway vs one surface on a rigid plane at δ/2). 1 %: both are relaxed to 1e-4 of the
    # force scale (measured: 0.13, 0.09, 0.04 %).
    np.testing.assert_allclose(soft, plane, rtol=0.01)


def test_soft_contact_force_matches_hertz(forces):
    soft, _ = forces
    # 8 %: the mesh resolves the contact radius with 2-4 cells (measured: 1.059, 1.038, 1.039;
    # the rigid plane on the same mesh 1.057, 1.037, 1.039), plus what separates the model from
    # Hertz's half-spaces, as in tests/test_hertz.py (finite bodies, the gap closed on the deformed
    # surfaces, linear tets: +2 to +4 % there on a mesh of R/100).
    np.testing.assert_allclose(soft / _hertz(DEPTHS), 1.0, atol=0.08)


def test_soft_contact_force_grows_as_depth_to_the_three_halves(forces):
    soft, _ = forces
    exponent = np.polyfit(np.log(DEPTHS), np.log(soft), 1)[0]
    # 1.5 ± 0.05: the discretization error shrinks as the contact radius spans more cells
    # (6 % at the smallest depth, 4 % at the others) and tilts the fit by about log(1.02)/log(4).
    assert abs(exponent - 1.5) < 0.05


def test_the_validation_resolution_relaxes_stably():
    """The full `pliant validate`'s mesh (R/60, 187,500 tets), its first approach: the relaxation of
    the two touching tips went unstable ("element 46890 inverted") while the contacts set the
    increment to u⁺ − u, which re-rounded it on every contact node every step; they add their
    correction now. 5 %: 3-5 cells across the contact radius, finite bodies (3.75 % measured)."""
    (force,) = hertz_two_bodies(DEPTHS[:1], R, E, NU, h=R / 60, soft=True)
    assert abs(force / _hertz(DEPTHS[0]) - 1) < 0.05


def _dome_on_block(friction, backend):
    """A quarter of a 4 × 4 × 2 cm block whose lower face bulges into a paraboloid of radius R,
    pressed 2 mm (its top moved down, ramped over 1 s) onto a 5 × 5 × 3 cm block of another mesh;
    neo-Hookean, soft contact with the given friction, float64. Returns the model, the lower
    block's bottom nodes and the upper block's top nodes (the supports, x = 0 and y = 0 rollers)."""
    import pliant as pl
    from pliant.mesh import grid_tets
    from pliant.tled.curves import Ramp
    from pliant.validate.models import paraboloid_block

    Xu, Tu = paraboloid_block(R, 2 * R, 0.2 * R, r1=0.3 * R)  # top bent down into the dome
    Xu[:, 2] = 1e-4 - Xu[:, 2]  # mirrored: the dome below, 0.1 mm above the lower block
    Tu = Tu[:, [0, 2, 1, 3]]
    xs = np.linspace(0.0, 2.5 * R, 10)
    Xl, Tl = grid_tets(xs, xs, np.linspace(-1.5 * R, 0.0, 6))
    b = pl.ModelBuilder()
    b.add_mesh(Xl, Tl)
    b.add_mesh(Xu, Tu)
    X = np.vstack([Xl, Xu])
    b.set_material(pl.NeoHookean(E=E, nu=0.4), density=1000.0)
    b.fix(np.flatnonzero(X[:, 0] == 0.0), "x")
    b.fix(np.flatnonzero(X[:, 1] == 0.0), "y")
    bottom = np.flatnonzero(X[:, 2] == X[:, 2].min())
    top = np.flatnonzero(X[:, 2] == X[:, 2].max())
    b.fix(bottom, "z")
    b.prescribe(top, [-0.1 * R], dofs="z", curve=Ramp(1.0))
    b.set_soft_contact(friction=friction)
    return b.finalize("float64", backend=backend), bottom, top


@pytest.mark.parametrize("friction", [0.0, 0.3])
def test_a_dome_pressed_onto_a_block_relaxes_to_equilibrium(friction, backend):
    """Dynamic relaxation through soft contact: curved surfaces of different meshes sliding on each
    other. The damping's estimate of the lowest eigenvalue, one step's Rayleigh quotient, swung with
    the contacts' corrections and the relaxation stalled (residual 2e-3 after 20,790 steps, here
    and with the organs of examples/organs_contact.toml); it converges now (measured: 890 steps).
    References: equilibrium, each body's supports carry what the other pushes on it (Newton's
    third law through the pair's relaxed contact force), and without friction the equilibrium does
    not depend on the path to it (two increments or four)."""
    import pliant as pl

    model, bottom, top = _dome_on_block(friction, backend)
    pushes = []
    for increments in (2, 4) if friction == 0.0 else (2,):
        sim = pl.Simulation(model)
        sim.relax(at_time=1.0, tol=1e-6, increments=increments, max_steps=20_000)  # raises if it stalls
        f = model.internal_forces(sim.state)  # at the supports: the force each exerts on its body
        push, press = f[bottom, 2].sum(), f[top, 2].sum()  # up on the lower block, down on the upper
        (pair,) = sim.contact_report().pairs  # what the lower block (body 0) receives from the upper
        # Relaxed to 1e-6 of the force scale; 1e-4 of the push leaves room for the residual's spread.
        assert push > 0.01  # [N]: Hertz's order for the quarter, 0.023 N (coarse cells, finite blocks)
        np.testing.assert_allclose([press, pair.relaxed[2]], [-push, -push], rtol=1e-4)
        pushes.append(push)
    # Path independence: 1e-4 (measured 1.2e-5 between 2 and 4 increments).
    assert abs(pushes[-1] / pushes[0] - 1) < 1e-4
