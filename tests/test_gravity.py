"""Gravity on some nodes only (ModelBuilder.add_gravity; NiftySim's Gravity constraint acts on its
listed nodes): each free body falls as ü = g from rest does under central differences,
u_n = g Δt² n(n + 1)/2 (tests/test_damping.py), with the g of its own nodes; a body without one
stays put, gravities add up, and nodes a cut copies keep theirs."""

from __future__ import annotations

import numpy as np

import pliant as pl
from pliant.tled.batch import Batch

DT, STEPS = 1e-5, 400


def _fall(g) -> np.ndarray:
    """u after STEPS steps of free fall at g [m/s²] from rest (central differences)."""
    return np.asarray(g) * DT**2 * STEPS * (STEPS + 1) / 2


def _cube(origin=(0.0, 0.0, 0.0)):
    X, T = pl.mesh.box_tets((0.02, 0.02, 0.02), (3, 3, 3), origin=origin)
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(pl.NeoHookean(E=2e5, nu=0.3), density=1000.0)
    return b


def _two_cubes():
    """Two separate cubes in one mesh: nodes of the first, then of the second."""
    X, T = pl.mesh.box_tets((0.02, 0.02, 0.02), (3, 3, 3))
    b = pl.ModelBuilder()
    b.add_mesh(np.vstack([X, X + [0.05, 0.0, 0.0]]), np.vstack([T, T + len(X)]))
    b.set_material(pl.NeoHookean(E=2e5, nu=0.3), density=1000.0)
    return b, np.arange(len(X)), np.arange(len(X), 2 * len(X))


def _run(b, backend="cpu") -> np.ndarray:
    sim = pl.Simulation(b.finalize("float64", backend=backend), dt=DT)
    sim.run(steps=STEPS)
    return sim.displacements


def test_each_body_falls_with_the_gravity_of_its_own_nodes(backend):
    """Opposite gravities on two cubes (NiftySim's two_cubes_sheet.xml pulls its cubes together
    so), and none on a third: closed-form free fall each, to round-off; the third does not move."""
    b, a, c = _two_cubes()
    g1, g2 = np.array([0.0, 0.0, -9.81]), np.array([0.0, 3.0, 9.81])
    b.add_gravity(g1, a)
    b.add_gravity(g2, c)
    u = _run(b, backend)
    assert np.allclose(u[a], _fall(g1), rtol=1e-12, atol=1e-18)
    assert np.allclose(u[c], _fall(g2), rtol=1e-12, atol=1e-18)
    b, a, c = _two_cubes()
    b.add_gravity(g1, a)
    u = _run(b, backend)
    assert np.all(u[c] == 0.0)


def test_node_gravity_adds_to_whole_body_gravity_and_to_itself():
    """set_gravity (every node) + add_gravity twice on every node: the accelerations sum."""
    b = _cube()
    everyone = np.arange(b.n_nodes)
    b.set_gravity((0.0, 0.0, -9.81))
    b.add_gravity((1.0, 0.0, 0.0), everyone)
    b.add_gravity((0.5, -2.0, 0.0), everyone, curve=pl.Constant())
    assert np.allclose(_run(b), _fall([1.5, -2.0, -9.81]), rtol=1e-12, atol=1e-18)


def test_cut_copies_keep_their_gravity():
    """A node copied by a cut (ModelBuilder.split: the first element takes a copy of its first
    node) carries its share of the mass; with the gravity kept, the whole body still falls
    rigidly (a copy without it would lag behind)."""
    b = _cube()
    g = np.array([0.0, 0.0, -9.81])
    b.add_gravity(g, np.arange(b.n_nodes))
    tets = b.tets.copy()
    n = int(tets[0, 0])
    tets[0, 0] = b.n_nodes  # the copy, numbered after the existing nodes
    cut = b.split(tets, [n])
    assert cut.n_nodes == b.n_nodes + 1
    assert np.allclose(_run(cut), _fall(g), rtol=1e-12, atol=1e-18)


def test_batch_bodies_keep_their_node_gravity():
    """Bodies batched into one model keep the gravity of their own nodes (offset with them)."""
    bodies, gs = [], [np.array([0.0, 0.0, -9.81]), np.array([2.0, 0.0, 0.0])]
    for g in gs:
        b = _cube()
        b.add_gravity(g, np.arange(b.n_nodes))
        bodies.append(b)
    batch = Batch(bodies, "float64")
    sim = pl.Simulation(batch.model, dt=DT)
    sim.run(steps=STEPS)
    off = batch.node_offsets
    for k, g in enumerate(gs):
        assert np.allclose(sim.displacements[off[k] : off[k + 1]], _fall(g), rtol=1e-12, atol=1e-18)


def test_add_gravity_refuses_bad_input():
    b = _cube()
    for g, nodes, says in [
        ((0, 0), [0], "3 finite components"),
        ((0, 0, np.nan), [0], "3 finite components"),
        ((0, 0, -9.81), [b.n_nodes], "add_gravity nodes"),
    ]:
        try:
            b.add_gravity(g, nodes)
        except pl.InputError as e:
            assert says in str(e)
        else:
            raise AssertionError(f"add_gravity({g}, {nodes}) accepted")


def test_internal_forces_at_a_support_are_what_it_holds_up():
    """A 2 × 2 × 10 cm bar hanging from its fixed top, relaxed under gravity: the internal forces at
    the top sum to the force the support exerts on the bar, upward: the bar's weight less the
    top nodes' own (their lumped masses are loaded at the support itself). Tolerance 1e-4 of the
    weight: the relaxation stops at a relative out-of-balance force of 1e-5 (its default tol), summed
    over the 9 top nodes."""
    X, T = pl.mesh.box_tets([0.02, 0.02, 0.1], [2, 2, 10])
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(pl.NeoHookean(E=1e5, nu=0.3), density=1000.0)
    top = np.flatnonzero(X[:, 2] > 0.1 - 1e-9)
    b.fix(top)
    b.set_gravity([0.0, 0.0, -9.81])
    m = b.finalize("float64")
    sim = pl.Simulation(m)
    sim.relax()
    weight = 9.81 * (m.mass.sum() - m.mass[top].sum())
    held = m.internal_forces(sim.state)[top].sum(axis=0)
    np.testing.assert_allclose(held, [0.0, 0.0, weight], atol=1e-4 * weight)
