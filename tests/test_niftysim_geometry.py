"""NiftySim geometry given by reference (user guide v2.4 §3.3 and §3.5.2): a mesh read from an
<MSHMesh> (Gmsh) or <VTKMesh> file with its Rotation, ScaleFactor and Translation, and constraint
nodes chosen by surface normal (with <RestrictTo> boxes and spheres), NumNodes="all" or a start
index.

References: the rotations in closed form (a quarter turn about z maps (x, y, z) to (−y, x, z)); the
file's points read here with meshio; the same model with its mesh listed inline (the same bits);
the faces of a box selected by coordinates."""

from __future__ import annotations

import shutil
from pathlib import Path

import meshio
import numpy as np
import pytest
from typer.testing import CliRunner

import pliant as pl
from pliant.cli import app
from pliant.io.niftysim import NiftySimError, load_niftysim
from pliant.mesh import box_tets

SPHERE_VTK = Path(__file__).parent / "data" / "niftysim_sphere.vtk"  # NiftySim's own test mesh
runner = CliRunner()

MATERIAL = '<Material Type="NH"><ElasticParams NumParams="2">1000 20000</ElasticParams></Material>'
SYSTEM = (
    "<SystemParams><TimeStep>1e-4</TimeStep><TotalTime>0.02</TotalTime><DampingCoeff>20</DampingCoeff>"
    "<Density>1000</Density></SystemParams>"
)


def _ints(a) -> str:
    return " ".join(str(int(v)) for v in np.ravel(a))


def _inline(X, T) -> str:
    return (
        f'<Nodes DOF="3" NumNodes="{len(X)}">{" ".join(repr(float(v)) for v in np.ravel(X))}</Nodes>'
        f'<Elements NumEls="{len(T)}" Type="T4">{_ints(T)}</Elements>'
    )


def _model(tmp_path: Path, mesh: str, constraints: str = "", name: str = "m.xml") -> Path:
    p = tmp_path / name
    p.write_text(
        f'<?xml version="1.0"?><Model>{mesh}<ElementSet Size="all">{MATERIAL}0</ElementSet>'
        f"{constraints}{SYSTEM}</Model>"
    )
    return p


def _write_msh(path: Path, X: np.ndarray, T: np.ndarray) -> None:
    """A Gmsh 2.2 ASCII file (NiftySim's MSHMesh format) of the tets, with zero tags."""
    tags = {"gmsh:physical": [np.zeros(len(T), int)], "gmsh:geometrical": [np.zeros(len(T), int)]}
    meshio.write(path, meshio.Mesh(X, [("tetra", T)], cell_data=tags), file_format="gmsh22", binary=False)


def _sphere_msh(tmp_path: Path) -> tuple[Path, np.ndarray, np.ndarray]:
    """NiftySim's sphere (VTK) written as a Gmsh 2.2 file beside the models; its points and tets."""
    m = meshio.read(SPHERE_VTK)
    X = np.asarray(m.points, float)
    T = np.concatenate([c.data for c in m.cells if c.type == "tetra"])
    _write_msh(tmp_path / "sphere.msh", X, T)
    return tmp_path / "sphere.msh", X, T


@pytest.mark.parametrize(
    "transform, expect",
    [
        ("", lambda X: X),
        ("<Translation>1 -2 0.5</Translation>", lambda X: X + [1.0, -2.0, 0.5]),
        ("<ScaleFactor>2.5</ScaleFactor>", lambda X: 2.5 * X),
        # a quarter turn about z around (1, 2, 3): (dx, dy, dz) -> (-dy, dx, dz)
        (
            "<Rotation>1 2 3 0 0 90</Rotation>",
            lambda X: np.column_stack([1 - (X[:, 1] - 2), 2 + (X[:, 0] - 1), X[:, 2]]),
        ),
        # Rx(90) Rz(90): (x, y, z) -> Rz: (-y, x, z) -> Rx: (-y, -z, x); then scale, then translate
        (
            "<Translation>0 0 1</Translation><Rotation>0 0 0 90 0 90</Rotation><ScaleFactor>2</ScaleFactor>",
            lambda X: 2 * np.column_stack([-X[:, 1], -X[:, 2], X[:, 0]]) + [0.0, 0.0, 1.0],
        ),
    ],
)
def test_msh_mesh_file_and_its_transforms(tmp_path, transform, expect):
    """<MSHMesh> reads the Gmsh file's nodes and tets (in its numbering) and applies rotation,
    then scaling, then translation, as the user guide orders them."""
    _, X, T = _sphere_msh(tmp_path)
    p = _model(tmp_path, f'<MSHMesh Type="T4">sphere.msh{transform}</MSHMesh>')
    b = load_niftysim(p).builder
    assert np.allclose(b.nodes, expect(X), rtol=0, atol=1e-12)
    assert np.array_equal(b.tets, T)


@pytest.mark.filterwarnings("ignore:.*limits the stable time step")  # the sphere's one sliver
def test_vtk_mesh_file_runs_as_the_same_model_listed_inline(tmp_path):
    """<VTKMesh Type="T4ANP"> of NiftySim's sphere, with a normal-chosen Disp on its top and Fix
    on its bottom, gives the bits of the same model with the mesh and node lists written out."""
    shutil.copy(SPHERE_VTK, tmp_path / "sphere.vtk")
    m = meshio.read(SPHERE_VTK)
    X = np.asarray(m.points, float)
    T = np.concatenate([c.data for c in m.cells if c.type == "tetra"])
    from pliant.mesh.topology import boundary_faces

    B = boundary_faces(T)[0]
    nrm = np.cross(X[B[:, 1]] - X[B[:, 0]], X[B[:, 2]] - X[B[:, 0]])
    nrm /= np.linalg.norm(nrm, axis=1)[:, None]
    top = np.unique(B[nrm[:, 2] >= np.cos(np.radians(30))])
    bottom = np.unique(B[nrm[:, 2] <= -np.cos(np.radians(30))])
    assert 5 < top.size < len(X) // 4 and 5 < bottom.size < len(X) // 4

    def cons(spec_top, spec_bottom):
        return (
            f'<Constraint Type="Fix" DOF="all" {spec_bottom}</Constraint>'
            f'<Constraint Type="Disp" DOF="2" LoadShape="RAMP" {spec_top}'
            '<Magnitudes Type="UNIFORM">-0.002</Magnitudes></Constraint>'
        )

    by_normal = cons(
        'SpecType="NORMAL"><Normal ToleranceAngle="30">0 0 1</Normal>',
        'SpecType="NORMAL"><Normal ToleranceAngle="30">0 0 -2</Normal>',
    )
    listed = cons(
        f'NumNodes="{top.size}"><Nodes>{_ints(top)}</Nodes>',
        f'NumNodes="{bottom.size}"><Nodes>{_ints(bottom)}</Nodes>',
    )
    a = load_niftysim(_model(tmp_path, '<VTKMesh Type="T4ANP">sphere.vtk</VTKMesh>', by_normal, "a.xml"))
    ref = _model(tmp_path, _inline(X, T).replace('Type="T4"', 'Type="T4ANP"'), listed, "b.xml")
    b = load_niftysim(ref)
    runs = []
    for sc in (a, b):
        sim = pl.Simulation(sc.builder.finalize("float64"), dt=sc.dt)
        sim.run(until=0.01)
        runs.append(sim.displacements)
    assert np.abs(runs[1][:, 2]).max() > 5e-4  # it moved
    assert np.array_equal(runs[0], runs[1])


def _box_model(tmp_path, constraint: str) -> tuple[Path, np.ndarray]:
    X, T = box_tets((0.1, 0.1, 0.1), (4, 4, 4))
    return _model(tmp_path, _inline(X, T), constraint), X


@pytest.mark.parametrize(
    "spec, select",
    [
        ('SpecType="NORMAL"><Normal ToleranceAngle="1">0 0 1</Normal>', lambda X: X[:, 2] > 0.1 - 1e-9),
        (
            'SpecType="NORMAL"><Normal ToleranceAngle="1">1 0 0</Normal>'
            '<RestrictTo Type="Box">0 1 0 0.05 -1 1</RestrictTo>',
            lambda X: (X[:, 0] > 0.1 - 1e-9) & (X[:, 1] <= 0.05 + 1e-12),
        ),
        (
            'SpecType="NORMAL"><Normal ToleranceAngle="1">0 -1 0</Normal>'
            '<RestrictTo Type="Sphere">0.06 0.05 0 0.05</RestrictTo>',
            lambda X: (X[:, 1] < 1e-9) & (np.linalg.norm(X - [0.05, 0.0, 0.05], axis=1) < 0.06),
        ),
        ('NumNodes="all">', lambda X: np.ones(len(X), bool)),
        ('NumNodes="7"><Nodes>10</Nodes>', lambda X: (np.arange(len(X)) >= 10) & (np.arange(len(X)) < 17)),
    ],
)
def test_constraint_nodes_by_normal_all_and_start_index(tmp_path, spec, select):
    """A Fix constraint fixes exactly the nodes chosen: the box's faces by coordinates (a face
    within a degree of the normal, inside the box or sphere it is restricted to), all nodes, or
    NumNodes consecutive nodes from the one listed."""
    p, X = _box_model(tmp_path, f'<Constraint Type="Fix" DOF="1" {spec}</Constraint>')
    b = load_niftysim(p).builder
    want = np.nonzero(select(X))[0]
    assert 0 < want.size
    held = b.finalize("float64").constrained  # (N, 3): DOFs a constraint holds
    assert np.nonzero(held[:, 1])[0].tolist() == want.tolist()
    assert not held[:, [0, 2]].any()


def test_submodel_mesh_files_and_normal_constraints_resolve_on_their_own_mesh(tmp_path):
    """NiftySim's submodel demo, smaller: two translated copies of one Gmsh box, each sub-model
    pulling its own +z face; the second is scaled. Each top face moves by its own magnitude, and
    neither constraint reaches the other body."""
    X, T = box_tets((1.0, 1.0, 1.0), (2, 2, 2))
    X = X - 0.5
    _write_msh(tmp_path / "box.msh", X, T)

    def sub(move, mag, scale=""):
        return (
            f'<SubModel><MSHMesh Type="T4">box.msh<Translation>{move}</Translation>{scale}</MSHMesh>'
            f'<ElementSet Size="all">{MATERIAL}0</ElementSet>'
            '<Constraint Type="Fix" DOF="all" SpecType="NORMAL"><Normal ToleranceAngle="2">0 0 -1</Normal>'
            '</Constraint><Constraint Type="Disp" DOF="2" SpecType="NORMAL" LoadShape="RAMP">'
            '<Normal ToleranceAngle="2">0 0 1</Normal>'
            f'<Magnitudes Type="UNIFORM">{mag}</Magnitudes></Constraint></SubModel>'
        )

    p = tmp_path / "subs.xml"
    p.write_text(
        f'<?xml version="1.0"?><Model>{sub("-3 0 0", -0.1)}'
        f"{sub('3 0 0', 0.05, '<ScaleFactor>1.5</ScaleFactor>')}{SYSTEM}</Model>"
    )
    sc = load_niftysim(p)
    Xm = sc.builder.nodes
    assert np.allclose(Xm[: len(X)], X + [-3, 0, 0]) and np.allclose(Xm[len(X) :], 1.5 * X + [3, 0, 0])
    sim = pl.Simulation(sc.builder.finalize("float64"), dt=sc.dt)
    sim.run(until=0.02)
    u = sim.displacements
    first, second = np.arange(len(Xm)) < len(X), np.arange(len(Xm)) >= len(X)
    assert np.allclose(u[first & np.isclose(Xm[:, 2], 0.5), 2], -0.1, rtol=1e-12)
    assert np.allclose(u[second & np.isclose(Xm[:, 2], 0.75), 2], 0.05, rtol=1e-12)
    assert np.all(u[first & np.isclose(Xm[:, 2], -0.5)] == 0)
    assert np.all(u[second & np.isclose(Xm[:, 2], -0.75)] == 0)


@pytest.mark.parametrize(
    "mesh, constraint, says",
    [
        ('<MSHMesh Type="T4">nowhere.msh</MSHMesh>', "", "'nowhere.msh': not found beside the model"),
        ('<MSHMesh Type="T4">.</MSHMesh>', "", "a folder, not a file"),
        ('<MSHMesh Type="H8">sphere.msh</MSHMesh>', "", "H8"),
        ('<MSHMesh Type="Q4">sphere.msh</MSHMesh>', "", "expected T4, T4ANP or H8"),
        ('<MSHMesh Type="T4">sphere.msh<Rotation>0 0 90</Rotation></MSHMesh>', "", "expected 6"),
        ('<MSHMesh Type="T4">sphere.msh<ScaleFactor>-1</ScaleFactor></MSHMesh>', "", "ScaleFactor"),
        ('<MSHMesh Type="T4">sphere.msh<Translation>1 2</Translation></MSHMesh>', "", "Translation"),
        ('<MSHMesh Type="T4">garbage.msh</MSHMesh>', "", "garbage.msh"),
        (
            '<MSHMesh Type="T4">sphere.msh</MSHMesh><VTKMesh Type="T4">sphere.msh</VTKMesh>',
            "",
            "more than one mesh",
        ),
        (
            None,
            '<Constraint Type="Fix" SpecType="NORMAL"><Normal>0 0 1</Normal></Constraint>',
            "ToleranceAngle",
        ),
        (
            None,
            '<Constraint Type="Fix" SpecType="NORMAL"><Normal ToleranceAngle="1">0 0 1</Normal>'
            '<RestrictTo Type="Cone">1 2 3</RestrictTo></Constraint>',
            "RestrictTo",
        ),
        (
            None,
            '<Constraint Type="Fix" SpecType="NORMAL"><Normal ToleranceAngle="1">1 1 1</Normal></Constraint>',
            "no boundary node",
        ),
        (None, '<Constraint Type="Fix" NumNodes="3"><Nodes>1 2</Nodes></Constraint>', "NumNodes=3"),
        (None, '<Constraint Type="Fix" NumNodes="999999999"><Nodes>0</Nodes></Constraint>', "past the mesh"),
    ],
)
def test_bad_mesh_files_and_node_specs_exit_2_naming_them(tmp_path, mesh, constraint, says):
    """Each mistake is an error naming the file and what is wrong, exit 2 on the command line."""
    _sphere_msh(tmp_path)
    (tmp_path / "garbage.msh").write_text("$MeshFormat\nnot a mesh\n")
    if mesh is None:
        p, _ = _box_model(tmp_path, constraint)
    else:
        p = _model(tmp_path, mesh, constraint)
    with pytest.raises(NiftySimError, match=says):
        load_niftysim(p)
    r = runner.invoke(app, ["run", str(p), "-o", str(tmp_path / "o")])
    assert r.exit_code == 2 and says in r.output and "Traceback" not in r.output


def test_gravity_acts_on_its_listed_nodes_as_niftysim_s(tmp_path):
    """NiftySim's two_cubes_sheet.xml pulls two cubes towards each other with a Gravity
    constraint in each sub-model, its nodes given by a start index: each cube falls its own way
    (u_n = g Δt² n(n + 1)/2 from rest under central differences, no damping), not both one way."""
    X, T = box_tets((0.02, 0.02, 0.02), (2, 2, 2))
    n = len(X)

    def sub(move, direction):
        return (
            f'<SubModel>{_inline(X + move, T)}<ElementSet Size="all">{MATERIAL}0</ElementSet>'
            f'<Constraint Type="Gravity" LoadShape="STEP" NumNodes="{n}"><Nodes>0</Nodes>'
            f"<AccelerationMagnitude>0.3</AccelerationMagnitude>"
            f"<AccelerationDirection>{direction}</AccelerationDirection></Constraint></SubModel>"
        )

    p = tmp_path / "cubes.xml"
    p.write_text(
        f'<?xml version="1.0"?><Model>{sub([0, 0, 0.05], "0 0 -1")}{sub([0, 0, -0.05], "0 0 2")}'
        f"{SYSTEM.replace('<DampingCoeff>20', '<DampingCoeff>0')}</Model>"
    )
    sc = load_niftysim(p)
    sim = pl.Simulation(sc.builder.finalize("float64"), dt=sc.dt)
    sim.run(steps=100)
    fall = 0.3 * sc.dt**2 * 100 * 101 / 2
    assert np.allclose(sim.displacements[:n], [0, 0, -fall], rtol=1e-12, atol=1e-18)
    assert np.allclose(sim.displacements[n:], [0, 0, fall], rtol=1e-12, atol=1e-18)
    p.write_text(p.read_text().replace(f'NumNodes="{n}"><Nodes>0</Nodes>', "><Nodes></Nodes>", 1))
    with pytest.raises(NiftySimError, match="lists no node"):
        load_niftysim(p)
