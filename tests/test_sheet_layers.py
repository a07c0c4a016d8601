"""Sheets of membranes against sheets (cpp/include/pliant/soft_contact.hpp, soft_detect and
soft_sheet_target): two sheets rest on each other at the sum of their half thicknesses, and a
sheet folded onto itself (self contact) rests on its own lower layer at its whole thickness.
Against closed forms: the distance between mid-surfaces and the weight the supports carry."""

from __future__ import annotations

import numpy as np
import pytest

import pliant as pl
from pliant.contact.sdf import point_triangle_distance
from pliant.mesh.topology import boundary_faces

MU, RHO = 1e3, 1000.0  # the membranes' shear modulus [Pa] and density [kg/m³]


def _grid(nx: int, ny: int, x0, dx, dy) -> tuple[np.ndarray, np.ndarray]:
    """A grid of nx × ny cells from corner x0 [m] along the vectors dx and dy [m] (one cell
    each), two triangles a cell: nodes ((nx + 1)(ny + 1), 3) and triangles (2 nx ny, 3)."""
    i, j = np.meshgrid(np.arange(nx + 1), np.arange(ny + 1))
    P = (
        np.asarray(x0, float)
        + i.reshape(-1, 1) * np.asarray(dx, float)
        + j.reshape(-1, 1) * np.asarray(dy, float)
    )
    a = np.array([q * (nx + 1) + p for q in range(ny) for p in range(nx)])
    F = np.vstack([np.stack([a, a + 1, a + nx + 2], 1), np.stack([a, a + nx + 2, a + nx + 1], 1)])
    return P, F


def _merged(parts) -> tuple[np.ndarray, np.ndarray]:
    """One sheet from grids that share nodes along their seams (nodes within 1e-9 m merged)."""
    P = np.vstack([p for p, _ in parts])
    F = np.vstack([f + sum(len(q) for q, _ in parts[:k]) for k, (_, f) in enumerate(parts)])
    key = np.round(P / 1e-9).astype(np.int64)
    _, first, inverse = np.unique(key, axis=0, return_index=True, return_inverse=True)
    order = np.argsort(first)  # the merged nodes in the order they first appear
    rank = np.empty_like(order)
    rank[order] = np.arange(order.size)
    return P[np.sort(first)], rank[inverse.ravel()][F]


def _gap_above(P, S, F):
    """Per point of P (n, 3): its distance [m] to the sheet (nodes S, triangles F) and whether it
    lies above its closest point there."""
    n, k = len(P), len(F)
    A, B, C = (np.tile(S[F[:, j]], (n, 1)) for j in range(3))
    d, Q = point_triangle_distance(np.repeat(P, k, axis=0), A, B, C)
    d, Q = d.reshape(n, k), Q.reshape(n, k, 3)
    j = d.argmin(axis=1)
    return d[np.arange(n), j], P[:, 2] > Q[np.arange(n), j, 2]


def _napkin_on_drum(dz: float, side: float = 0.02, cells: int = 4):
    """A pinned 4 cm drum of membranes 1 mm thick (8 × 8 cells, its rim the support "rim") and a
    napkin 2 mm thick of ``side`` [m] in ``cells`` × ``cells`` cells, centred ``dz`` [m] above the
    drum's mid-plane, under gravity, damped, in soft contact. Returns the builder and the drum's
    nodes (its first) and triangles."""
    D, FD = _grid(8, 8, (-0.02, -0.02, 0.0), (0.005, 0, 0), (0, 0.005, 0))
    a = side / cells
    N, FN = _grid(cells, cells, (-side / 2, -side / 2, dz), (a, 0, 0), (0, a, 0))
    b = pl.ModelBuilder()
    b.add_mesh(np.vstack([D, N]), np.zeros((0, 4), np.int64))
    b.add_membrane(FD, pl.NeoHookeanMembrane(mu=MU, thickness=1e-3, density=RHO))
    b.add_membrane(FN + len(D), pl.NeoHookeanMembrane(mu=MU, thickness=2e-3, density=RHO))
    b.fix(np.nonzero(np.abs(D[:, :2]).max(axis=1) > 0.02 - 1e-9)[0], name="rim")
    b.add_gravity((0, 0, -9.81), np.arange(len(D) + len(N)))
    b.set_soft_contact()
    b.damping = 30.0
    return b, D, FD


@pytest.mark.parametrize("side, cells", [(0.02, 4), (0.04, 8)], ids=["smaller", "rim-on-rim"])
def test_a_napkin_rests_on_a_drum_at_both_half_thicknesses(backend, side, cells):
    """A napkin of membranes 2 mm thick dropped (from 3 mm) onto a pinned 4 cm drum 1 mm thick,
    damped, 1 s: the rim carries the weight of both, m g (1e-4: what of the motion the damping has
    left), and every napkin node lies above the drum at the sum of the two half thicknesses from its
    mid-surface, 1.5 mm (1e-2: each sheet's nodes meet the other's triangles and the Jacobi average
    of the two leaves them within 0.15 % of it; measured 1.3e-3). Before, each node met a sheet at
    that sheet's half thickness alone (0.5 mm: the two sheets overlapping by half). A 2 cm napkin,
    and one of the drum's own size squarely over it, each rim node over a drum rim node, whose rim
    rests on the drum's rounded rim: before, a node whose closest point lay on a sheet's rim passed
    beside it, the napkin's rim fell past the drum's, the two crossed and the run blew up at 0.29 s."""
    b, D, FD = _napkin_on_drum(0.003, side, cells)
    m = b.finalize("float64", backend=backend)
    assert m.contact_pairs == [(0, 1)]
    sim = pl.Simulation(m)
    sim.run(until=1.0)
    x = sim.state.positions
    np.testing.assert_allclose(m.support_reactions(sim.state)["rim"][2], m.mass.sum() * 9.81, rtol=1e-4)
    gap, above = _gap_above(x[len(D) :], x[: len(D)], FD)
    assert above.all()
    np.testing.assert_allclose(gap, 1.5e-3, rtol=1e-2)


def _sheet_and_block(X, T, S, F, thickness: float) -> pl.ModelBuilder:
    """A block (nodes X [m], tets T; Neo-Hookean, 5e4 Pa, ν = 0.3) and a sheet of membranes (nodes S
    [m], triangles F) ``thickness`` [m] thick, in soft contact."""
    b = pl.ModelBuilder()
    b.add_mesh(np.vstack([X, S]), T)
    b.set_material(pl.NeoHookean(E=5e4, nu=0.3), density=RHO)
    b.add_membrane(F + len(X), pl.NeoHookeanMembrane(mu=MU, thickness=thickness, density=RHO))
    b.set_soft_contact()
    return b


def test_a_node_on_a_sheets_mid_surface_at_the_start_is_refused_by_name():
    """Contact keeps a node on the side of a sheet it starts on; a node on the sheet's mid-surface is
    on neither. The napkin laid in the drum's plane, or 1e-12 m off it (round-off: within 1e-9 of an
    edge), is refused naming the node, both sheets and what to do (before, both sheets' nodes were
    pushed to the side the normal points to and the napkin ended tangled half below the drum); so
    is a block whose top face lies in a sheet's plane. A napkin 1e-6 m above the plane, within the
    thicknesses but on a side, is accepted (the first step puts it at their sum)."""
    for dz in (0.0, 1e-12):
        with pytest.raises(
            pl.InputError, match=r"node \d+ of body [01] starts on the mid-surface of body [01]"
        ):
            _napkin_on_drum(dz)[0].finalize("float64")
    _napkin_on_drum(1e-6)[0].finalize("float64")
    X, T = pl.mesh.box_tets((0.01, 0.01, 0.01), (2, 2, 2), origin=(-0.005, -0.005, -0.01))
    b = _sheet_and_block(X, T, *_grid(4, 4, (-0.01, -0.01, 0.0), (0.005, 0, 0), (0, 0.005, 0)), 1e-3)
    with pytest.raises(
        pl.InputError, match="of body 0 starts on the mid-surface of body 1.*neither of its sides"
    ):
        b.finalize("float64")


def test_a_napkin_rests_on_a_block_at_its_half_thickness(backend):
    """The 2 cm napkin of membranes 2 mm thick dropped (from 3 mm) onto a 4 cm block (its base held),
    damped, 1 s: every napkin node rests 1 mm, its half thickness, above the block's top face (2e-2:
    the napkin's nodes and the block's press on each other's triangles, and the Jacobi average of
    the two leaves them up to 1 % of it apart; measured 0.992–0.998 mm), as the block's nodes rest
    1 mm below the napkin's mid-surface; and the base carries the weight of both (1e-4). Before, a
    sheet's node met a solid's surface itself, while the solid's nodes kept the sheet's half
    thickness from it: the napkin lay between 0 and 1 mm above the block."""
    X, T = pl.mesh.box_tets((0.04, 0.04, 0.01), (4, 4, 1), origin=(-0.02, -0.02, -0.01))
    N, FN = _grid(4, 4, (-0.01, -0.01, 0.003), (0.005, 0, 0), (0, 0.005, 0))
    b = _sheet_and_block(X, T, N, FN, 2e-3)
    b.fix(np.nonzero(X[:, 2] < -0.01 + 1e-9)[0], name="base")
    b.add_gravity((0, 0, -9.81), np.arange(len(X) + len(N)))
    b.damping = 30.0
    m = b.finalize("float64", backend=backend)
    sim = pl.Simulation(m)
    sim.run(until=1.0)
    x = sim.state.positions
    faces = boundary_faces(T)[0]
    top = faces[(X[faces, 2] > -1e-9).all(axis=1)]  # the block's top face, as it is now
    gap, above = _gap_above(x[len(X) :], x, top)
    assert above.all()
    np.testing.assert_allclose(gap, 1e-3, rtol=2e-2)
    np.testing.assert_allclose(m.support_reactions(sim.state)["base"][2], m.mass.sum() * 9.81, rtol=1e-4)


def _folded(h: float):
    """A sheet folded over: a lower layer 4 × 4 cm at z = 0, a wall 2 cm wide and 6 mm tall at its
    edge x = 0, and an upper layer 3 × 2 cm at z = 6 mm over the lower one, joined at the wall's top;
    cells of 2 mm. The lower layer's rim, the wall and the upper layer's first 4 mm fixed (a frame
    and a clamp), the rest free under gravity (a membrane has no bending stiffness: the upper layer
    pivots about the clamp's edge, 4 mm from the wall, so that it lands on the lower layer and not
    through the fold, whose triangles around a node are no contact of it). Returns the model
    builder (membranes 2 h [m] thick), the upper layer's free nodes and the lower layer's triangles
    (K, 3)."""
    lower = _grid(20, 20, (0.0, -0.02, 0.0), (0.002, 0, 0), (0, 0.002, 0))
    wall = _grid(3, 10, (0.0, -0.01, 0.0), (0, 0, 0.002), (0, 0.002, 0))
    upper = _grid(15, 10, (0.0, -0.01, 0.006), (0.002, 0, 0), (0, 0.002, 0))
    P, F = _merged([lower, wall, upper])
    b = pl.ModelBuilder()
    b.add_mesh(P, np.zeros((0, 4), np.int64))
    b.add_membrane(F, pl.NeoHookeanMembrane(mu=MU, thickness=2 * h, density=RHO))
    lower_rim = (P[:, 2] < 1e-9) & (
        (P[:, 0] < 1e-9) | (P[:, 0] > 0.04 - 1e-9) | (np.abs(P[:, 1]) > 0.02 - 1e-9)
    )
    held = lower_rim | (P[:, 0] < 0.004 + 1e-9)  # the lower layer's rim, the wall, a clamp 4 mm deep
    b.fix(np.nonzero(held)[0], name="held")
    b.add_gravity((0, 0, -9.81), np.arange(len(P)))
    b.damping = 30.0
    lower_F = F[: len(lower[1])]
    return b, np.nonzero(~held & (P[:, 2] > 1e-9))[0], lower_F


def test_a_sheet_folded_onto_itself_rests_on_its_lower_layer(backend):
    """The upper layer of a folded sheet (membranes 1 mm thick) falls 6 mm onto the lower layer,
    damped, 1 s. With the sheet's self contact every free node of the upper layer lies above the
    lower layer, the nearest at the whole thickness from its mid-surface (both layers' halves;
    1e-2, as two sheets, above: measured 3e-4), and the frame and clamp carry the whole sheet's
    weight (1e-4: what of the motion the damping has left); without it the upper layer falls
    through the lower one."""
    h = 5e-4
    b, free, lower = _folded(h)
    b.set_soft_contact(self_contact=True)
    m = b.finalize("float64", backend=backend)
    assert m.contact_pairs == [(0, 0)]
    sim = pl.Simulation(m)
    sim.run(until=1.0)
    x = sim.state.positions
    gap, above = _gap_above(x[free], x, lower)
    assert above.all() and gap.min() >= 2 * h * (1 - 1e-2)
    np.testing.assert_allclose(gap.min(), 2 * h, rtol=1e-2)
    np.testing.assert_allclose(m.support_reactions(sim.state)["held"][2], m.mass.sum() * 9.81, rtol=1e-4)
    if backend == "cpu":
        b.soft_contact = None
        sim = pl.Simulation(b.finalize("float64"))
        sim.run(until=1.0)
        assert sim.state.positions[free, 2].min() < -0.005


def test_self_contact_of_every_body_takes_the_sheets_too():
    """self_contact=True: every body's own pair, sheets included (the fold above runs on it); a
    body number beyond the sheets is refused, naming where the sheets start."""
    b, _, _ = _folded(5e-4)
    X, T = pl.mesh.box_tets([0.01] * 3, [1, 1, 1], origin=[0.0, 0.0, -0.02])
    b.add_mesh(X, T)
    b.set_material(pl.NeoHookean(E=1e4, nu=0.3), density=RHO)
    b.set_soft_contact(self_contact=True)
    assert b.finalize("float64").contact_pairs == [(0, 0), (0, 1), (1, 1)]  # the block 0, the sheet 1
    b.set_soft_contact(self_contact=[2])
    with pytest.raises(pl.InputError, match="self_contact body 2 does not exist.*sheets of membranes from 1"):
        b.finalize("float64")
