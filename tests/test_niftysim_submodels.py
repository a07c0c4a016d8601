"""NiftySim <SubModel>s: several models assembled into one (user guide v2.4 §3.7).

Reference: a box cut into two sub-models, each with its own numbering, material and constraint,
and merged at their shared nodes (SubModelNodeMergerDistance), is the same model as the box
written whole: its nodes, and its displacements under the same loads, to the bit."""

from __future__ import annotations

import numpy as np
import pytest

import pliant as pl
from pliant.io.niftysim import NiftySimError, load_niftysim
from pliant.mesh import box_tets

SIZE, CELLS = (0.02, 0.02, 0.04), (2, 2, 4)


def _nodes(X):
    return "\n".join(" ".join(repr(float(v)) for v in x) for x in X)


def _ints(a):
    return " ".join(str(int(v)) for v in np.ravel(a))


def _set(elems, mu, first=None):
    text = _ints(elems) if first is None else str(first)
    return (
        f'<ElementSet Size="{len(elems)}">{text}<Material Type="NH">'
        f'<ElasticParams NumParams="2">{mu} {10 * mu}</ElasticParams></Material></ElementSet>'
    )


def _fix(ids):
    return f'<Constraint DOF="all" NumNodes="{len(ids)}" Type="Fix"><Nodes>{_ints(ids)}</Nodes></Constraint>'


def _force(ids, fz):
    return (
        f'<Constraint DOF="2" LoadShape="RAMP" NumNodes="{len(ids)}" Type="Force"><Nodes>{_ints(ids)}</Nodes>'
        f'<Magnitudes Type="UNIFORM">{fz}</Magnitudes></Constraint>'
    )


SYSTEM = (
    "<SystemParams><TimeStep>1e-5</TimeStep><TotalTime>0.01</TotalTime>"
    "<DampingCoeff>50</DampingCoeff><Density>1000</Density></SystemParams>"
)


def _mesh(X, T, etype="T4"):
    return (
        f'<Nodes DOF="3" NumNodes="{len(X)}">{_nodes(X)}</Nodes>'
        f'<Elements NumEls="{len(T)}" Type="{etype}">{_ints(T)}</Elements>'
    )


def halves():
    """The box, its elements sorted lower half first, and each half as its own mesh."""
    X, T = box_tets(SIZE, CELLS)
    zc = X[T].mean(axis=1)[:, 2]
    T = np.concatenate([T[zc < SIZE[2] / 2], T[zc >= SIZE[2] / 2]])
    parts = []
    for sel in (slice(0, len(T) // 2), slice(len(T) // 2, None)):
        used, local = np.unique(T[sel], return_inverse=True)
        parts.append((X[used], local.reshape(-1, 4), used))
    return X, T, parts


def test_two_merged_submodels_are_the_whole_box(tmp_path):
    X, T, ((X0, T0, g0), (X1, T1, g1)) = halves()
    bottom, top = np.nonzero(X[:, 2] < 1e-9)[0], np.nonzero(X[:, 2] > SIZE[2] - 1e-9)[0]
    whole = tmp_path / "whole.xml"
    whole.write_text(
        f"<Model>{_mesh(X, T)}{_set(range(len(T0)), 1000, 0)}{_set(range(len(T0), len(T)), 3000, len(T0))}"
        f"{_fix(bottom)}{_force(top, -0.01)}{SYSTEM}</Model>"
    )
    local = {int(g): i for i, g in enumerate(g0)}, {int(g): i for i, g in enumerate(g1)}
    sub = tmp_path / "sub.xml"
    sub.write_text(
        "<Model><SubModelNodeMergerDistance>1e-6</SubModelNodeMergerDistance>"
        f"<SubModel>{_mesh(X0, T0)}{_set(range(len(T0)), 1000)}"
        f"{_fix([local[0][n] for n in bottom])}</SubModel>"
        f'<SubModel>{_mesh(X1, T1)}<ElementSet Size="all"><Material Type="NH">'
        '<ElasticParams NumParams="2">3000 30000</ElasticParams></Material></ElementSet>'
        f"{_force([local[1][n] for n in top], -0.01)}{SYSTEM}</SubModel>{SYSTEM}</Model>"
    )
    a, b = load_niftysim(whole), load_niftysim(sub)
    assert b.builder.n_nodes == len(X)  # the interface's nodes merged
    # The merged numbering: sub-model 0's nodes, then sub-model 1's new ones.
    assert np.array_equal(b.builder.nodes[: len(X0)], X0)
    order = [int(np.argmin(np.linalg.norm(X - x, axis=1))) for x in b.builder.nodes]
    assert sorted(order) == list(range(len(X)))
    ua, ub = (_run(s) for s in (a, b))
    assert np.abs(ub[:, 2]).max() > 1e-5  # it deformed (the top pulled down by 0.1 mm at least)
    # Same elements in the same order and sets: the engine runs the same arrays, so the same bits.
    assert np.array_equal(ua[order], ub)


def _run(scene):
    sim = pl.Simulation(scene.builder.finalize("float64"), dt=scene.dt, damping=scene.builder.damping)
    sim.run(until=scene.duration)
    return sim.displacements


def test_unmerged_submodels_are_separate_bodies(tmp_path):
    """Without a merger distance, each sub-model is a body of its own: two boxes side by side,
    each fixed at its base and pulled at its top, deform each like the box alone."""
    X, T = box_tets(SIZE, CELLS)
    shift = np.array([0.05, 0.0, 0.0])
    bottom, top = np.nonzero(X[:, 2] < 1e-9)[0], np.nonzero(X[:, 2] > SIZE[2] - 1e-9)[0]
    body = f"{_set(range(len(T)), 1000, 0)}{_fix(bottom)}{_force(top, -0.01)}"
    one = tmp_path / "one.xml"
    one.write_text(f"<Model>{_mesh(X, T)}{body}{SYSTEM}</Model>")
    two = tmp_path / "two.xml"
    two.write_text(
        f"<Model><SubModel>{_mesh(X, T)}{body}</SubModel>"
        f"<SubModel>{_mesh(X + shift, T)}{body}</SubModel>{SYSTEM}</Model>"
    )
    s = load_niftysim(two)
    assert s.builder.n_nodes == 2 * len(X) and s.builder.n_elements == 2 * len(T)
    u1, u2 = _run(load_niftysim(one)), _run(s)
    # Each body as the box alone (the engine orders two bodies' elements differently from one's:
    # equal to round-off, not to the bit).
    for part in (u2[: len(X)], u2[len(X) :]):
        np.testing.assert_allclose(part, u1, rtol=0, atol=1e-9 * np.abs(u1).max())


def test_a_submodel_pressure_on_all_faces_is_its_own_surface(tmp_path):
    X, T = box_tets(SIZE, CELLS)
    shift = np.array([0.05, 0.0, 0.0])
    pressure = (
        '<Constraint LoadShape="RAMP" NumFaces="all" Type="Pressure"><Magnitude>10</Magnitude></Constraint>'
    )
    f = tmp_path / "p.xml"
    f.write_text(
        f"<Model><SubModel>{_mesh(X, T)}{_set(range(len(T)), 1000, 0)}</SubModel>"
        f"<SubModel>{_mesh(X + shift, T)}{_set(range(len(T)), 1000, 0)}{pressure}</SubModel>{SYSTEM}</Model>"
    )
    ((faces, p, _),) = load_niftysim(f).builder._pressures
    assert faces.min() >= len(X)  # sub-model 1's nodes only
    from pliant.mesh.topology import boundary_faces

    assert len(faces) == len(boundary_faces(T)[0]) and np.all(p == 10)


@pytest.mark.parametrize(
    "body, key",
    [
        ("<ContactPlate/>", r"SubModel\[1\]/ContactPlate"),
        (f"{_fix([999])}", r"SubModel\[1\]/Constraint\[0\]"),
        ('<ElementSet Size="99">0<Material Type="NH"/></ElementSet>', r"SubModel\[1\]/ElementSet\[0\]"),
    ],
)
def test_bad_submodels_are_refused_naming_them(tmp_path, body, key):
    X, T = box_tets(SIZE, CELLS)
    f = tmp_path / "bad.xml"
    f.write_text(
        f"<Model><SubModel>{_mesh(X, T)}</SubModel><SubModel>{_mesh(X, T)}{body}</SubModel>{SYSTEM}</Model>"
    )
    with pytest.raises(NiftySimError, match=key):
        load_niftysim(f)


def test_submodels_of_two_element_types_are_refused(tmp_path):
    X, T = box_tets(SIZE, CELLS)
    f = tmp_path / "mixed.xml"
    f.write_text(
        f"<Model><SubModel>{_mesh(X, T)}</SubModel>"
        f"<SubModel>{_mesh(X, T, 'T4ANP')}</SubModel>{SYSTEM}</Model>"
    )
    with pytest.raises(NiftySimError, match="one element type"):
        load_niftysim(f)


def _shells(kind, facets, mu, listed=None):
    """<ShellElements> of ``kind`` with ``facets`` and one NeoHookean set (μ [Pa]) of them all, or
    of those ``listed``."""
    members = 'Size="all">' if listed is None else f'Size="{len(listed)}">{_ints(listed)}'
    return (
        f'<ShellElements Type="{kind}" NumEls="{len(facets)}">{_ints(facets)}</ShellElements>'
        f'<ShellElementSet {members}<Material Type="NeoHookean">{mu}<Density>10</Density>'
        "<Thickness>0.001</Thickness></Material></ShellElementSet>"
    )


def _sheet(x0):
    """Two sheets' worth of nodes: a 2 × 2 cm square at height 3 cm from x = x0 (4 nodes)."""
    return np.array([[0, 0, 0.03], [0.02, 0, 0.03], [0.02, 0.02, 0.03], [0, 0.02, 0.03]]) + [x0, 0, 0]


def test_membranes_of_sub_models_are_the_model_written_whole(tmp_path):
    """<ShellElements> with their <ShellElementSet>s in sub-models (NiftySim's two_cubes_sheet.xml
    has a membrane-only sub-model, NumEls="0"): a cube, a sheet of two T3 triangles of one material
    and a sheet of one Q4 facet of another, as three sub-models, are the model written whole — its
    nodes, its membranes (the second sheet's set offset past the first's triangles, the Q4 split as
    the whole model splits it) and its displacements under gravity, to the bit. --ignore
    ShellElements skips them with one warning, and the solid runs alone."""
    X, T = pl.mesh.box_tets((0.02, 0.02, 0.02), (1, 1, 1))
    n = len(X)
    nh = '<Material Type="NH"><ElasticParams NumParams="2">1000 20000</ElasticParams></Material>'
    base = np.nonzero(X[:, 2] == 0)[0]
    edge = lambda off: _ints(off + np.array([0, 3]))  # noqa: E731  each sheet held at its x = x0 edge
    fix = lambda ids: f'<Constraint DOF="all" Type="Fix" NumNodes="2"><Nodes>{ids}</Nodes></Constraint>'  # noqa: E731
    system = (
        "<SystemParams><TimeStep>1e-4</TimeStep><TotalTime>0.002</TotalTime><DampingCoeff>10"
        "</DampingCoeff><Density>1000</Density></SystemParams>"
    )
    gravity = (
        '<Constraint Type="Gravity" LoadShape="STEP" NumNodes="all"><AccelerationMagnitude>9.81'
        "</AccelerationMagnitude><AccelerationDirection>0 0 -1</AccelerationDirection></Constraint>"
    )
    tri, quad = np.array([[0, 1, 2], [0, 2, 3]]), np.array([[0, 1, 2, 3]])
    cube = f'{_mesh(X, T)}<ElementSet Size="all">{nh}</ElementSet>{_fix(base)}'
    sheets = np.vstack([_sheet(0.05), _sheet(0.1)])
    whole_X = np.vstack([X, sheets])
    whole = (
        f"<Model>{_mesh(whole_X, T)}"
        f'<ElementSet Size="all">{nh}</ElementSet>{_fix(base)}{fix(edge(n))}{fix(edge(n + 4))}{gravity}'
        f'<ShellElements Type="T3" NumEls="4">{_ints(np.vstack([tri + n, tri + n + 4]))}'
        "</ShellElements>"
        '<ShellElementSet Size="2">0 1<Material Type="NeoHookean">500<Density>10</Density><Thickness>0.001'
        "</Thickness></Material></ShellElementSet>"
        '<ShellElementSet Size="2">2 3<Material Type="NeoHookean">800<Density>10</Density><Thickness>0.001'
        f"</Thickness></Material></ShellElementSet>{system}</Model>"
    )
    no_tets = '<Elements NumEls="0" Type="T4"></Elements>'
    sheet = lambda x0: f'<Nodes DOF="3" NumNodes="4">{_nodes(_sheet(x0))}</Nodes>{no_tets}'  # noqa: E731
    subs = (
        f"<Model><SubModel>{cube}</SubModel>"
        f'<SubModel>{sheet(0.05)}<ElementSet Size="all">{nh}</ElementSet>{fix(edge(0))}'
        f"{_shells('T3', tri, 500, listed=[0, 1])}</SubModel>"
        f'<SubModel>{sheet(0.1)}<ElementSet Size="all">{nh}</ElementSet>{fix(edge(0))}'
        f"{_shells('Q4', quad, 800)}</SubModel>{gravity}{system}</Model>"
    )
    runs = {}
    for name, xml in (("whole.xml", whole), ("subs.xml", subs)):
        p = tmp_path / name
        p.write_text(xml)
        sc = load_niftysim(p)
        assert sc.builder.n_membranes == 4 and sc.builder.n_nodes == n + 8
        sim = pl.Simulation(sc.builder.finalize("float64"), dt=sc.dt)
        sim.run(steps=20)
        runs[name] = sim.displacements
    assert np.array_equal(runs["whole.xml"], runs["subs.xml"])
    assert np.abs(runs["subs.xml"][n:, 2]).max() > 1e-6  # the sheets sag
    sc = load_niftysim(tmp_path / "subs.xml", ignore=("ShellElements",))
    assert sc.builder.n_membranes == 0
    assert sum("ShellElements" in w for w in sc.warnings) == 1
    sim = pl.Simulation(sc.builder.finalize("float64"), dt=sc.dt)
    sim.run(steps=5)
    assert np.isfinite(sim.displacements).all()


@pytest.mark.parametrize(
    "shells, key, message",
    [
        ('<ShellElements Type="T3">0 1 2</ShellElements>', "SubModel[1]/ShellElements", "expected one"),
        (_shells("T3", [[0, 1, 9]], 500), "SubModel[1]/ShellElements", "refers to node 9"),
        (_shells("T4", [[0, 1, 2]], 500), "SubModel[1]/ShellElements", "expected T3, Q4 or SURFACE"),
        (
            _shells("T3", [[0, 1, 2]], 500, listed=[3]),
            "SubModel[1]/ShellElementSet[0]",
            r"element index 3 out of range 0\.\.0",
        ),
    ],
)
def test_a_sub_models_bad_membranes_are_named(tmp_path, shells, key, message):
    X, T = pl.mesh.box_tets((0.02, 0.02, 0.02), (1, 1, 1))
    nh = '<Material Type="NH"><ElasticParams NumParams="2">1000 20000</ElasticParams></Material>'
    xml = (
        f'<Model><SubModel>{_mesh(X, T)}<ElementSet Size="all">{nh}</ElementSet></SubModel>'
        f'<SubModel><Nodes DOF="3" NumNodes="4">{_nodes(_sheet(0.05))}</Nodes>'
        f'<Elements NumEls="0" Type="T4"></Elements><ElementSet Size="all">{nh}</ElementSet>{shells}'
        f"</SubModel>{SYSTEM}</Model>"
    )
    p = tmp_path / "bad.xml"
    p.write_text(xml)
    with pytest.raises(NiftySimError, match=message) as e:
        load_niftysim(p)
    assert e.value.key == key
    # the model's own membranes beside a sub-model's: one place expected
    p.write_text(xml.replace("<SubModel>", _shells("T3", [[0, 1, 2]], 500) + "<SubModel>", 1))
    if "expected one" not in message:
        with pytest.raises(NiftySimError, match="in the model and in a sub-model"):
            load_niftysim(p)
