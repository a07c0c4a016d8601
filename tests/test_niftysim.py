"""NiftySim import: the BSD test model ball_ball.xml and small models written here."""

import xml.etree.ElementTree as ET
from pathlib import Path

import re

import numpy as np
import pytest
from typer.testing import CliRunner

import pliant as pl
from pliant.cli import app
from pliant.io.niftysim import NiftySimError, load_niftysim

BALLS = Path(__file__).parent / "data" / "niftysim_ball_ball.xml"
runner = CliRunner()


def test_deformable_and_self_collision_map_to_soft_contact(tmp_path):
    """DoDeformableCollision: every pair of bodies, frictionless (NiftySim's mesh-based contact);
    DoSelfCollision: each body with itself; a value that is not 0 or 1 is refused by name."""
    sc = load_niftysim(BALLS)
    c = sc.builder.soft_contact
    assert (c.pairs, c.self_contact, c.mu_s, c.mu_k) == (None, False, 0.0, 0.0)
    xml = BALLS.read_text().replace(
        "<DoDeformableCollision>", "<DoSelfCollision>1</DoSelfCollision><DoDeformableCollision>", 1
    )
    xml = xml.replace("\n      1\n    </DoDeformableCollision>", "0</DoDeformableCollision>")
    p = tmp_path / "self.xml"
    p.write_text(xml)
    c = load_niftysim(p).builder.soft_contact
    assert (c.pairs, c.self_contact) == ((), True)
    p.write_text(
        BALLS.read_text().replace("\n      1\n    </DoDeformableCollision>", "x</DoDeformableCollision>")
    )
    r = runner.invoke(app, ["run", str(p), "-o", str(tmp_path / "o")])
    assert r.exit_code == 2 and "DoDeformableCollision" in r.output


def test_ball_ball_import_and_driven_nodes_follow_ramp():
    """Parsed independently here with ElementTree: node count, element count, NH (μ, K),
    density, damping, Δt; the driven nodes follow RAMP: u = magnitude · t / T exactly."""
    root = ET.parse(BALLS).getroot()
    cons = [
        (np.array(c.find("Nodes").text.split(), int), float(c.find("Magnitudes").text))
        for c in root.findall("Constraint")
    ]
    sc = load_niftysim(BALLS)
    b = sc.builder
    assert (b.n_nodes, b.n_elements) == (556, 1578)
    (s,) = b.sets
    assert isinstance(s.material, pl.NeoHookean) and (s.material.mu, s.material.K) == (100.0, 800.0)
    assert s.density == 20.0 and b.damping == 0.5 and sc.dt == 1e-4 and sc.duration == 1.0
    model = b.finalize("float64")
    sim = pl.Simulation(model, dt=sc.dt)
    sim.run(steps=150)  # t = 0.015 s: the balls (gap 0.02) have not met yet
    u = sim.displacements
    for ids, mag in cons:
        assert np.allclose(u[ids, 0], mag * sim.time / sc.duration, rtol=1e-12, atol=1e-15)
    assert np.all(np.isfinite(u))


def _cube_xml(
    extra_constraint="",
    material='<Material Type="NH"><ElasticParams NumParams="2">1000 20000</ElasticParams></Material>',
    elements_type="T4",
):
    X, T = pl.mesh.box_tets((0.1, 0.1, 0.1), (2, 2, 2))
    left = np.nonzero(X[:, 0] < 1e-9)[0]
    right = np.nonzero(X[:, 0] > 0.1 - 1e-9)[0]
    fmt = lambda a: " ".join(str(v) for v in np.ravel(a))  # noqa: E731
    xml = f"""<?xml version="1.0"?>
<Model>
  <Nodes DOF="3" NumNodes="{len(X)}">{fmt(X)}</Nodes>
  <Elements NumEls="{len(T)}" Type="{elements_type}">{fmt(T)}</Elements>
  <ElementSet Size="{len(T)}">{material}0</ElementSet>
  <Constraint DOF="all" NumNodes="{len(left)}" Type="Fix"><Nodes>{fmt(left)}</Nodes></Constraint>
  <Constraint DOF="0" LoadShape="POLY345" NumNodes="{len(right)}" Type="Disp">
    <Nodes>{fmt(right)}</Nodes><Magnitudes Type="UNIFORM">0.01</Magnitudes></Constraint>
  <Constraint DOF="2" LoadShape="RAMP" NumNodes="{len(right)}" Type="Force">
    <Nodes>{fmt(right)}</Nodes>
    <Magnitudes Type="DIFFORM">{fmt(np.linspace(-1, -2, len(right)))}</Magnitudes></Constraint>
  {extra_constraint}
  <SystemParams><TimeStep>1e-4</TimeStep><TotalTime>0.05</TotalTime><DampingCoeff>20</DampingCoeff>
    <Density>1000</Density></SystemParams>
</Model>"""
    return X, T, left, right, xml


@pytest.mark.parametrize("etype", ["T4", "T4ANP"])
def test_small_model_matches_the_same_model_built_through_the_api(tmp_path, etype):
    """The importer maps NH, Fix, Disp POLY345 and Force RAMP (DIFFORM), and T4ANP to average
    nodal pressure, to the builder exactly: the same model built by hand gives the same bits."""
    X, T, left, right, xml = _cube_xml(elements_type=etype)
    p = tmp_path / "cube.xml"
    p.write_text(xml)
    nh = pl.NeoHookean(mu=1000, K=20000)
    same_motion_as_by_hand(load_niftysim(p), X, T, left, right, [(nh, None)], anp=etype == "T4ANP")


def same_motion_as_by_hand(sc, X, T, left, right, materials, anp=False):
    """The imported scene sc and _cube_xml's model built with the API (materials: (material,
    elements or None) pairs) run to the same bits over 0.05 s."""
    sim_a = pl.Simulation(sc.builder.finalize("float64"), dt=sc.dt)
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    for material, elements in materials:
        b.set_material(material, density=1000, elements=elements)
    b.damping = 20
    b.nodal_pressure = anp
    b.fix(left)
    b.prescribe(right, 0.01, "x", curve=pl.SmoothRamp(0.05))
    f = np.zeros((len(right), 3))
    f[:, 2] = np.linspace(-1, -2, len(right))
    b.add_force(right, f, curve=pl.Ramp(0.05))
    sim_b = pl.Simulation(b.finalize("float64"), dt=1e-4)
    sim_a.run(until=0.05)
    sim_b.run(until=0.05)
    assert np.abs(sim_a.displacements).max() > 1e-3
    assert np.array_equal(sim_a.displacements, sim_b.displacements)


def test_element_sets_listed_after_their_material_are_read(tmp_path):
    """The user guide's <ElementSet>s list their elements after the <Material> child; only the
    text before it was read, so a set of listed elements became the first Size elements (or a
    clash with the next set). Two sets, even and odd elements, each with its Neo-Hookean, run to
    the same bits as the model built with the API; an element in no set is named."""
    X, T, left, right, xml = _cube_xml()
    nh = '<Material Type="NH"><ElasticParams NumParams="2">{} {}</ElasticParams></Material>'
    even, odd = np.arange(0, len(T), 2), np.arange(1, len(T), 2)
    fmt = lambda a: " ".join(str(v) for v in np.ravel(a))  # noqa: E731
    sets = (
        f'<ElementSet Size="{even.size}">\n  {nh.format(1000, 20000)}\n  {fmt(even)}\n</ElementSet>\n'
        f'<ElementSet Size="{odd.size}">\n  {nh.format(3000, 60000)}\n  {fmt(odd)}\n</ElementSet>'
    )
    one = f'<ElementSet Size="{len(T)}">{nh.format(1000, 20000)}0</ElementSet>'
    assert one in xml
    p = tmp_path / "two.xml"
    p.write_text(xml.replace(one, sets))
    materials = [(pl.NeoHookean(mu=1000, K=20000), even), (pl.NeoHookean(mu=3000, K=60000), odd)]
    same_motion_as_by_hand(load_niftysim(p), X, T, left, right, materials)
    # A sweep's override of one listed element (the text after <Material>) swaps two elements'
    # materials: element 1 joins the first set, element 0 the second.
    swapped = load_niftysim(p, overrides={"ElementSet[0][0]": 1, "ElementSet[1][0]": 0})
    assert [s.elements.tolist()[:2] for s in swapped.builder.sets] == [[1, 2], [0, 3]]
    q = tmp_path / "missing.xml"
    short = (
        f'<ElementSet Size="{even.size}">{nh.format(1000, 20000)} {fmt(even)}</ElementSet>'
        f'<ElementSet Size="{odd.size - 1}">{nh.format(3000, 60000)} {fmt(odd[:-1])}</ElementSet>'
    )
    q.write_text(xml.replace(one, short))
    with pytest.raises(pl.InputError, match=f"element {odd[-1]} is in no <ElementSet>"):
        load_niftysim(q)


@pytest.mark.parametrize("etype", ["T4", "T4ANP"])
def test_elements_given_in_either_orientation_run_as_niftysim_runs_them(tmp_path, etype):
    """NiftySim takes |det J| (tledElementT4::ComputeDhDx): a model with every third element's
    nodes given in the other orientation was refused as inverted. Imported, those elements are
    turned over, with a warning, and the model moves as the one given positively: to 1e-12 of the
    largest displacement (float64; the element's corner sums run in another order, round-off)."""
    X, T, left, right, xml = _cube_xml(elements_type=etype)
    flipped = T.copy()
    flipped[::3, [0, 1]] = flipped[::3, [1, 0]]
    fmt = lambda a: " ".join(str(v) for v in np.ravel(a))  # noqa: E731
    p, q = tmp_path / "given.xml", tmp_path / "flipped.xml"
    p.write_text(xml)
    q.write_text(xml.replace(f">{fmt(T)}</Elements>", f">{fmt(flipped)}</Elements>"))
    sims = []
    for path in (p, q):
        sc = load_niftysim(path)
        sims.append(pl.Simulation(sc.builder.finalize("float64"), dt=sc.dt))
        sims[-1].run(until=0.05)
    assert not load_niftysim(p).warnings
    assert any(
        f"{len(T[::3])} of {len(T)} element(s) given with negative orientation" in w for w in sc.warnings
    )
    u, v = sims[0].displacements, sims[1].displacements
    assert np.abs(u).max() > 1e-3 and np.abs(u - v).max() <= 1e-12 * np.abs(u).max()


def test_an_ignored_material_names_its_element_set(tmp_path):
    """--ignore skips a feature a run can do without; an unsupported material cannot be skipped (its
    elements would have none): the import names the set and the count instead of a later
    "element 0 has no material" in the API's words."""
    *_, xml = _cube_xml(
        material='<Material Type="HGO"><ElasticParams NumParams="2">1 2</ElasticParams></Material>'
    )
    p = tmp_path / "m.xml"
    p.write_text(xml)
    with pytest.raises(NiftySimError, match=r"ElementSet\[0\]/Material.*48 element\(s\) without a material"):
        load_niftysim(p, ignore=("Material Type=HGO",))


@pytest.mark.parametrize(
    "kwargs, name",
    [
        (dict(elements_type="H20"), "Elements Type=H20"),
        (
            dict(material='<Material Type="HGO"><ElasticParams NumParams="2">1 2</ElasticParams></Material>'),
            "Material Type=HGO",
        ),
        (
            dict(
                extra_constraint='<Constraint DOF="0" LoadShape="SINE" NumNodes="1" Type="Disp">'
                '<Nodes>0</Nodes><Magnitudes Type="UNIFORM">1</Magnitudes></Constraint>'
            ),
            "LoadShape=SINE",
        ),
        (
            dict(
                extra_constraint='<Constraint DOF="0" LoadShape="RAMP" NumNodes="1" Type="Disp">'
                '<Nodes>0</Nodes><Magnitudes Type="FILE">u.txt</Magnitudes></Constraint>'
            ),
            "Magnitudes Type=FILE",
        ),
        (dict(extra_constraint="<ContactSurface><Friction/></ContactSurface>"), "ContactSurface/Friction"),
        (
            dict(
                extra_constraint="<ContactCylinder><Origin>0 0 0</Origin><Axis>0 0 1</Axis><Radius>0.01"
                "</Radius><Length>0.1</Length><RadChange>0.01</RadChange></ContactCylinder>"
            ),
            "ContactCylinder/RadChange",
        ),
    ],
)
def test_unsupported_features_are_refused_by_name(tmp_path, kwargs, name):
    *_, xml = _cube_xml(**kwargs)
    p = tmp_path / "m.xml"
    p.write_text(xml)
    with pytest.raises(NiftySimError, match=name.replace("=", "=")):
        load_niftysim(p)


def test_malformed_xml(tmp_path):
    p = tmp_path / "bad.xml"
    p.write_text("<Model><Nodes>1 2</Nodes>")
    r = runner.invoke(app, ["run", str(p), "-o", str(tmp_path / "o")])
    assert r.exit_code == 2 and "XML" in r.output


@pytest.mark.parametrize(
    "sub, says",
    [
        ("<SubMesh>789 2000</SubMesh>", "SubMesh[1]"),  # past the 1,578 elements
        ("<SubMesh>1578 789</SubMesh>", "SubMesh[1]"),  # reversed
        ("<SubMesh>a b</SubMesh>", "two integers"),
        ("<SubMesh>700 1578</SubMesh>", "overlaps SubMesh[0]"),
    ],
)
def test_submesh_ranges_are_checked(tmp_path, sub, says):
    """ball_ball.xml's <SubMesh> element ranges: a malformed one is an error naming it (exit 2);
    one that cuts through a connected ball runs with a warning (bodies come from connectivity)."""
    p = tmp_path / "bad.xml"
    p.write_text(BALLS.read_text().replace("<SubMesh>789 1578</SubMesh>", sub))
    r = runner.invoke(app, ["run", str(p), "-o", str(tmp_path / "o")])
    assert r.exit_code == 2 and says in r.output, r.output


def test_submesh_that_splits_a_body_warns(tmp_path):
    xml = BALLS.read_text()
    assert "<SubMesh>0 789</SubMesh>" in xml and "<SubMesh>789 1578</SubMesh>" in xml
    assert not any("SubMesh" in w for w in load_niftysim(BALLS).warnings)  # one range per ball
    p = tmp_path / "split.xml"
    p.write_text(xml.replace("<SubMesh>0 789</SubMesh>", "<SubMesh>0 700</SubMesh>"))
    (w,) = [w for w in load_niftysim(p).warnings if "SubMesh" in w]
    assert "SubMesh[0] (elements 0 to 699)" in w


def _poly345(tr):
    return tr**3 * (10 - 15 * tr + 6 * tr**2)  # NiftySim user guide v2.4, eq. 1


def test_contact_plate_moves_and_presses_only_its_slave_nodes(tmp_path):
    """A ContactPlate (normal (b − a) × (c − a) = −z) above a cube moves down by 6 mm with the
    POLY345 profile; only the listed SlvNodes (top nodes with x < 0.05) are kept out of it."""
    fmt = lambda a: " ".join(str(v) for v in np.ravel(a))  # noqa: E731
    X, T = pl.mesh.box_tets((0.1, 0.1, 0.1), (4, 4, 4))
    top = np.nonzero(X[:, 2] > 0.1 - 1e-9)[0]
    slaves = top[X[top, 0] < 0.05 - 1e-9]
    bottom = np.nonzero(X[:, 2] < 1e-9)[0]
    a = np.array([-0.05, -0.05, 0.101])
    xml = f"""<Model>
  <Nodes DOF="3" NumNodes="{len(X)}">{fmt(X)}</Nodes>
  <Elements NumEls="{len(T)}" Type="T4">{fmt(T)}</Elements>
  <ElementSet Size="all"><Material Type="NH"><ElasticParams NumParams="2">3000 30000</ElasticParams>
    </Material></ElementSet>
  <Constraint DOF="all" NumNodes="{len(bottom)}" Type="Fix"><Nodes>{fmt(bottom)}</Nodes></Constraint>
  <ContactPlate><a>{fmt(a)}</a><b>{fmt(a + [0, 0.2, 0])}</b><c>{fmt(a + [0.2, 0, 0])}</c>
    <Disp>0 0 -0.007</Disp><SlvNodes NumNodes="{len(slaves)}">{fmt(slaves)}</SlvNodes></ContactPlate>
  <SystemParams><TimeStep>1e-4</TimeStep><TotalTime>0.5</TotalTime><DampingCoeff>50</DampingCoeff>
    <Density>1000</Density></SystemParams>
</Model>"""
    p = tmp_path / "plate.xml"
    p.write_text(xml)
    sc = load_niftysim(p)
    (tool,) = sc.builder.tools
    # Geometry: the plate's surface at time t is a + s(t/T) d; 1 mm on its normal side is outside.
    for t in (0.0, 0.1, 0.25, 0.5):
        x = a + [0.1, 0.1, 0] + _poly345(t / 0.5) * np.array([0, 0, -0.007])
        phi = tool.signed_distance(np.array([x, x - [0, 0, 0.001]]), t)
        np.testing.assert_allclose(phi, [0.0, 0.001], atol=1e-4 * 0.007)  # keyframe sampling
    sim = pl.Simulation(sc.builder.finalize("float64"), dt=sc.dt)
    sim.run(until=0.5)
    z = sim.positions[:, 2]
    assert z[slaves].max() <= 0.094 + 1e-9  # the slaves are pressed to the plate
    assert z[top[X[top, 0] > 0.1 - 1e-9]].min() > 0.094 + 1e-4  # others pass through it
    assert sim.tool_force(0)[0][2] > 0  # the cube pushes the plate up


def test_contact_cylinder_and_probe_geometry(tmp_path):
    """ContactCylinder / ContactUSProbe: Origin at one end, unit Axis, Radius, Length; the probe's
    hemispherical tip is centred at Origin + Length·Axis."""
    *_, xml = _cube_xml(
        extra_constraint="""
  <ContactCylinder><Origin>0.3 0 0</Origin><Axis>0 0 2</Axis><Radius>0.02</Radius>
    <Length>0.1</Length></ContactCylinder>
  <ContactUSProbe><Origin>0.5 0 0</Origin><Axis>1 0 0</Axis><Radius>0.01</Radius>
    <Length>0.05</Length><OrigDisp>0 0.1 0</OrigDisp><RadChange>0</RadChange></ContactUSProbe>"""
    )
    p = tmp_path / "tools.xml"
    p.write_text(xml)
    cyl, probe = load_niftysim(p).builder.tools
    pts = np.array([[0.32, 0, 0.05], [0.3, 0, 0.11], [0.31, 0, 0.05]])
    np.testing.assert_allclose(cyl.signed_distance(pts), [0.0, 0.01, -0.01], atol=1e-12)
    tip = np.array([[0.5 + 0.05 + 0.01, 0, 0], [0.52, 0.01, 0]])
    np.testing.assert_allclose(probe.signed_distance(tip, 0.0), [0.0, 0.0], atol=1e-12)
    # OrigDisp moves it by 0.1 m along y with the POLY345 profile over TotalTime (0.05 s).
    moved = tip + [0, 0.1 * _poly345(0.5), 0]
    np.testing.assert_allclose(probe.signed_distance(moved, 0.025), [0.0, 0.0], atol=1e-5)


def test_tets_given_as_h8_are_refused_not_run(tmp_path):
    """Tetrahedra listed under Type="H8" (eight indices taken as a hexahedron): the cells they
    make are not hexahedra, and the split into tetrahedra names the first such element rather than
    running garbage; --ignore cannot skip an element type."""
    *_, xml = _cube_xml(elements_type="H8")
    p = tmp_path / "h8.xml"
    p.write_text(xml)
    with pytest.raises(NiftySimError, match=r"\[Elements\]: <Elements NumEls=\d+> but \d+ elements listed"):
        load_niftysim(p, ignore=("Elements Type=H8",))
    p.write_text(re.sub(r' NumEls="\d+"', "", xml))
    with pytest.raises(NiftySimError, match=r"\[Elements\]: element \d+ \(hexahedron\): split into"):
        load_niftysim(p, ignore=("Elements Type=H8",))
    *_, xml = _cube_xml(elements_type="H20")
    p.write_text(xml)
    with pytest.raises(NiftySimError, match="Elements Type=H20"):
        load_niftysim(p, ignore=("Elements Type=H20",))


def test_ramphold_reaches_its_value_at_a_tenth_of_the_total_time(tmp_path):
    """RAMPHOLD (NiftySim's tledConstraint::ComputeAmplitude): u = magnitude · min(1, t / 0.1T)."""
    *_, xml = _cube_xml(
        extra_constraint='<Constraint DOF="1" LoadShape="RAMPHOLD" NumNodes="1" '
        'Type="Disp"><Nodes>26</Nodes><Magnitudes Type="UNIFORM">0.002</Magnitudes>'
        "</Constraint>"
    )
    p = tmp_path / "rh.xml"
    p.write_text(xml)
    sc = load_niftysim(p)
    sim = pl.Simulation(sc.builder.finalize("float64"), dt=sc.dt)
    for t in (0.0025, 0.005, 0.02):  # T = 0.05 s: ramp until 0.005 s
        sim.run(until=t)
        assert np.isclose(sim.displacements[26, 1], 0.002 * min(1.0, sim.time / 0.005), rtol=1e-9)


def _pressure_cube_xml(pressure_xml):
    """Jittered unit cube, symmetry planes x = 0, y = 0, z = 0, NH (μ = 1 kPa, K = 10 kPa)."""
    fmt = lambda a: " ".join(str(v) for v in np.ravel(a))  # noqa: E731
    X, T = pl.mesh.box_tets((1.0, 1.0, 1.0), (3, 3, 3), jitter=0.25, seed=1)
    fixes = "".join(
        f'<Constraint DOF="{d}" NumNodes="{len(ids)}" Type="Fix"><Nodes>{fmt(ids)}</Nodes></Constraint>'
        for d, ids in ((d, np.nonzero(X[:, d] < 1e-9)[0]) for d in range(3))
    )
    return (
        X,
        T,
        f"""<Model>
  <Nodes DOF="3" NumNodes="{len(X)}">{fmt(X)}</Nodes>
  <Elements NumEls="{len(T)}" Type="T4">{fmt(T)}</Elements>
  <ElementSet Size="all"><Material Type="NH"><ElasticParams NumParams="2">1000 10000</ElasticParams>
    </Material></ElementSet>
  {fixes}
  {pressure_xml}
  <SystemParams><TimeStep>1e-3</TimeStep><TotalTime>1</TotalTime><DampingCoeff>0</DampingCoeff>
    <Density>1000</Density></SystemParams>
</Model>""",
    )


def test_pressure_faces_list_normal_and_all(tmp_path):
    """Pressure (user guide §3.5): listed faces (winding kept), SpecType="NORMAL" and NumFaces="all".
    The x = L faces listed and selected by their normal give the model built through the API,
    bit for bit; "all" gives hydrostatic compression, J = 1 − p/K (decoupled NH, σ = K(J − 1) I)."""
    from pliant.mesh.topology import boundary_faces

    fmt = lambda a: " ".join(str(v) for v in np.ravel(a))  # noqa: E731
    X, T, _ = _pressure_cube_xml("")
    B, _ = boundary_faces(T)
    right = B[np.all(X[B][:, :, 0] > 1 - 1e-9, axis=1)]
    listed = (
        f'<Constraint Type="Pressure" NumFaces="{len(right)}" FaceType="Tri" LoadShape="RAMP">'
        f"<Faces>{fmt(right)}</Faces><Magnitude>300</Magnitude></Constraint>"
    )
    normal = (
        '<Constraint Type="Pressure" SpecType="NORMAL" LoadShape="RAMP"><Normal '
        'ToleranceAngle="5">1 0 0</Normal><Magnitude>300</Magnitude></Constraint>'
    )
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(pl.NeoHookean(mu=1000, K=10000), density=1000)
    for d in range(3):
        b.fix(np.nonzero(X[:, d] < 1e-9)[0], "xyz"[d])
    b.add_pressure(right, 300.0, pl.Ramp(1.0))
    ref = pl.Simulation(b.finalize("float64"), dt=1e-3)
    ref.run(until=0.2)
    for k, xml in enumerate((listed, normal)):
        p = tmp_path / f"p{k}.xml"
        p.write_text(_pressure_cube_xml(xml)[2])
        sim = pl.Simulation(load_niftysim(p).builder.finalize("float64"), dt=1e-3)
        sim.run(until=0.2)
        assert np.abs(sim.displacements).max() > 1e-4
        assert np.array_equal(sim.displacements, ref.displacements)
    p = tmp_path / "all.xml"
    p.write_text(
        _pressure_cube_xml(
            '<Constraint Type="Pressure" NumFaces="all" LoadShape="RAMP">'
            "<Magnitude>500</Magnitude></Constraint>"
        )[2]
    )
    sim = pl.Simulation(load_niftysim(p).builder.finalize("float64"))
    sim.relax(tol=1e-9, increments=4)
    corner = np.argmax(X.sum(axis=1))
    np.testing.assert_allclose(np.prod(1 + sim.displacements[corner]), 1 - 500 / 1e4, rtol=1e-8)


@pytest.mark.parametrize(
    "xml, expect",
    [
        (
            '<Material Type="PY"><ElasticParams NumParams="6">300 200 100 50 80 10000</ElasticParams>'
            "</Material>",
            pl.Polynomial(300, 200, 100, 50, 80, K=10000),
        ),
        (
            '<Material Type="AB"><ElasticParams NumParams="3">1000 2.5 10000</ElasticParams></Material>',
            pl.ArrudaBoyce(1000, 2.5, 10000),
        ),
        (
            '<Material Type="TI"><ElasticParams NumParams="6">1000 10000 500 0 0 2</ElasticParams>'
            "</Material>",
            pl.TransverselyIsotropic(1000, 10000, 250, (0, 0, 1)),  # η/2: NiftySim's code, below
        ),
    ],
)
def test_other_hyperelastic_materials(tmp_path, xml, expect):
    """PY (C10 C01 C20 C02 C11 κ), AB (μ λm κ) and TI (μ κ η a1 a2 a3, a normalized), in the order
    of NiftySim's user guide, App. A.1; TI's η halved, as NiftySim's code computes its fibre stress
    (tests/test_niftysim_cross.py compares the motion with NiftySim's own)."""
    *_, text = _cube_xml(material=xml)
    p = tmp_path / "m.xml"
    p.write_text(text)
    (s,) = load_niftysim(p).builder.sets
    assert s.material == expect
    bad = tmp_path / "bad.xml"
    bad.write_text(
        text.replace('NumParams="6">1000 10000 500 0 0 2', 'NumParams="5">1000 10000 500 0 0')
        .replace('NumParams="3">1000 2.5', 'NumParams="2">1000')
        .replace('NumParams="6">300 200 100 50 80 10000<', 'NumParams="5">300 200 100 50 80<')
    )
    with pytest.raises(NiftySimError, match="takes"):
        load_niftysim(bad)


def test_contact_surface_inline_and_vtk(tmp_path):
    """<ContactSurface>: a closed rigid surface, inline or from a VTK file beside the model, becomes a
    mesh tool whose signed distance matches the shape (a sphere of radius 0.05 m: its icosphere
    facets lie within 0.6 mm of it, the grid interpolation adds at most a cell's curvature error);
    an open surface is refused by name."""
    import meshio

    fmt = lambda a: " ".join(str(v) for v in np.ravel(a))  # noqa: E731
    V, F = pl.mesh.primitive_surface("sphere", radius=0.05)
    V = V + [0.05, 0.05, -0.05]
    meshio.write(tmp_path / "ball.vtk", meshio.Mesh(V, [("triangle", F)]))
    inline = (
        f'<ContactSurface><Nodes>{fmt(V)}</Nodes><Elements Type="T3">{fmt(F)}</Elements></ContactSurface>'
    )
    for k, xml in enumerate(
        (inline, '<ContactSurface><VTKSurface Type="T3">ball.vtk</VTKSurface></ContactSurface>')
    ):
        *_, text = _cube_xml(extra_constraint=xml)
        p = tmp_path / f"s{k}.xml"
        p.write_text(text)
        (tool,) = load_niftysim(p).builder.tools
        pts = np.array([[0.05, 0.05, -0.05], [0.05, 0.05, 0.0], [0.05, 0.05, 0.03]])
        np.testing.assert_allclose(tool.signed_distance(pts), [-0.05, 0.0, 0.03], atol=1.5e-3)
    *_, text = _cube_xml(
        extra_constraint=f"<ContactSurface><Nodes>{fmt(V)}</Nodes><Elements "
        f'Type="T3">{fmt(F[:-10])}</Elements></ContactSurface>'
    )
    p = tmp_path / "open.xml"
    p.write_text(text)
    with pytest.raises(NiftySimError, match="not closed"):
        load_niftysim(p)


def test_contact_surface_from_niftysims_own_vtk_polydata(tmp_path):
    """NiftySim's contact models name surfaces written by VTK (legacy POLYDATA, which meshio does
    not read): its box_surface.vtk, the unit cube about the origin, becomes a mesh tool whose
    signed distance is the cube's (inside −0.5 at the centre, 0 on a face, +0.25 a quarter outside;
    within the distance grid's interpolation, 1.5e-3 as above)."""
    import shutil

    shutil.copy(Path(__file__).parent / "data" / "niftysim_box_surface.vtk", tmp_path / "box_surface.vtk")
    *_, text = _cube_xml(
        extra_constraint='<ContactSurface><VTKSurface Type="T3">box_surface.vtk</VTKSurface></ContactSurface>'
    )
    p = tmp_path / "m.xml"
    p.write_text(text)
    (tool,) = load_niftysim(p).builder.tools
    pts = np.array([[0.0, 0.0, 0.0], [0.5, 0.1, -0.2], [0.0, 0.0, 0.75], [-0.2, -0.75, 0.1]])
    np.testing.assert_allclose(tool.signed_distance(pts), [-0.5, 0.0, 0.25, 0.25], atol=1.5e-3)


def test_viscoelastic_nhv_and_tiv(tmp_path):
    """NHV / TIV: the NH / TI elastic parameters and <ViscoParams> (α, τ pairs, isochoric terms
    first; user guide §3.4.4) → pliant.Viscoelastic; a wrong count is a named error."""
    nhv = (
        '<Material Type="NHV"><ElasticParams NumParams="2">1000 10000</ElasticParams>'
        '<ViscoParams NumIsoTerms="2" NumVolTerms="1">0.3 0.1 0.2 1.0 0.1 0.5</ViscoParams>'
        "</Material>"
    )
    tiv = (
        '<Material Type="TIV"><ElasticParams NumParams="6">1000 10000 500 1 0 0</ElasticParams>'
        '<ViscoParams NumIsoTerms="1" NumVolTerms="0">0.4 0.05</ViscoParams></Material>'
    )
    expect = [
        pl.Viscoelastic(pl.NeoHookean(mu=1000, K=10000), iso=[(0.3, 0.1), (0.2, 1.0)], vol=[(0.1, 0.5)]),
        pl.Viscoelastic(pl.TransverselyIsotropic(1000, 10000, 250, (1, 0, 0)), iso=[(0.4, 0.05)]),
    ]
    for k, (xml, e) in enumerate(zip((nhv, tiv), expect)):
        *_, text = _cube_xml(material=xml)
        p = tmp_path / f"v{k}.xml"
        p.write_text(text)
        (s,) = load_niftysim(p).builder.sets
        assert s.material == e
    *_, text = _cube_xml(material=nhv.replace("0.1 0.5</Visco", "0.1</Visco"))
    p = tmp_path / "bad.xml"
    p.write_text(text)
    with pytest.raises(NiftySimError, match="ViscoParams"):
        load_niftysim(p)


def test_rom_off_runs_and_rom_on_is_refused_by_name(tmp_path):
    """<ROM>0</ROM> (NiftySim's default: reduced order modelling off, as its models/cubehex10.xml
    writes it) imports as the model without it, the same bits; <ROM>1</ROM> is refused by name
    and can be skipped knowingly; a value that is not 0 or 1 is named."""
    X, T, left, right, xml = _cube_xml()
    runs = []
    for rom in ("", "<ROM>0</ROM>"):
        p = tmp_path / "rom.xml"
        p.write_text(xml.replace("</SystemParams>", rom + "</SystemParams>"))
        sim = pl.Simulation(load_niftysim(p).builder.finalize("float64"), dt=1e-4)
        sim.run(steps=50)
        runs.append(sim.displacements)
    assert np.abs(runs[0]).max() > 0 and np.array_equal(runs[0], runs[1])
    p.write_text(xml.replace("</SystemParams>", "<ROM>1</ROM></SystemParams>"))
    with pytest.raises(NiftySimError, match=r"unsupported NiftySim feature SystemParams/ROM"):
        load_niftysim(p)
    assert any("SystemParams/ROM" in w for w in load_niftysim(p, ignore=("SystemParams/ROM",)).warnings)
    p.write_text(xml.replace("</SystemParams>", "<ROM>on</ROM></SystemParams>"))
    with pytest.raises(NiftySimError, match=r"\[SystemParams/ROM\].*expected an integer"):
        load_niftysim(p)


def test_output_variables_u_and_f_write_niftysims_text_files(tmp_path):
    """<Output Freq="100"><Variable>U</Variable><Variable>F</Variable><Variable>S</Variable>:
    `pliant run` writes OUT/U.txt and OUT/F.txt as NiftySim lays them out (a row per DOF, x y z of
    node 0 first; a column per frame after the first): U equal to the displacements of the frames'
    .vtu files (read with meshio; 1e-8: the 9 digits written), F to the internal forces a fresh
    float64 import of the model computes from them (1e-6: the run's float32 arithmetic); S, which
    pliant does not write, is named in a warning."""
    import json

    import meshio
    from typer.testing import CliRunner

    from pliant.cli import app

    X, T, left, right, xml = _cube_xml()
    out = '<Output Freq="100"><Variable>U</Variable><Variable>F</Variable><Variable>S</Variable></Output>'
    xml = xml.replace("</SystemParams>", "</SystemParams>" + out)
    p = tmp_path / "out.xml"
    p.write_text(xml)
    r = CliRunner().invoke(app, ["run", str(p), "-o", str(tmp_path / "o")])
    assert r.exit_code == 0, r.output
    U = np.loadtxt(tmp_path / "o" / "U.txt", ndmin=2)
    F = np.loadtxt(tmp_path / "o" / "F.txt", ndmin=2)
    frames = sorted((tmp_path / "o").glob("frame_*.vtu"))
    assert U.shape == F.shape == (3 * len(X), len(frames) - 1) == (3 * len(X), 5)  # 0.05 s / (100 × 1e-4 s)
    model = load_niftysim(p).builder.finalize("float64")
    s = model.state()
    for k, f in enumerate(frames[1:]):
        u = meshio.read(f).point_data["displacement"]
        np.testing.assert_allclose(U[:, k], u.reshape(-1), rtol=1e-8, atol=1e-8 * np.abs(u).max())
        s.set_displacements(u)
        fint = model.internal_forces(s).reshape(-1)
        np.testing.assert_allclose(F[:, k], fint, rtol=1e-6, atol=1e-6 * np.abs(fint).max())
    assert np.abs(U[:, -1]).max() > 1e-3 and np.abs(F[:, -1]).max() > 0
    summary = json.loads((tmp_path / "o" / "summary.json").read_text())
    assert {"U.txt", "F.txt"} <= set(summary["files"])
    assert any("Variable S not written" in w for w in summary["warnings"])


def _balls_with(tmp_path, extra: str, name: str = "balls.xml", deformable: bool = True) -> Path:
    """ball_ball.xml with ``extra`` SystemParams (and DoDeformableCollision 0 if not
    ``deformable``), written to tmp_path/name."""
    xml = BALLS.read_text()
    if not deformable:
        xml = xml.replace("\n      1\n    </DoDeformableCollision>", "0</DoDeformableCollision>")
    p = tmp_path / name
    p.write_text(xml.replace("<DoDeformableCollision>", extra + "<DoDeformableCollision>", 1))
    return p


def test_deformable_friction_coefficient_is_the_soft_contacts_friction(tmp_path):
    """<DeformableFrictionCoefficient> (NiftySim's Coulomb coefficient of its deformable contact
    surface) becomes the soft contact's friction, static and kinetic alike: the same bits over
    ball_ball's 1 s as the model given that friction through the API, and other bits than
    frictionless; without deformable contact it is named as having no effect; the contact offsets
    NiftySim's method has (ContactSafetyMargin, RateConstraintDistance) are refused by name."""
    mu = "<DeformableFrictionCoefficient>0.4</DeformableFrictionCoefficient>"
    p = _balls_with(tmp_path, mu)
    sc = load_niftysim(p)
    c = sc.builder.soft_contact
    assert (c.pairs, c.self_contact, c.mu_s, c.mu_k) == (None, False, 0.4, 0.4)
    runs = []
    for b in (sc.builder, load_niftysim(BALLS).builder):
        if b is not sc.builder:
            b.set_soft_contact(friction=0.4)
        sim = pl.Simulation(b.finalize("float32"), dt=sc.dt)
        sim.run(steps=10000)
        runs.append(sim.displacements)
    assert np.array_equal(runs[0], runs[1])
    frictionless = pl.Simulation(load_niftysim(BALLS).builder.finalize("float32"), dt=sc.dt)
    frictionless.run(steps=10000)
    assert not np.array_equal(runs[0], frictionless.displacements)
    p = _balls_with(tmp_path, mu, deformable=False)
    assert any("DeformableFrictionCoefficient ignored" in w for w in load_niftysim(p).warnings)
    for k in ("ContactSafetyMargin", "RateConstraintDistance"):
        p = _balls_with(tmp_path, f"<{k}>0.001</{k}>")
        with pytest.raises(NiftySimError, match=f"unsupported NiftySim feature SystemParams/{k}"):
            load_niftysim(p)


def test_niftysims_contact_search_settings_are_accepted_as_having_no_physics(tmp_path):
    """<BVType> (AABB or OBB) and <DoMultiPassContacts> choose how NiftySim finds and resolves its
    contacts: the model imports with a warning naming each and runs to the same bits as without
    them (300 steps); a BVType NiftySim does not know is named."""
    p = _balls_with(tmp_path, "<BVType>OBB</BVType><DoMultiPassContacts>1</DoMultiPassContacts>")
    sc = load_niftysim(p)
    assert sum("ignored (how NiftySim searches" in w for w in sc.warnings) == 2
    runs = []
    for b in (sc.builder, load_niftysim(BALLS).builder):
        sim = pl.Simulation(b.finalize("float32"), dt=sc.dt)
        sim.run(steps=300)
        runs.append(sim.displacements)
    assert np.array_equal(runs[0], runs[1])
    p = _balls_with(tmp_path, "<BVType>KDOP</BVType>")
    with pytest.raises(NiftySimError, match=r"\[SystemParams/BVType\].*expected AABB or OBB"):
        load_niftysim(p)


def test_ball_balls_dynamics_do_not_depend_on_the_step(tmp_path):
    """ball_ball.xml without its contact (each ball driven 0.2 m by its cap, y and z free; 1 m
    balls, μ = 100 Pa, ρ = 20 kg/m³, α = 0.5 /s), float32 as imported: the answers at the model's
    Δt = 0.1 ms and at Δt/2 agree to 2e-4 of the largest displacement at t = 1 s (measured 1.1e-4:
    the time discretization's O(Δt²)). NiftySim's own answers at those two steps are 25 % and 49 %
    from this one, from its float32 update coefficients (benchmarks/niftysim_ball_ball.py,
    docs/validation.md): a spurious spring that grows the balls' free motion, the faster the
    smaller the step; pliant's increment form has none."""
    p = tmp_path / "balls.xml"
    p.write_text(
        re.sub(r"<DoDeformableCollision>.*?</DoDeformableCollision>", "", BALLS.read_text(), flags=re.S)
    )
    u = []
    for dt in (1e-4, 5e-5):
        sc = load_niftysim(p, overrides={"SystemParams.TimeStep": dt})
        with pytest.warns(pl.PliantWarning, match="stable time step estimate"):  # the mesh's sliver
            sim = pl.Simulation(sc.builder.finalize("float32"), dt=sc.dt)
        sim.run(until=1.0)
        u.append(sim.displacements)
    largest = np.linalg.norm(u[0], axis=1).max()
    assert largest > 0.2  # the caps' 0.2 m and the balls' own motion
    assert np.linalg.norm(u[0] - u[1], axis=1).max() < 2e-4 * largest


def test_a_repeated_element_read_once_is_its_first_with_a_warning(tmp_path):
    """NiftySim's tledModel reads an element it expects once through XMLNode::getChildNode: the
    first of its name. A model with two <TimeStep> (1e-4 s first, then 2e-4 s) and two <Density>
    in its SystemParams runs at the first step (pliant took the last), and each repeat is named in
    a warning; repeated elements that NiftySim reads each of (two <Constraint>) give none."""
    X, T, left, right, xml = _cube_xml()
    twice = xml.replace("<TimeStep>1e-4</TimeStep>", "<TimeStep>1e-4</TimeStep><TimeStep>2e-4</TimeStep>")
    twice = twice.replace(
        "<DampingCoeff>20</DampingCoeff>", "<DampingCoeff>20</DampingCoeff><DampingCoeff>5</DampingCoeff>"
    )
    assert twice.count("<TimeStep>") == 2 and twice.count("<DampingCoeff>") == 2
    p = tmp_path / "twice.xml"
    p.write_text(twice)
    sc = load_niftysim(p)
    assert sc.dt == 1e-4 and sc.builder.damping == 20.0
    said = [w for w in sc.warnings if "the first is read" in w]
    assert len(said) == 2 and "<SystemParams> holds 2 <TimeStep>" in said[0] + said[1], said
    assert xml.count("<Constraint") >= 2
    p.write_text(xml)
    assert not [w for w in load_niftysim(p).warnings if "the first is read" in w]
