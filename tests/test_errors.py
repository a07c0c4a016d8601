"""Bad input gives typed errors that name the culprit; state save/restore round-trips."""

import re

import numpy as np
import pytest

import pliant as pl
from pliant.mesh import box_tets


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


@pytest.mark.parametrize(
    "extra_nodes, tet",
    [
        ([[1, 1, 0]], [1, 2, 4, 0]),  # four coplanar points
        # Four nodes at one point: no edge to measure flatness by (the relative volume was 0/0 and
        # slipped through).
        ([[2.0, 2.0, 2.0]] * 4, [4, 5, 6, 7]),
    ],
)
def test_degenerate_element_is_reported_by_id(extra_nodes, tet):
    X, T = _tet()
    X = np.vstack([X, extra_nodes])
    T = np.vstack([T, [tet]])
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(pl.NeoHookean(mu=1e3, K=1e4), density=1000)
    with pytest.raises(pl.DegenerateElementError) as err:
        b.finalize()
    assert err.value.element == 1 and "element 1" in str(err.value)


@pytest.mark.parametrize(
    "kwargs, text",
    [
        (dict(E=1e3, nu=0.5), "nu"),
        (dict(E=-1.0, nu=0.3), "E"),
        (dict(mu=0.0, K=1.0), "mu"),
        (dict(mu=1.0, K=float("nan")), "K"),
        # Not numbers: float() made True 1.0 and '5' 5.0 silently, and raised a bare ValueError or
        # TypeError naming no argument for 'abc' or None.
        (dict(E=True, nu=0.3), "E = True"),
        (dict(E="5", nu=0.3), "E = '5'"),
        (dict(E=5e3, nu="abc"), "nu = 'abc'"),
        (dict(mu=[1.0], K=10.0), r"mu = \[1.0\]"),
    ],
)
def test_bad_material_parameters(kwargs, text):
    with pytest.raises(pl.MaterialError, match=text):
        pl.NeoHookean(**kwargs)


def test_parameters_that_are_not_numbers_are_named():
    """Each material family, the density, damping, loads, friction and the solver's step settings
    refuse a non-number by name; numpy scalars and 0-d arrays are numbers."""
    assert pl.NeoHookean(E=np.float32(4e3), nu=np.array(0.25)).mu == pytest.approx(1600.0)  # E / 2.5
    with pytest.raises(pl.MaterialError, match="C01 = None"):
        pl.MooneyRivlin(C10=1e3, C01=None, K=1e4)
    with pytest.raises(pl.MaterialError, match="tau='1'"):
        pl.Viscoelastic(pl.NeoHookean(E=5e3, nu=0.3), iso=[(0.5, "1")])
    with pytest.raises(pl.MaterialError, match="nu = None"):
        pl.StVKMembrane(E=1e3, nu=None, thickness=1e-3, density=1000.0)
    X, T = _tet()
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    with pytest.raises(pl.MaterialError, match="density = True"):
        b.set_material(pl.NeoHookean(mu=1, K=10), density=True)
    b.set_material(pl.NeoHookean(mu=1, K=10), density=1000.0)
    b.damping = "5"
    with pytest.raises(pl.InputError, match="damping = '5'"):
        b.finalize()
    b.damping = 0.0
    with pytest.raises(pl.InputError, match="gravity = 'down'"):
        b.set_gravity("down")
    with pytest.raises(pl.InputError, match="force = 'up'"):
        b.add_force([0], "up")
    with pytest.raises(pl.InputError, match=r"force = \(True, 0, 0\)"):  # numpy made it (1, 0, 0)
        b.add_force([0], (True, 0, 0))
    with pytest.raises(pl.InputError, match="gravity"):
        b.set_gravity([0.0, True, -9.81])
    with pytest.raises(pl.InputError, match="soft contact friction = '0.3'"):
        b.set_soft_contact(friction="0.3")
    model = b.finalize("float64")
    for kwargs, says in [
        (dict(dt=True), "dt = True"),  # was a step of 1 s
        (dict(dt="1e-4"), "dt = '1e-4'"),
        (dict(safety=True), "safety = True"),  # was the critical step itself
        (dict(damping=True), "damping = True"),
    ]:
        with pytest.raises(pl.InputError, match=says):
            pl.Solver(model, **kwargs)


@pytest.mark.parametrize(
    "make, says",
    [
        (lambda: pl.Ramp(True), "t1 = True"),  # float() made it 1 s
        (lambda: pl.Step("0.1"), "t0 = '0.1'"),
        (lambda: pl.SmoothRamp(None), "t1 = None"),  # a bare TypeError
        (lambda: pl.Table([0, 1], [0, True]), r"values = \[0, True\]"),  # numpy made it 1
        (lambda: pl.Table([0, 1], [0, "1"]), r"values = \[0, '1'\]"),
        (lambda: pl.Table([0, 1], [[0], [1]]), "values"),  # was flattened
        (lambda: pl.Table(["a", "b"], [0, 1]), "times"),  # a bare ValueError
    ],
)
def test_load_curves_that_are_not_numbers_are_named(make, says):
    with pytest.raises(pl.InputError, match=says):
        make()


# A mesh tool's test shape: a 1 cm tetrahedron, its faces outward.
_TET_V = 0.01 * np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
_TET_F = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])


@pytest.mark.parametrize(
    "make, says",
    [
        (lambda: pl.contact.Sphere(True), "radius = True"),  # float() made it 1 m
        (lambda: pl.contact.Capsule(0.01, "0.1"), "length = '0.1'"),
        (lambda: pl.contact.Box((True, 1.0, 1.0)), "half_extents"),
        (lambda: pl.contact.Box((0.1, 0.1, float("inf"))), "half_extents"),
        (lambda: pl.contact.Sphere(0.1, mu_s="0.3"), "mu_s = '0.3'"),
        (lambda: pl.contact.Sphere(0.1, rotation=(True, 0, 0, 0)), "rotation"),
        (lambda: pl.contact.Sphere(0.1, rotation=np.diag([2.0, 1.0, 1.0])), "not a rotation matrix"),
        (lambda: pl.contact.Sphere(0.1, rotation=np.diag([1.0, 1.0, -1.0])), "not a rotation matrix"),
        (lambda: pl.cutting.Blade(True), "length = True"),
        # Its swept areas overflowed (an OverflowError, exit 3, from a scene's depth = 1e300).
        (
            lambda: pl.cutting.Blade(1e300),
            "length = 1e\\+300; expected a length > 0 \\[m\\], at most 1e\\+150",
        ),
        (lambda: pl.cutting.Blade(0.01, depth=1e300), "depth = 1e\\+300"),
        (lambda: pl.cutting.Blade(float("nan")), "length = nan"),
        # A mesh tool: bare numpy errors, a negative spacing accepted, a tiny one asked for 1e21 cells.
        (lambda: pl.contact.MeshTool(_TET_V * np.nan, _TET_F), "finite positions"),
        (lambda: pl.contact.MeshTool(_TET_V, _TET_F + 10), "face 0 = \\[10, 12, 11\\] indexes beyond the 4"),
        (lambda: pl.contact.MeshTool(_TET_V[:, :2], _TET_F), "expected \\(n >= 4, 3\\)"),
        (lambda: pl.contact.MeshTool(_TET_V, _TET_F, spacing=-1.0), "spacing = -1.0"),
        (lambda: pl.contact.MeshTool(_TET_V, _TET_F, spacing=1e-9), "at most 4,194,304"),
    ],
)
def test_tool_parameters_that_are_not_numbers_or_rotations_are_named(make, says):
    """A scaled or mirrored matrix was taken for some other rotation; bools and strings for
    numbers; an infinite box was accepted."""
    with pytest.raises(pl.InputError, match=says):
        make()


def test_a_rotation_matrix_gives_its_quaternion():
    """Against scipy's conversion of the same matrix (float64 and float32 round-off)."""
    from scipy.spatial.transform import Rotation

    R = Rotation.from_euler("xyz", [10.0, 20.0, 30.0], degrees=True)
    for M, tol in ((R.as_matrix(), 1e-12), (R.as_matrix().astype(np.float32), 1e-6)):
        q = pl.contact.Sphere(0.1, rotation=M).keys[0][4:]
        assert np.allclose(q, R.as_quat()[[3, 0, 1, 2]], atol=tol)  # scipy: (x, y, z, w)


def test_a_boolean_mask_for_node_ids_says_how_to_give_them():
    """np.asarray(mask, int) would have made a mask nodes 0 and 1; the call is named (fix said
    "prescribe")."""
    X, T = _tet()
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    for call, name in (
        (lambda m: b.fix(m), "fix"),
        (lambda m: b.add_force(m, (0.0, 0.0, -1.0)), "add_force"),
    ):
        with pytest.raises(
            pl.InputError, match=rf"^{name}: node ids of type bool \(a mask\? give np.flatnonzero"
        ):
            call(X[:, 2] == 0.0)


def test_an_empty_node_selection_is_refused_by_each_call():
    """A selection that missed (a plane a little off the nodes) would have fixed, loaded or
    exposed nothing and run on; scenes refuse an empty selection, and so does the API, naming the
    call."""
    X, T = _tet()
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    none = np.flatnonzero(X[:, 2] < -1.0)
    for call, name in (
        (lambda: b.fix(none), "fix"),
        (lambda: b.prescribe([], 0.01, "z"), "prescribe"),
        (lambda: b.add_force(none, (0.0, 0.0, -1.0)), "add_force"),
        (lambda: b.add_gravity((0.0, 0.0, -9.81), none), "add_gravity nodes"),
        (lambda: b.add_tool(pl.contact.Sphere(0.01), nodes=[]), "add_tool 'sphere' nodes"),
    ):
        with pytest.raises(pl.InputError, match=rf"^{name}: no nodes given \(an empty selection\)"):
            call()
    assert not b.tools  # nothing half-added


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


def test_repeated_and_overlapping_elements_are_named():
    """A tetrahedron given twice (its mass and stiffness counted twice; a lone pair has no
    boundary, which crashed the run's picture: exit 3) and a third element on an interior face
    (elements that overlap) are refused, naming the elements and the face."""
    X = 0.01 * np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [0, 0, -1], [0.2, 0.2, -0.5]])
    b = pl.ModelBuilder()
    with pytest.raises(pl.MeshError, match=r"element 2 has the same four nodes as element 0: \[3, 1, 2, 0\]"):
        b.add_mesh(X, np.array([[0, 1, 2, 3], [0, 2, 1, 4], [3, 1, 2, 0]]))
    with pytest.raises(pl.MeshError, match=r"face \[0, 1, 2\] belongs to elements 0, 1 and 2"):
        b.add_mesh(X, np.array([[0, 1, 2, 3], [0, 2, 1, 4], [0, 2, 1, 5]]))
    b.add_mesh(X, np.array([[0, 1, 2, 3], [0, 2, 1, 4]]))  # two elements on a face: fine


def test_tangled_elements_are_named():
    """Two tets on the same side of their common face overlap (a node dragged through a face):
    refused naming both and the face; the same two on either side are a mesh."""
    X = 0.01 * np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [0.2, 0.2, 0.5], [0.2, 0.2, -0.5]])
    with pytest.raises(
        pl.MeshError, match=r"elements 0 and 1 lie on the same side of their common face \[0, 1, 2\]"
    ):
        pl.ModelBuilder().add_mesh(X, np.array([[0, 1, 2, 3], [1, 0, 2, 4]]))
    pl.ModelBuilder().add_mesh(X, np.array([[0, 1, 2, 3], [0, 2, 1, 5]]))


def test_folded_face_matches_the_sides_of_each_face():
    """topology.folded_face against the geometry: for every face two tets share, the signs of
    their opposite nodes' heights above the face's plane (opposite: a mesh; equal: folded). On
    jittered boxes with random elements turned over (orientation must not matter) and random
    nodes moved far enough to tangle."""
    from pliant.mesh.topology import folded_face

    rng = np.random.default_rng(3)
    for trial in range(30):
        X, T = box_tets((1.0, 1.0, 1.0), (3, 3, 2), jitter=0.2, seed=trial)
        T = T.copy()
        turn = rng.random(len(T)) < 0.5
        T[turn, 0], T[turn, 1] = T[turn, 1], T[turn, 0].copy()
        if trial % 2:
            X = X.copy()
            X[rng.integers(len(X))] += rng.normal(0, 0.6, 3)
        folded = set()
        by_face = {}
        for e, t in enumerate(T):
            for k in range(4):
                face = tuple(sorted(np.delete(t, k)))
                by_face.setdefault(face, []).append((e, t[k]))
        for face, pair in by_face.items():
            if len(pair) == 2:
                n = np.cross(X[face[1]] - X[face[0]], X[face[2]] - X[face[0]])
                h = [np.dot(X[apex] - X[face[0]], n) for _, apex in pair]
                if h[0] * h[1] > 0:
                    folded.add(face)
        got = folded_face(X, T)
        assert (got is None) == (not folded), (trial, got, folded)
        if got is not None:
            assert tuple(got[0]) in folded


@pytest.mark.parametrize("offset", [0, 2**40])  # node numbers packed into one integer, or not
def test_repeat_search_matches_brute_force(offset):
    """topology.repeated_element / overshared_face against a direct search over all pairs and
    triples, on random small index sets where repeats are likely."""
    from itertools import combinations

    from pliant.mesh.topology import overshared_face, repeated_element

    rng = np.random.default_rng(5)
    for _ in range(200):
        T = np.array([rng.choice(7, 4, replace=False) for _ in range(rng.integers(1, 9))]) + offset
        keys = [tuple(sorted(t)) for t in T]
        pairs = [(i, j) for i, j in combinations(range(len(T)), 2) if keys[i] == keys[j]]
        want = min(pairs, key=lambda p: (p[0], p[1])) if pairs else None
        got = repeated_element(T)
        assert got == want, (T, got, want)
        faces = [{f for f in combinations(k, 3)} for k in keys]
        triple = any(set.intersection(*(faces[e] for e in tri)) for tri in combinations(range(len(T)), 3))
        shared = overshared_face(T)
        assert (shared is None) == (not triple), (T, shared)
        if shared is not None:
            face, elems = shared
            assert len(set(elems)) == 3 and all(tuple(face) in faces[e] for e in elems)


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


@pytest.mark.parametrize("dofs", [1.5, True, float("inf"), slice(1), [[0, 1]], [], "", None, 3, -1, [0, "y"]])
def test_dofs_that_are_not_0_1_2_or_xyz_are_named(dofs):
    """A DOF list is 0, 1, 2 or letters of 'xyz': a float, bool, slice, nested list or an empty
    selection is refused naming it (1.5 read as DOF 1 before; inf, a slice and a nested list were
    Python's OverflowError / TypeError)."""
    X, T = _tet()
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    with pytest.raises(pl.InputError, match="dofs = "):
        b.fix([1], dofs)
    with pytest.raises(pl.InputError, match="dofs = "):
        b.prescribe([1], 0.1, dofs)
    b.fix([1], np.array([0, 2]))  # numpy integers are DOFs too
    assert b.supports[-1][2] == "xz"


@pytest.mark.parametrize(
    "curve", [2.0, "ramp", np.array([0.0, 1.0]), (0.0, 1.0), pl.NeoHookean(E=1e3, nu=0.3)]
)
def test_a_curve_that_is_not_a_load_curve_is_named_by_its_call(curve):
    """Every call that takes a load curve refuses what is not one, naming the call (a float was
    an AttributeError at finalize, an array numpy's ambiguous truth value)."""
    X, T = _tet()
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    calls = {
        "prescribe": lambda: b.prescribe([1], 0.1, "x", curve=curve),
        "add_force": lambda: b.add_force([1], [0.0, 0.0, 1.0], curve=curve),
        "add_pressure": lambda: b.add_pressure([[1, 2, 3]], 1.0, curve=curve),
        "add_traction": lambda: b.add_traction([[1, 2, 3]], [0.0, 0.0, 1.0], curve=curve),
        "set_gravity": lambda: b.set_gravity(curve=curve),
        "add_gravity": lambda: b.add_gravity((0.0, 0.0, -9.81), [1], curve=curve),
    }
    for who, call in calls.items():
        with pytest.raises(pl.InputError, match=rf"{who}: curve = .*expected a load curve"):
            call()


@pytest.mark.parametrize("dtype", [0, "float16", "int32", (1, 2), np.array([1.5]), object()])
def test_a_dtype_other_than_float32_or_float64_is_named(dtype):
    """finalize(dtype) takes float32 or float64; anything else is an InputError naming it (numpy's
    TypeError for what is no dtype at all before)."""
    X, T = _tet()
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(pl.NeoHookean(mu=1e3, K=1e4), density=1000)
    with pytest.raises(pl.InputError, match="dtype = .*expected 'float32' or 'float64'"):
        b.finalize(dtype)


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
    sim.run(steps=50)
    sim.save(tmp_path / "s.npz")
    sim.run(steps=50)
    ref = sim.displacements
    other = pl.Simulation(m)
    other.load(tmp_path / "s.npz")
    assert other.time == pytest.approx(50 * sim.solver.dt)
    other.run(steps=50)
    assert np.array_equal(other.displacements, ref)  # same bits: restart is exact
    # A file written before the state kept its last increment (no "du"): it loads, the increment
    # taken as u − u⁻, and runs within round-off of the exact restart.
    with np.load(tmp_path / "s.npz") as d:
        np.savez(tmp_path / "old.npz", **{k: d[k] for k in d.files if k != "du"})
    older = pl.Simulation(m)
    older.load(tmp_path / "old.npz")
    older.run(steps=50)
    np.testing.assert_allclose(older.displacements, ref, rtol=0, atol=1e-12 * np.abs(ref).max())
    # A run clock that is not one of this state's (t_epoch not finite, step_epoch not a whole step
    # from 0 to the state's step count) is named, not loaded.
    for t_epoch, step_epoch in ((np.nan, 0), (0.0, 1.5), (0.0, 51), (0.0, -1), ("x", 0)):
        with np.load(tmp_path / "s.npz") as d:
            data = {k: d[k] for k in d.files}
        data.update(t_epoch=t_epoch, step_epoch=step_epoch)
        np.savez(tmp_path / "clock.npz", **data)
        with pytest.raises(pl.InputError, match=r"clock\.npz: run clock"):
            pl.Simulation(m).load(tmp_path / "clock.npz")
    # The time a state is set to is a finite number of seconds: NaN ran into a misleading "unstable,
    # reduce dt", inf ran on with the time stuck, a string or None were Python's errors.
    for t in (float("nan"), float("inf"), -float("inf"), "x", None, True, [1.0]):
        with pytest.raises(pl.InputError, match=r"State\.time = .*expected a finite time"):
            other.state.time = t
    # A folder as the file name was saved beside it (tmp_path/d -> tmp_path/d.npz)
    (tmp_path / "d").mkdir()
    with pytest.raises(pl.InputError, match="the state file is a folder"):
        sim.save(tmp_path / "d")
    assert not (tmp_path / "d.npz").exists()
    # relax: a time that is not a number, a tolerance that is not positive (NaN relaxed forever)
    with pytest.raises(pl.InputError, match="at_time = 'x'"):
        sim.solver.relax(sim.state, at_time="x")
    with pytest.raises(pl.InputError, match="tol = nan"):
        sim.solver.relax(sim.state, tol=float("nan"))


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
        sim.run(steps=50)
    assert err.value.element is not None and 0 <= err.value.element < len(T)


# --- the Python API under hostile calls (issue 11) ----------------------------------------------
def _sim(E=1e6, tool=False):
    X, T = _two_cubes()
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(pl.NeoHookean(E=E, nu=0.3), density=1000)
    b.fix(np.nonzero(X[:, 2] < 1e-9)[0])
    b.set_gravity()
    if tool:
        b.add_tool(pl.contact.Plane((0, 0, -0.1), (0, 0, 1)))
    return pl.Simulation(b.finalize("float64")), b


@pytest.mark.parametrize(
    "content, text",
    [
        (None, "no such state file"),
        (b"", "not a readable pliant state file"),
        (b"PK\x03\x04 truncated zip", "not a readable pliant state file"),
        (b"\x93NUMPY garbage" * 10, "not a readable pliant state file"),
    ],
)
def test_state_load_of_missing_or_corrupt_files(tmp_path, content, text):
    sim, _ = _sim()
    p = tmp_path / "s.npz"
    if content is not None:
        p.write_bytes(content)
    with pytest.raises(pl.InputError, match=text) as err:
        sim.load(p)
    assert str(p) in str(err.value)


def test_state_load_of_truncated_foreign_and_other_models_files(tmp_path):
    sim, _ = _sim()
    sim.run(steps=10)
    good = tmp_path / "s.npz"
    sim.save(good)
    data = good.read_bytes()
    (tmp_path / "half.npz").write_bytes(data[: len(data) // 2])
    np.savez(tmp_path / "foreign.npz", weights=np.ones(3))
    for name, text in (("half.npz", "not a readable"), ("foreign.npz", "not a pliant state file")):
        with pytest.raises(pl.InputError, match=text):
            sim.load(tmp_path / name)
    # Same sizes, different model (another stiffness): refused by the fingerprint.
    other, _ = _sim(E=2e6)
    assert (other.model.n_nodes, other.model.n_elements) == (sim.model.n_nodes, sim.model.n_elements)
    with pytest.raises(pl.InputError, match="different model"):
        other.load(good)
    sim.load(good)  # and the right model still takes it
    assert sim.state.steps == 10


def test_state_load_checks_values(tmp_path):
    sim, _ = _sim()
    sim.save(tmp_path / "s.npz")
    with np.load(tmp_path / "s.npz") as d:
        data = {k: d[k] for k in d.files}
    data["u"] = data["u"].copy()
    data["u"][3, 1] = np.nan
    np.savez(tmp_path / "nan.npz", **data)
    with pytest.raises(pl.InputError, match=r"1 non-finite value\(s\), first at node 3"):
        sim.load(tmp_path / "nan.npz")


@pytest.mark.parametrize(
    "key, value", [("grip_tool", 5), ("grip_tool", -2), ("grip_tool", 0.5), ("grip_at", np.nan)]
)
def test_state_load_checks_the_grip_state(tmp_path, key, value):
    """A saved grasp state names, per contact node, the tool holding it: a number past the model's
    tools went into the engine, which reads that tool's jaws by it (past the end of its array)."""
    sim, _ = _sim(tool=True)
    sim.save(tmp_path / "s.npz")
    with np.load(tmp_path / "s.npz") as d:
        data = {k: d[k] for k in d.files}
    assert data["grip_tool"].size > 0 and data["grip_at"].size == 3 * data["grip_tool"].size
    data[key] = data[key].astype(float)
    data[key].flat[0] = value
    np.savez(tmp_path / "bad.npz", **data)
    with pytest.raises(pl.InputError, match=r"grip state holds tool numbers outside -1\.\.0"):
        sim.load(tmp_path / "bad.npz")
    sim.load(tmp_path / "s.npz")  # the file as saved still loads


@pytest.mark.parametrize(
    "call, text",
    [
        (lambda s: s.run(steps=2**70), "expected 0 to"),
        (lambda s: s.run(steps=-1), "expected 0 to"),
        (lambda s: s.run(steps=2.5), "whole number"),
        (lambda s: s.run(steps="10"), "whole number"),
        (lambda s: s.run(until=float("nan")), "until = nan; expected a finite number"),
        (lambda s: s.run(until=float("inf")), "until = inf; expected a finite number"),
        (lambda s: s.run(until=1e30), "steps"),
        (lambda s: s.tool_force(5), "tool index 5"),
        (lambda s: s.set_tool_pose(-1, (0, 0, 0)), "tool index -1"),
        (lambda s: s.set_tool_pose(0, (0, 0, float("nan"))), "position"),
        (lambda s: s.solver.step(s.state, s.state.copy(), float("nan")), "dt"),
        (lambda s: s.state.set_displacements(np.zeros((3, 3))), "expected shape"),
        # Counts are whole numbers (a dict, a tuple, inf were Python's TypeError / OverflowError).
        (lambda s: s.relax(max_steps=(1, 0)), "max_steps = .*whole number"),
        (lambda s: s.relax(max_steps=1.5), "max_steps = 1.5; expected a whole number"),
        (lambda s: s.relax(increments=-float("inf")), "increments = -inf; expected a whole number"),
        (lambda s: s.relax(increments=True), "increments = True; expected a whole number"),
        (lambda s: s.relax(check_every={}), "check_every = .*whole number"),
        (lambda s: s.relax(check_every=0), "check_every = 0; expected 1 to"),
        (lambda s: pl.Simulation(s.model, check_every=1e300), "check_every = 1e\\+300; expected 1 to"),
        (lambda s: pl.Simulation(s.model, check_every=slice(1)), "check_every = .*whole number"),
    ],
)
def test_simulation_calls_with_bad_arguments(call, text):
    sim, _ = _sim(tool=True)
    with pytest.raises(pl.InputError, match=text):
        call(sim)
    assert sim.state.steps == 0  # nothing ran


def test_simulation_of_a_builder_and_node_ids_of_the_wrong_type():
    _, b = _sim()
    with pytest.raises(
        pl.InputError,
        match="ModelBuilder; expected a pliant Model; call "
        r"builder.finalize\(\) first",
    ):
        pl.Simulation(b)
    for ids, text in (
        ([1.5], "node id 1.5"),
        (["a"], "type <U1"),
        ([True], "type bool"),
        ([float("nan")], "node id nan"),
    ):
        with pytest.raises(pl.InputError, match=re.escape(text)):
            b.add_force(ids, (0, 0, 1))
    b.add_force(np.array([1.0, 2.0]), (0, 0, 1))  # integral floats are node ids


def test_slow_element_warning_matches_the_quality_tool():
    """The warning's element and factor agree with pliant.mesh.critical_time_steps, which computes
    h_min / √((λ + 2μ)/ρ) per element in NumPy (the engine's own per-element steps feed the
    warning); 3 significant digits, as printed."""
    # A 0.1 mm layer of cells among 2 cm ones (a jitter of 0.499 made such elements, by tangling
    # the mesh, until box_tets stopped letting its elements turn over).
    X, T = pl.mesh.grid_tets([0.0, 0.02, 0.04, 0.0401, 0.06, 0.1], [0.0, 0.01, 0.02], [0.0, 0.01, 0.02])
    mat = pl.NeoHookean(E=5e5, nu=0.45)
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(mat, density=1000.0)
    with pytest.warns(pl.PliantWarning) as rec:
        model = b.finalize("float64")
    dt = pl.mesh.critical_time_steps(X, T, pl.LinearElastic(mu=mat.mu, lam=mat.lam), 1000.0)
    worst = int(np.argmin(dt))
    text = str(rec[0].message)
    assert f"element {worst} limits" in text and model.dt_critical_element == worst
    assert f"{np.median(dt) / dt[worst]:.0f}x below" in text
    assert f"{dt[worst]:.3g} s" in text


def _builder_flag(sim, value):
    b = pl.ModelBuilder()
    b.add_mesh(*_two_cubes())
    b.set_material(pl.NeoHookean(E=1e6, nu=0.3), density=1000)
    b.nodal_pressure = value
    return b.finalize()


def _scene_flag(tmp_path, **flags):
    from pliant.runner import run_scene
    from pliant.scene import load_scene

    scene = tmp_path / "s.toml"
    scene.write_text(
        '[mesh]\nprimitive = "box"\n[[material]]\ntype = "neo-hookean"\nE = 1e4\nnu = 0.3\n'
        "density = 1000.0\n[solver]\nduration = 0.001\n"
    )
    return run_scene(load_scene(scene), tmp_path / "out", **flags)


def _validation_flag(tmp_path, quick):
    from pliant.validate import run_validation

    return run_validation(tmp_path / "v", quick=quick)


def _sweep_flag(tmp_path, **flags):
    from pathlib import Path

    from pliant.sweep import load_sweep, run_sweep

    spec = load_sweep(Path(__file__).parents[1] / "examples" / "cantilever_sweep.toml")
    return run_sweep(spec, tmp_path / "out", **flags)


@pytest.mark.parametrize("bad", ["false", np.array([True, False]), None, 2.0])
@pytest.mark.parametrize(
    "call, name",
    [
        (lambda s, b, tmp: pl.Simulation(s.model, allow_unstable=b), "allow_unstable"),
        (lambda s, b, tmp: s.relax(strict=b), "strict"),
        (lambda s, b, tmp: pl.haptics.HapticLoop(s, realtime=b), "realtime"),
        (lambda s, b, tmp: pl.haptics.HapticLoop(s, passivity=b), "passivity"),
        (lambda s, b, tmp: _builder_flag(s, b), "nodal_pressure"),
        (lambda s, b, tmp: _scene_flag(tmp, progress=b), "progress"),
        (lambda s, b, tmp: _scene_flag(tmp, allow_unstable=b), "allow_unstable"),
        (lambda s, b, tmp: _validation_flag(tmp, b), "quick"),
        (lambda s, b, tmp: _sweep_flag(tmp, retry_failed=b), "retry_failed"),
        (lambda s, b, tmp: _sweep_flag(tmp, analyze=b), "analyze"),
        (lambda s, b, tmp: _sweep_flag(tmp, progress=b), "progress"),
    ],
)
def test_flags_are_true_or_false(tmp_path, call, name, bad):
    """A flag given a string, an array, None or 2.0 is named before anything runs: bool() made
    "false" True (nodal_pressure = "no" switched T4ANP on, strict = "no" kept raising), and an
    array was numpy's "truth value of an array is ambiguous", naming no argument."""
    sim, _ = _sim(tool=True)
    with pytest.raises(pl.InputError, match=rf"{name} = .*expected True or False"):
        call(sim, bad, tmp_path)
    assert sim.state.steps == 0 and not (tmp_path / "out").exists() and not (tmp_path / "v").exists()


def test_a_relaxation_that_inverts_says_to_give_more_increments():
    """A 5 cm column's top pressed down 8 mm (1.6 of its 5 mm elements) in one increment of a
    quasi-static solve: the prescribed nodes move there at once and an element inverts, whatever
    Δt (the message said only "reduce dt or the loads"). The message says to give increments; with
    10 the same solve converges, to the equilibrium 20 increments reach (a hyperelastic equilibrium
    does not depend on the path: the same displacements to 1e-4 of the push, the tolerance's order)."""
    X, T = pl.mesh.box_tets((0.02, 0.02, 0.05), (4, 4, 10))
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(pl.NeoHookean(E=1e4, nu=0.3), density=1000.0)
    b.fix(np.nonzero(X[:, 2] < 1e-9)[0])
    b.prescribe(np.nonzero(X[:, 2] > 0.05 - 1e-9)[0], [0, 0, -0.008], curve=pl.Ramp(1.0))
    model = b.finalize("float64")
    with pytest.raises(pl.InstabilityError, match=r"each of the 1 increment\(s\) .* give more increments"):
        pl.Simulation(model).relax()
    u = []
    for n in (10, 20):
        sim = pl.Simulation(model)
        assert sim.relax(increments=n).converged
        u.append(sim.state.displacements)
    np.testing.assert_allclose(u[0], u[1], atol=1e-4 * 0.008)
