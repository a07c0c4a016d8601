"""Bad input gives typed errors that name the culprit; state save/restore round-trips."""

import numpy as np
import pytest

import pliant as pl


def _tet():
    X = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0]])
    return X, np.array([[0, 1, 2, 3]])


def _two_cubes():
    return pl.mesh.box_tets((1, 1, 1), (2, 2, 2))


def test_inverted_element_is_reported_by_id():
    X, T = _two_cubes()
    T = T.copy()
    T[7, [2, 3]] = T[7, [3, 2]]
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(pl.NeoHookean(mu=1e3, K=1e4), density=1000)
    with pytest.raises(pl.InvertedElementError) as err:
        b.finalize()
    assert err.value.element == 7 and "element 7" in str(err.value)


def test_degenerate_element_is_reported_by_id():
    X, T = _tet()
    X = np.vstack([X, [[1, 1, 0]]])
    T = np.vstack([T, [[1, 2, 4, 0]]])  # four coplanar points
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(pl.NeoHookean(mu=1e3, K=1e4), density=1000)
    with pytest.raises(pl.DegenerateElementError) as err:
        b.finalize()
    assert err.value.element == 1 and "element 1" in str(err.value)


@pytest.mark.parametrize("kwargs, text", [
    (dict(E=1e3, nu=0.5), "nu"), (dict(E=-1.0, nu=0.3), "E"), (dict(mu=0.0, K=1.0), "mu"),
    (dict(mu=1.0, K=float("nan")), "K")])
def test_bad_material_parameters(kwargs, text):
    with pytest.raises(pl.MaterialError, match=text):
        pl.NeoHookean(**kwargs)


def test_bad_density_and_missing_material():
    X, T = _tet()
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    with pytest.raises(pl.MaterialError, match="density"):
        b.set_material(pl.NeoHookean(mu=1, K=10), density=0.0)
    with pytest.raises(pl.MaterialError, match="element 0 has no material"):
        b.finalize()


def test_bad_mesh_arrays():
    X, T = _tet()
    b = pl.ModelBuilder()
    with pytest.raises(pl.MeshError, match="node 2"):
        b.add_mesh(np.where(np.arange(12).reshape(4, 3) == 7, np.nan, X), T)
    with pytest.raises(pl.MeshError, match="element 0 has node index 9"):
        b.add_mesh(X, np.array([[0, 1, 2, 9]]))
    with pytest.raises(pl.MeshError, match="shape"):
        b.add_mesh(X[:, :2], T)
    with pytest.raises(pl.DegenerateElementError, match="repeats"):
        b.add_mesh(X, np.array([[0, 1, 1, 3]]))


def test_conflicting_constraints_and_bad_loads():
    X, T = _tet()
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    b.fix([0])
    with pytest.raises(pl.InputError, match="node 0 DOF x is constrained twice"):
        b.prescribe([0], 0.1, "x")
    with pytest.raises(pl.InputError, match="node 7 out of range"):
        b.fix([7])
    with pytest.raises(pl.InputError, match="unknown DOF"):
        b.fix([1], "w")
    with pytest.raises(pl.InputError, match="force"):
        b.add_force([1, 2], np.ones((3, 3)))


def test_bad_time_step_values():
    X, T = _two_cubes()
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(pl.NeoHookean(mu=1e3, K=1e4), density=1000)
    m = b.finalize()
    for dt in (0.0, -1.0, float("nan"), float("inf")):
        with pytest.raises(pl.TimeStepError):
            pl.Solver(m, dt=dt)


def test_state_save_and_restore(tmp_path):
    X, T = _two_cubes()
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(pl.NeoHookean(mu=1e6, K=1e7), density=1000)
    b.fix(np.nonzero(X[:, 2] < 1e-9)[0])
    b.set_gravity()
    m = b.finalize("float64")
    sim = pl.Simulation(m)
    sim.step(50)
    sim.save(tmp_path / "s.npz")
    sim.step(50)
    ref = sim.displacements
    other = pl.Simulation(m)
    other.load(tmp_path / "s.npz")
    assert other.time == pytest.approx(50 * sim.solver.dt)
    other.step(50)
    assert np.array_equal(other.displacements, ref)  # same bits: restart is exact


def test_non_finite_element_is_named_as_an_element():
    """A float32 overflow (absurd force) makes J NaN: the error names the element (it used to be
    read as a node index, which crashed with an IndexError when the element id exceeded the node
    count, as on the full liver example)."""
    X, T = pl.mesh.box_tets((0.1, 0.1, 0.1), (2, 2, 2))
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(pl.NeoHookean(E=1e4, nu=0.3), density=1000.0)
    b.add_force([len(X) - 1], (3e38, 0.0, 0.0))
    sim = pl.Simulation(b.finalize("float32"))
    with pytest.raises(pl.InstabilityError, match=r"non-finite deformation in element \d+") as err:
        sim.step(50)
    assert err.value.element is not None and 0 <= err.value.element < len(T)
