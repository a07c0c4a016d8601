"""Soft contact with a sheet of membranes apart from the tets (pliant.contact.soft.sheets_apart;
cpp/include/pliant/soft_contact.hpp, soft_sheet_target): the sheet is two-sided, a node keeps to
the side of its mid-surface it came from, half the sheet's thickness away. Against a closed form
(a block resting on a drum, from either side: the drum's rim carries the block's weight), momentum
conservation in free flight, and NiftySim's own model of two cubes dropped onto a sheet from
opposite sides (two_cubes_sheet.xml)."""

from __future__ import annotations

import json
from pathlib import Path

import meshio
import numpy as np
import pytest

import pliant as pl
from pliant.contact.sdf import point_triangle_distance
from pliant.mesh import grid_tets

DATA = Path(__file__).parent / "data"
H = 1e-3  # the sheet's thickness [m]


def _drum(n=9, L=0.04):
    """A square sheet L × L [m] at z = 0 of n × n nodes, 2 (n − 1)² triangles, and its rim nodes."""
    g = np.linspace(-L / 2, L / 2, n)
    S = np.array([[x, y, 0.0] for y in g for x in g])
    F = [[a, a + 1, a + n + 1] for a in range(n * n - n) if a % n < n - 1]
    F += [[a, a + n + 1, a + n] for a in range(n * n - n) if a % n < n - 1]
    rim = np.nonzero(np.abs(S[:, :2]).max(axis=1) > L / 2 - 1e-9)[0]
    return S, np.array(F), rim


def _block(side: int, a=0.01, cells=2):
    """A cube of side a [m] of 2 × 2 × 2 cells centred over the drum, 1 mm beyond the sheet's
    surface on the given side (+1 above, −1 below)."""
    X, T = grid_tets(*(np.linspace(-a / 2, a / 2, cells + 1),) * 2, np.linspace(0, a, cells + 1))
    X = X.copy()
    X[:, 2] += H / 2 + 1e-3 if side > 0 else -(a + H / 2 + 1e-3)
    return X, T


def _clearance(P: np.ndarray, S: np.ndarray, F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per point of P (n, 3): its distance [m] to the sheet (nodes S, triangles F) and the sign of
    its height over its closest point there (which side it is on)."""
    n, k = len(P), len(F)
    A, B, C = (np.tile(S[F[:, j]], (n, 1)) for j in range(3))
    d, Q = point_triangle_distance(np.repeat(P, k, axis=0), A, B, C)
    d, Q = d.reshape(n, k), Q.reshape(n, k, 3)
    j = d.argmin(axis=1)
    return d[np.arange(n), j], np.sign(P[:, 2] - Q[np.arange(n), j, 2])


def _block_on_drum(
    side: int, backend: str, contact=True, gravity=9.81, pinned=True, damping=30.0, threads=None
):
    X, T = _block(side)
    S, F, rim = _drum()
    b = pl.ModelBuilder()
    b.add_mesh(np.vstack([X, S]), T)
    b.set_material(pl.NeoHookean(E=2e4, nu=0.3), density=1000.0)
    b.add_membrane(F + len(X), pl.NeoHookeanMembrane(mu=1e3, thickness=H, density=1000.0))
    if pinned:
        b.fix(rim + len(X), name="rim")
    if gravity:
        b.add_gravity((0, 0, -side * gravity), np.arange(len(X) + len(S)))
    if contact:
        b.set_soft_contact()
    b.damping = damping
    return b.finalize("float64", backend=backend, threads=threads), len(X), F + len(X)


@pytest.mark.parametrize("side", [1, -1])
def test_a_block_rests_on_a_drum_from_either_side(side, backend):
    """A 1 cm block (2 × 10⁴ Pa) dropped from 1 mm onto a 4 cm drum of membranes (pinned rim,
    μ = 10³ Pa, 1 mm thick) from above, or pushed up onto it from below by gravity reversed, comes
    to rest on it (damped, 1 s): the rim carries the weight of block and drum, m g, to 1e-4 (what
    of the motion the damping has left; measured 3.4e-6 and 4.1e-6), and no node of the block is on
    the other side of the sheet or nearer its mid-surface than half its thickness (less 1e-6, the
    contact's round-off; measured 8e-9). Without contact the block falls through and the rim
    carries the drum alone (0.5 %: the drum still swings a little)."""
    m, nb, F = _block_on_drum(side, backend)
    sim = pl.Simulation(m)
    sim.run(until=1.0)
    x = sim.state.positions
    weight = m.mass.sum() * 9.81
    np.testing.assert_allclose(m.support_reactions(sim.state)["rim"][2], side * weight, rtol=1e-4)
    gap, on = _clearance(x[:nb], x, F)
    assert (on == side).all() and gap.min() >= 0.5 * H * (1 - 1e-6)
    if backend == "cpu":
        m, nb, F = _block_on_drum(side, backend, contact=False)
        sim = pl.Simulation(m)
        sim.run(until=1.0)
        assert (_clearance(sim.state.positions[:nb], sim.state.positions, F)[1] == -side).all()
        drum = m.mass[nb:].sum() * 9.81
        np.testing.assert_allclose(m.support_reactions(sim.state)["rim"][2], side * drum, rtol=5e-3)


def test_a_block_flying_into_a_free_sheet_conserves_momentum(backend):
    """No gravity, no damping, no support: a block at 0.2 m/s meets a free sheet of membranes.
    Contact impulses are equal and opposite (docs/contact.md), so the total momentum Σ m v stays
    what it was, to round-off (1e-12 of it, float64; measured 4e-16), while the sheet, at rest
    before, carries away much of it (over 10 %; measured 34 % after 30 ms) and the block stays on
    its side."""
    m, nb, F = _block_on_drum(1, backend, gravity=0.0, pinned=False, damping=0.0)
    s = m.state()
    v = np.zeros((m.n_nodes, 3))
    v[:nb, 2] = -0.2
    dt = 0.5 * m.dt_critical
    s.set_displacements(np.zeros((m.n_nodes, 3)), v, dt)
    solver = pl.Solver(m, dt=dt, damping=0.0)
    p0 = (m.mass[:, None] * s.velocities).sum(axis=0)
    solver.run(s, until=0.03)
    p = (m.mass[:, None] * s.velocities).sum(axis=0)
    np.testing.assert_allclose(p, p0, rtol=0, atol=1e-12 * np.abs(p0).max())
    sheet = (m.mass[nb:, None] * s.velocities[nb:]).sum(axis=0)
    assert sheet[2] < 0.1 * p0[2]  # both negative: the sheet pushed along
    assert (_clearance(s.positions[:nb], s.positions, F)[1] == 1).all()


def test_niftysims_two_cubes_are_held_apart_by_the_sheet(tmp_path):
    """NiftySim's testing/data/two_cubes_sheet.xml (tests/data): two Neo-Hookean cubes of 555
    nodes drawn by gravity (0.3 m/s²) from opposite sides onto a 2 × 1 sheet of 400 NeoHookean
    membranes 0.05 thick, fixed at its rim, DoDeformableCollision, 5 s. At every frame every node of
    the upper cube lies above the sheet and every node of the lower one below it, at least half the
    sheet's thickness from its mid-surface (less 0.1 %; measured to 4 digits: 0.02500); without
    contact (--ignore MembraneContact before pliant took sheets) they fell through it."""
    from typer.testing import CliRunner

    from pliant.cli import app

    out = tmp_path / "out"
    r = CliRunner().invoke(app, ["run", str(DATA / "niftysim_two_cubes_sheet.xml"), "-o", str(out)])
    assert r.exit_code == 0, r.output
    frames = sorted(out.glob("frame_*.vtu"))
    assert len(frames) == 21
    for f in frames:
        frame = meshio.read(f)
        x = frame.points + frame.point_data["displacement"]
        F = frame.cells_dict["triangle"]
        for nodes, side in ((slice(0, 555), 1), (slice(555, 1110), -1)):
            gap, on = _clearance(x[nodes], x, F)
            assert (on == side).all() and gap.min() >= 0.025 * (1 - 1e-3), f.name
    summary = json.loads((out / "summary.json").read_text())
    assert summary["max_membrane_tension"] > 0 and not summary["warnings"]


def test_same_bits_for_any_thread_count_and_after_save_restore(tmp_path):
    """The block landing on the drum (0.1 s, in contact from about 15 ms) on 1 and 2 threads, and
    saved at 50 ms and restored: the same bits."""
    runs = []
    for threads in (1, 2):
        sim = pl.Simulation(_block_on_drum(1, "cpu", threads=threads)[0])
        sim.run(until=0.1)
        runs.append(sim.positions)
    np.testing.assert_array_equal(runs[0], runs[1])
    model = _block_on_drum(1, "cpu")[0]
    sim = pl.Simulation(model)
    sim.run(until=0.05)
    sim.save(tmp_path / "s.npz")
    again = pl.Simulation(model)
    again.load(tmp_path / "s.npz")
    again.run(until=0.1)
    np.testing.assert_array_equal(again.positions, runs[0])


def test_a_sheet_through_a_solid_at_the_start_is_refused_by_name():
    """The block placed across the drum's mid-plane: the drum's centre node starts 5 mm inside the
    block (half its side), deeper than the contact band, where contact would never push it out:
    an InputError naming that node, the sheet (body 1) and the block (body 0)."""
    X, T = _block(1)
    X[:, 2] -= X[:, 2].mean()  # centred on z = 0
    S, F, rim = _drum()
    b = pl.ModelBuilder()
    b.add_mesh(np.vstack([X, S]), T)
    b.set_material(pl.NeoHookean(E=2e4, nu=0.3), density=1000.0)
    b.add_membrane(F + len(X), pl.NeoHookeanMembrane(mu=1e3, thickness=H, density=1000.0))
    b.set_soft_contact()
    centre = len(X) + int(np.argmin(np.linalg.norm(S, axis=1)))
    with pytest.raises(pl.InputError, match=f"node {centre} of body 1 starts 0.005 m inside body 0, deeper"):
        b.finalize("float64")


def _sheet_alone(size, cells, material, z=0.0):
    """A builder with a square sheet of membranes alone, size [m] a side, cells × cells squares
    (pliant.scene.sheets.rectangle), centred over the origin at height z [m]."""
    from pliant.scene.sheets import rectangle

    V, F = rectangle(size, size, cells, cells)
    b = pl.ModelBuilder()
    b.add_mesh(V + [0.0, 0.0, z], np.zeros((0, 4), int))
    b.add_membrane(F, material)
    return b


def test_a_sheet_meets_a_rigid_tool_with_its_face(backend):
    """A sheet of membranes alone (h = 2 mm) dropped onto a rigid table rests with its nodes, its
    mid-surface, h/2 above it (its face on the table, as in soft contact: to 1e-9 m, the kinematic
    contact's round-off in float64), the table carrying its weight (1e-6); a block wrapped in a
    capsule of the same membranes rests on its own nodes (a membrane on a solid's surface has the
    solid's face: no offset)."""
    h = 2e-3
    mat = pl.NeoHookeanMembrane(mu=1e4, thickness=h, density=1000.0)
    b = _sheet_alone(0.1, 5, mat, z=0.01)
    b.add_tool(pl.contact.Plane(point=(0, 0, 0), normal=(0, 0, 1)))
    b.set_gravity((0, 0, -9.81))
    b.damping = 40.0
    m = b.finalize("float64", backend=backend)
    sim = pl.Simulation(m)
    sim.run(until=0.5)
    np.testing.assert_allclose(sim.state.positions[:, 2], h / 2, atol=1e-9)
    weight = 1000.0 * h * 0.1 * 0.1 * 9.81
    np.testing.assert_allclose(-sim.tool_force(0)[0][2], weight, rtol=1e-6)
    from pliant.mesh import grid_tets
    from pliant.mesh.topology import boundary_faces

    Xb, Tb = grid_tets(np.linspace(-0.01, 0.01, 3), np.linspace(-0.01, 0.01, 3), np.linspace(0.001, 0.021, 3))
    b = pl.ModelBuilder()
    b.add_mesh(Xb, Tb)
    b.set_material(pl.NeoHookean(E=1e4, nu=0.3), density=1000.0)
    b.add_membrane(boundary_faces(Tb)[0], mat)
    b.add_tool(pl.contact.Plane(point=(0, 0, 0), normal=(0, 0, 1)))
    b.set_gravity((0, 0, -9.81))
    b.damping = 40.0
    sim = pl.Simulation(b.finalize("float64", backend=backend))
    sim.run(until=0.5)
    assert abs(sim.state.positions[:, 2].min()) < 1e-9


def test_a_grasp_reaches_a_sheet_by_its_face(backend):
    """Jaws (a sphere of radius 1 cm) closing 1.6 mm above a sheet's mid-surface with a reach of
    1 mm: a sheet 2 mm thick has its face 0.6 mm from them, so its nodes under them are held (the
    reach counts from its face), and lifted with them; a sheet 1 mm thick, its face 1.1 mm away,
    is not held."""
    held = {}
    for h in (2e-3, 1e-3):
        b = _sheet_alone(0.04, 8, pl.NeoHookeanMembrane(mu=1e4, thickness=h, density=1000.0))
        jaws = pl.contact.Sphere(radius=0.01).at(0.0, (0, 0, 0.0116)).at(0.2, (0, 0, 0.0216))
        b.add_tool(jaws.grasp(0.0, reach=1e-3))
        b.damping = 20.0
        sim = pl.Simulation(b.finalize("float64", backend=backend))
        sim.run(until=0.2)
        held[h] = sorted(sim.state.held)
        if held[h]:
            assert sim.state.positions[held[h], 2].min() > 0.009  # lifted 1 cm with the jaws
    assert held[2e-3] == [40] and held[1e-3] == []  # the centre node of 9 × 9
