"""Surface traction (ModelBuilder.add_traction; NiftySim's Traction; a scene's "traction" load): a
force per current area in a fixed direction.

References: momentum. Internal forces sum to zero, so on a free body central differences give
Σ m (u_{n+1} − u_n) = Σ m (u_n − u_{n−1}) + Δt² F(u_n) exactly, F(u) = Σ_faces |a(u)| t the total
traction over the faces' current areas, measured here from the positions at each step (a force on
the reference areas misses by more than a thousand times the tolerance). NiftySim's importer
against the same model built through the API, and NiftySim's sign (its own unit test,
testTractionConstraint: the forces on a face sum to −area · t)."""

from __future__ import annotations

import numpy as np
import pytest
from typer.testing import CliRunner

import pliant as pl
from pliant.cli import app
from pliant.io.niftysim import NiftySimError, load_niftysim
from pliant.mesh.topology import boundary_faces

runner = CliRunner()
DT = 2e-4


def _free_cube():
    X, T = pl.mesh.box_tets((0.02, 0.02, 0.02), (3, 3, 3), jitter=0.2, seed=3)
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(pl.NeoHookean(E=2e4, nu=0.3), density=1000.0)
    B, _ = boundary_faces(T)
    top = B[np.all(X[B][:, :, 2] > 0.02 - 1e-9, axis=1)]
    return b, X, top


def _area(x: np.ndarray, faces: np.ndarray) -> float:
    """Total area [m²] of triangles ``faces`` at positions x."""
    v = x[faces]
    return float(0.5 * np.linalg.norm(np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]), axis=1).sum())


def test_traction_moves_a_free_body_by_its_force_on_the_current_area(backend):
    """A free cube pulled by a traction on its top face (upwards and sideways; it stretches, and
    the face shrinks laterally): Σ m u_N = Σ_{n<N} (N − n) Δt² |a(u_n)| t, to round-off (the
    momentum relation above summed from rest)."""
    b, X, top = _free_cube()
    t = np.array([150.0, 0.0, 600.0])
    b.add_traction(top, t)
    model = b.finalize("float64", backend=backend)
    sim = pl.Simulation(model, dt=DT)
    steps = 300
    current, reference = np.zeros(3), np.zeros(3)
    for n in range(steps):
        current += (steps - n) * DT**2 * _area(X + sim.displacements, top) * t
        reference += (steps - n) * DT**2 * _area(X, top) * t
        sim.run(steps=1)
    momentum = (model.mass[:, None] * sim.displacements).sum(axis=0)
    assert abs(_area(X + sim.displacements, top) / _area(X, top) - 1) > 1e-3  # the face changed
    np.testing.assert_allclose(momentum, current, rtol=1e-10, atol=1e-18)
    assert np.abs(current - reference).max() > 1e3 * 1e-10 * np.abs(current).max()


def test_niftysim_traction_as_the_api_builds_it_with_niftysim_s_sign(tmp_path):
    """<Constraint Type="Traction"> on the facets facing +x (UNIFORM) and on listed faces
    (DIFFORM): the same bits as add_traction(faces, −t) (NiftySim applies −|a| t); the cube
    moves against t."""
    b, X, top = _free_cube()
    T = b.tets
    fmt = lambda a: " ".join(str(v) for v in np.ravel(a))  # noqa: E731
    B, _ = boundary_faces(T)
    right = B[np.all(X[B][:, :, 0] > 0.02 - 1e-9, axis=1)]
    t = np.array([0.0, 0.0, 1.23e3])
    head = (
        f'<Model><Nodes DOF="3" NumNodes="{len(X)}">{fmt(X)}</Nodes>'
        f'<Elements NumEls="{len(T)}" Type="T4">{fmt(T)}</Elements>'
        '<ElementSet Size="all"><Material Type="NH"><ElasticParams NumParams="2">7692.3 16666.7'
        "</ElasticParams></Material>0</ElementSet>"
    )
    tail = (
        "<SystemParams><TimeStep>2e-4</TimeStep><TotalTime>0.05</TotalTime><DampingCoeff>0"
        "</DampingCoeff><Density>1000</Density></SystemParams></Model>"
    )
    uniform = (
        '<Constraint Type="Traction" SpecType="NORMAL" LoadShape="RAMP"><Normal ToleranceAngle="1">1 0 0'
        f'</Normal><Magnitudes Type="UNIFORM">{fmt(t)}</Magnitudes></Constraint>'
    )
    listed = (
        f'<Constraint Type="Traction" NumFaces="{len(right)}" FaceType="Tri" LoadShape="RAMP">'
        f'<Faces>{fmt(right)}</Faces><Magnitudes Type="DIFFORM">{fmt(np.tile(t, len(right)))}'
        "</Magnitudes></Constraint>"
    )
    ref = pl.ModelBuilder()
    ref.add_mesh(X, T)
    ref.set_material(pl.NeoHookean(mu=7692.3, K=16666.7), density=1000.0)
    ref.add_traction(right, -t, pl.Ramp(0.05))
    want = pl.Simulation(ref.finalize("float64"), dt=DT)
    want.run(steps=100)
    assert want.displacements[:, 2].mean() < -1e-6  # against t, as NiftySim
    for k, xml in enumerate((uniform, listed)):
        p = tmp_path / f"t{k}.xml"
        p.write_text(head + xml + tail)
        sim = pl.Simulation(load_niftysim(p).builder.finalize("float64"), dt=DT)
        sim.run(steps=100)
        assert np.array_equal(sim.displacements, want.displacements)
    for bad, says in [
        (uniform.replace(fmt(t), "1 2"), "expected 3"),
        (listed.replace('Type="DIFFORM">', 'Type="DIFFORM">1 2 3 '), "for each of the"),
        (uniform.replace(f'Type="UNIFORM">{fmt(t)}', 'Type="FILE">t.txt'), "Magnitudes Type=FILE"),
        (
            uniform.replace("<Magnitudes", "<Magnitude").replace("</Magnitudes>", "</Magnitude>"),
            "needs <Magnitudes>",
        ),
    ]:
        p = tmp_path / "bad.xml"
        p.write_text(head + bad + tail)
        with pytest.raises(NiftySimError, match=says):
            load_niftysim(p)
        r = runner.invoke(app, ["run", str(p), "-o", str(tmp_path / "o")])
        assert r.exit_code == 2 and "Traceback" not in r.output


def test_scene_traction_load_and_node_gravity(tmp_path):
    """A scene's [[load]] type = "traction" on a selected face patch, and type = "gravity" with
    nodes: the faces and nodes selected, with their vectors; a traction of two components exits 2
    naming the key."""
    scene = tmp_path / "s.toml"
    body = """
[mesh]
primitive = "box"
size = [0.02, 0.02, 0.02]
edge_length = 0.005
[[material]]
type = "neo-hookean"
E = 2e4
nu = 0.3
density = 1000.0
[[load]]
type = "traction"
traction = [150.0, 0.0, 600.0]
nodes = { box = [[-1, -1, 0.0099], [1, 1, 1]] }
[[load]]
type = "gravity"
g = [0.0, 0.0, -9.81]
nodes = { box = [[-1, -1, -1], [1, 1, -0.0049]] }
[solver]
duration = 0.01
dt = 2e-4
"""
    scene.write_text(body)
    from pliant.scene import load_scene

    sc = load_scene(scene)
    b = sc.builder
    X = b.nodes
    assert len(b._tractions) == 1 and len(b._node_gravity) == 1
    (faces, t, _), (ids, g, _) = b._tractions[0], b._node_gravity[0]
    assert np.all(X[faces][:, :, 2] > 0.01 - 1e-9) and np.allclose(t, [150.0, 0.0, 600.0])
    assert np.array_equal(ids, np.nonzero(X[:, 2] <= -0.0049)[0]) and np.allclose(g, [0, 0, -9.81])
    scene.write_text(body.replace("traction = [150.0, 0.0, 600.0]", "traction = [150.0, 0.0]"))
    r = runner.invoke(app, ["run", str(scene), "-o", str(tmp_path / "o")])
    assert r.exit_code == 2 and "load[0].traction" in r.output and "Traceback" not in r.output


def test_add_traction_refuses_bad_input():
    b, X, top = _free_cube()
    for faces, t, says in [
        (top, (1.0, 2.0), r"traction = \(1.0, 2.0\) \(shape \(2,\)\)"),
        (top, "up", "traction = 'up'"),
        (top, (1.0, 2.0, np.inf), r"traction = \(1.0, 2.0, inf\) .* expected finite"),
        (top[:, :2], (1.0, 2.0, 3.0), r"faces of shape \(18, 2\), int\d+; expected \(F, 3\) integer"),
        (top + b.n_nodes, (1.0, 2.0, 3.0), "add_traction faces"),
    ]:
        with pytest.raises(pl.InputError, match=says):
            b.add_traction(faces, t)
