"""Membranes that wrinkle (``wrinkling=True``; cpp/include/pliant/membrane.hpp, membrane_wrinkle)
against tension-field theory written here in Cartesian components (Roddeman et al. 1987; Pipkin's
relaxed energy, 1986): a homogeneous in-plane deformation of a sheet, rotated in space, gives the
material's stress where taut, none where slack, and uniaxial tension along the major principal
direction where wrinkled, with the relaxed energy; the stable step counts the sheet as taut; a
drape laid over a ball runs at the default step; and a step that is unstable on membranes alone
is caught as a jump of a node."""

import numpy as np
import pytest

import pliant as pl
from pliant.validate.references import membrane_stress_2d as _material
from pliant.validate.references import tension_field as _tension_field

MATERIALS = {
    "neo-hookean": lambda w: pl.NeoHookeanMembrane(mu=2e3, thickness=1e-3, density=1100.0, wrinkling=w),
    "stvk": lambda w: pl.StVKMembrane(E=5e3, nu=0.35, thickness=2e-3, density=900.0, wrinkling=w),
}

# In-plane deformation gradients (x, y) and the state tension-field theory gives both materials.
CASES = {
    "simple shear": ([[1.0, 0.2], [0.0, 1.0]], "wrinkled"),
    "stretched past its free width": ([[1.3, 0.0], [0.0, 0.8]], "wrinkled"),
    "stretched, width held": ([[1.2, 0.0], [0.0, 1.0]], "taut"),
    "stretched both ways, sheared": ([[1.1, 0.05], [0.0, 1.15]], "taut"),
    "compressed both ways": ([[0.9, 0.0], [0.02, 0.95]], "slack"),
}


def _sheet(n=2):
    """A 1 m square sheet in the plane z = 0, n × n squares of two triangles each."""
    xs = np.linspace(0, 1, n + 1)
    X = np.array([[x, y, 0.0] for x in xs for y in xs])
    idx = lambda i, j: i * (n + 1) + j  # noqa: E731
    F = [
        t
        for i in range(n)
        for j in range(n)
        for t in (
            [idx(i, j), idx(i + 1, j), idx(i + 1, j + 1)],
            [idx(i, j), idx(i + 1, j + 1), idx(i, j + 1)],
        )
    ]
    return X, np.array(F)


def _rotation():
    """A rotation by 40° about the axis (1, 2, 3)/√14 (Rodrigues)."""
    k = np.array([1.0, 2.0, 3.0]) / np.sqrt(14.0)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    a = np.radians(40.0)
    return np.eye(3) + np.sin(a) * K + (1 - np.cos(a)) * K @ K


@pytest.mark.parametrize("case", sorted(CASES))
@pytest.mark.parametrize("kind", sorted(MATERIALS))
def test_a_homogeneous_deformation_meets_tension_field_theory(kind, case, backend):
    """A sheet deformed by F2 in its plane and then rotated in space: each membrane's Cauchy
    resultant t = R F S Fᵀ Rᵀ / det F and energy A0 h W are tension-field theory's (in the state the
    case names) with wrinkling, and the material's own without (different wherever the sheet is not
    taut). float64: round-off (1e-9 of the largest resultant)."""
    F2, state = np.array(CASES[case][0]), CASES[case][1]
    X, F = _sheet()
    R = _rotation()
    x = X.copy()
    x[:, :2] = X[:, :2] @ F2.T
    x = x @ R.T
    got = {}
    for wrinkling in (True, False):
        material = MATERIALS[kind](wrinkling)
        b = pl.ModelBuilder()
        b.add_mesh(X, np.zeros((0, 4), int))
        b.add_membrane(F, material)
        m = b.finalize("float64", backend=backend)
        s = m.state()
        s.set_displacements(x - X)
        r = got[wrinkling] = m.membrane_results(s)
        if wrinkling:
            theory, S, W = _tension_field(material, F2)
            assert theory == state
        else:
            S, W = _material(material, F2.T @ F2)
        t3 = np.zeros((3, 3))
        t3[:2, :2] = F2 @ S @ F2.T / np.linalg.det(F2)
        t = R @ t3 @ R.T
        want = np.array([t[0, 0], t[1, 1], t[2, 2], t[0, 1], t[1, 2], t[0, 2]])
        scale = np.abs(_material(material, F2.T @ F2)[0]).max()
        np.testing.assert_allclose(r["tension"], np.tile(want, (len(F), 1)), rtol=0, atol=1e-9 * scale)
        np.testing.assert_allclose(r["energy"], W / len(F), rtol=1e-9, atol=1e-12 * scale)
    differ = np.abs(got[True]["tension"] - got[False]["tension"]).max()
    assert (differ > 1e-3 * np.abs(got[False]["tension"]).max()) == (state != "taut")


def _free_sheet(wrinkling, n=8):
    b = pl.ModelBuilder()
    X, F = _sheet(n)
    b.add_mesh(X, np.zeros((0, 4), int))
    b.add_membrane(F, MATERIALS["neo-hookean"](wrinkling))
    return b, X


def test_the_stable_step_counts_a_wrinkling_sheet_as_taut():
    """About the flat reference state a compressive perturbation of a wrinkling sheet meets no
    stiffness; the stable step is the taut sheet's all the same (the stiffness a stretched sheet
    has), and so is the default step."""
    models = [_free_sheet(w)[0].finalize("float64") for w in (True, False)]
    assert models[0].stable_step() == models[1].stable_step()
    assert pl.Solver(models[0]).dt == pl.Solver(models[1]).dt
    # About a state compressed 10 % (slack everywhere: no stiffness at all while it wrinkles), as
    # after a cut (pliant.cutting re-estimates the step about the current state).
    from pliant.cutting.stability import highest_frequency

    w = []
    for m in models:
        s = m.state()
        s.set_displacements(-0.1 * m.reference_positions)
        w.append(highest_frequency(m, s))
    assert w[0] == w[1] > 0


@pytest.mark.parametrize("wrinkling", [True, False])
def test_an_unstable_step_on_membranes_alone_is_caught_as_a_jump(wrinkling, backend):
    """Membranes have no J to go negative: a sheet stepped at 3 × its stable step (allowed), from a
    bump of 1 µm, beats in a growing sawtooth that is stopped when a node moves more than the
    sheet's size (its diagonal, √2 m) in one step, long before any displacement reaches 100 sizes,
    naming the node and the step; where the sheet carries compression the message says that it
    might wrinkle."""
    b, X = _free_sheet(wrinkling)
    m = b.finalize("float64", backend=backend)
    sim = pl.Simulation(m, dt=3 * m.stable_step(), allow_unstable=True, check_every=1)
    u = np.zeros_like(X)
    u[:, 2] = 1e-6 * np.sin(7 * X[:, 0]) * np.cos(5 * X[:, 1])
    u[:, 0] = 1e-6 * np.cos(3 * X[:, 1])
    sim.state.set_displacements(u)
    with pytest.raises(pl.InstabilityError) as err:
        sim.run(until=100 * sim.dt)
    e = err.value
    assert e.quantity == "step displacement" and abs(e.value) > np.sqrt(2) and e.node is not None
    assert f"node {e.node} moved" in str(e) and "in one step" in str(e)
    assert np.abs(sim.displacements).max() < 100 * np.sqrt(2)
    assert ("wrinkling=True" in str(e)) == (not wrinkling)
