"""Batches: N independent bodies in one model, stepped by the same launches. Each body must move
exactly as it does alone (same bits: the element and node functions are the same, and so is the
order of every sum), on every backend; the per-body tool forces add up to the tool's own sum."""

from __future__ import annotations

import numpy as np
import pytest

import pliant as pl
from pliant.contact import Sphere
from pliant.tled.batch import Batch, merge_builders

X, T = pl.mesh.box_tets((0.04, 0.02, 0.02), (8, 4, 4))


def body(material, tool: bool = False, X=X, T=T) -> pl.ModelBuilder:
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(material, density=1000.0)
    b.fix(np.nonzero(X[:, 0] < 1e-9)[0])
    b.set_gravity((0.0, 0.0, -9.81))
    b.add_force(np.nonzero(X[:, 0] > X[:, 0].max() - 1e-9)[0], (0.0, 0.001, 0.0), curve=pl.Ramp(0.01))
    b.damping = 20.0
    if tool:  # touches the free end (the bar: 0 ≤ x ≤ 0.04 m, 0 ≤ z ≤ 0.02 m), presses 0.4 mm/ms
        probe = Sphere(0.006, mu_s=0.3, mu_k=0.2, name="probe")
        b.add_tool(probe.at(0.0, (0.035, 0.01, 0.026)).at(0.01, (0.035, 0.01, 0.022)))
    return b


MATERIALS = [
    pl.NeoHookean(E=3e4, nu=0.45),
    pl.NeoHookean(E=6e4, nu=0.4),
    pl.MooneyRivlin(C10=4e3, C01=2e3, K=1e5),
    pl.Viscoelastic(pl.NeoHookean(E=3e4, nu=0.45), iso=[(0.3, 0.002)]),
]


@pytest.mark.parametrize("tool", [False, True], ids=["free", "tool"])
def test_each_body_moves_as_it_does_alone(backend, tool):
    """Four bodies (two Neo-Hookean moduli, Mooney–Rivlin, viscoelastic: three kinds of launch)
    with one fixed step, 300 steps: each body's displacements equal its run alone, bit for bit."""
    dt, steps = 2e-6, 300
    batch = Batch([body(m, tool) for m in MATERIALS], "float64", backend=backend)
    sim = pl.Simulation(batch.model, dt=dt)
    sim.run(steps=steps)
    U = batch.stack(sim.displacements)
    assert U.shape == (len(MATERIALS), len(X), 3)
    for k, m in enumerate(MATERIALS):
        alone = pl.Simulation(body(m, tool).finalize("float64", backend=backend), dt=dt)
        alone.run(steps=steps)
        assert np.abs(alone.displacements).max() > 1e-7
        assert np.array_equal(U[k], alone.displacements), k
        assert np.array_equal(batch.nodes(sim.velocities, k), alone.velocities)
        vm = batch.elements(sim.element_results()["von_mises"], k)
        assert np.array_equal(vm, alone.element_results()["von_mises"])
        if tool:
            f_alone = alone.contact_report().force(0)[0]
            f_batch = batch.tool_forces(sim.contact_report())[k, 0]
            assert np.linalg.norm(f_alone) > 0
            # The body's nodal forces summed in node order against the engine's per-chunk sums:
            # the same terms in another order, so round-off apart (1e-12 relative, float64).
            assert np.allclose(f_batch, f_alone, rtol=1e-12, atol=1e-15)
    if tool:  # the tool's own sum is over every body
        total = sim.contact_report().force(0)[0]
        assert np.allclose(
            batch.tool_forces(sim.contact_report())[:, 0].sum(axis=0), total, rtol=1e-12, atol=1e-15
        )


def test_different_bodies_and_material_dicts():
    """Bodies of different meshes in one batch; replicate() with per-set materials."""
    X2, T2 = pl.mesh.box_tets((0.03, 0.02, 0.02), (6, 3, 3))
    b2 = body(MATERIALS[0], X=X2, T=T2)
    batch = Batch([body(MATERIALS[0]), b2], "float64")
    assert list(np.diff(batch.node_offsets)) == [len(X), len(X2)]
    assert list(np.diff(batch.element_offsets)) == [len(T), len(T2)]
    with pytest.raises(pl.InputError, match="different node counts"):
        batch.stack(batch.model.reference_positions)
    assert np.array_equal(batch.nodes(batch.model.reference_positions, 1), X2)
    b = body(MATERIALS[0])
    rep = Batch.replicate(b, [MATERIALS[1], {b.sets[0].name: MATERIALS[2]}], "float64")
    assert [type(s.material).__name__ for s in rep.model.sets] == ["NeoHookean", "MooneyRivlin"]
    with pytest.raises(pl.InputError, match="names element set"):
        Batch.replicate(b, [{"liver": MATERIALS[0]}])


def test_lists_that_are_not_lists_of_bodies_or_materials_are_named():
    """Batch's builders and replicate's materials must be lists of ModelBuilders and of Materials
    (or dicts of set names to Materials): anything else is named (a number or None was Python's
    TypeError, a tuple of numbers an AttributeError at finalize)."""
    for builders in (None, 3, "bodies", {"a": 1}):
        with pytest.raises(pl.InputError, match="builders"):
            Batch(builders)
    for materials in (None, float("inf"), True, (0, 0, 0), [MATERIALS[0], "x"], [{"body": 3}]):
        with pytest.raises(pl.InputError, match="materials"):
            Batch.replicate(body(MATERIALS[0]), materials)


@pytest.mark.parametrize(
    "change, what",
    [
        (lambda b: setattr(b, "damping", 3.0), "damping"),
        (lambda b: b.set_gravity((0.0, 0.0, -1.0)), "gravity"),
        (lambda b: setattr(b, "nodal_pressure", True), "nodal_pressure"),
        (lambda b: b.add_tool(Sphere(0.01, name="other")), "tools"),
    ],
)
def test_shared_settings_must_agree(change, what):
    other = body(MATERIALS[0])
    change(other)
    with pytest.raises(pl.InputError, match=f"body 1 .*another {what}"):
        merge_builders([body(MATERIALS[0]), other])
