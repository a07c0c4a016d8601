"""A thin-walled surface (an organ's capsule: two sheets a wall apart, joined at the rims of its
openings) meshed as the solid inside its outer sheet (fill_shell). References: the closed-form
volumes of the spherical segments a thick-walled spherical bowl's outer sheet bounds; a thin
plate and a solid ball, refused by name; HuBMAP's liver capsule (examples/data), whose outer sheet
holds the organ: far more than its wall, less than its convex hull."""

import math
from pathlib import Path

import numpy as np
import pytest
import trimesh

import pliant as pl
from pliant.errors import MeshError
from pliant.scene import load_scene
from pliant.mesh.shell import opposite_faces, outer_sheet

R, WALL = 0.05, 0.001  # the bowl's outer radius and wall [m]
EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def _bowl(opening_deg: float, inside_out: bool = False, wall: float = WALL):
    """A spherical bowl of wall ``wall`` [m], its outer sheet a cap of polar angle ``opening_deg`` on
    a sphere of radius R about +z, its inner sheet R − wall, joined at the rim: a profile of 24 + 24
    points revolved in 64 sections. V [m] (n, 3), F (f, 3)."""
    a = np.linspace(0.0, math.radians(opening_deg), 24)
    outer = np.c_[R * np.sin(a), R * np.cos(a)]
    inner = np.c_[(R - wall) * np.sin(a), (R - wall) * np.cos(a)][::-1]
    m = trimesh.creation.revolve(np.r_[outer, inner], sections=64)
    F = np.asarray(m.faces)
    return np.asarray(m.vertices), (F[:, ::-1] if inside_out else F)


def _volume(X, T):
    e = X[T]
    return float(
        np.einsum("ij,ij->i", np.cross(e[:, 1] - e[:, 0], e[:, 2] - e[:, 0]), e[:, 3] - e[:, 0]).sum() / 6
    )


def _segment(opening_deg: float) -> float:
    """Volume [m³] of the spherical segment of radius R and height h = R(1 − cos θ): π h² (3R − h)/3."""
    h = R * (1.0 - math.cos(math.radians(opening_deg)))
    return math.pi * h * h * (3.0 * R - h) / 3.0


@pytest.mark.parametrize(
    "opening, inside_out", [(90, False), (120, False), (120, True)], ids=["hemisphere", "bag", "inside-out"]
)
def test_a_bowl_is_filled_to_the_segment_its_outer_sheet_bounds(opening, inside_out):
    """The tets fill the spherical segment under the outer sheet, its opening closed flat: a
    hemisphere (90°) or a bag closing to a third of its width (120°), whichever way the file winds.
    Tolerance 3 %: the 64-gon and 24-segment facets hold 0.5 % less, fTetWild's envelope moves the
    surface by ~0.1 mm (0.6 %), and the rim, one wall (2 % of R) wide, may end on either sheet."""
    V, F = _bowl(opening, inside_out)
    X, T, info = pl.mesh.surface_to_tets(V, F, edge_length=0.008, fill_shell=True)
    assert _volume(X, T) == pytest.approx(_segment(opening), rel=0.03)
    assert "kept the outer sheet" in info["shell"][0]


def test_a_bowl_whose_wall_is_thicker_than_its_triangles_is_filled_too():
    """A 1 cm wall under triangles of about 4.5 mm: the faces within three edges of a face are on
    its own sheet (fewer than PAIRED of them find an opposite there), so the rays look deeper, along
    points down the ray. The tets fill the same segment (3 %, as above) and the wall is measured
    (1 %: the facets of the two sheets lie at slightly different depths)."""
    from pliant.mesh.shell import PAIRED

    V, F = _bowl(120, wall=0.01)
    Vr, Fr, _ = pl.mesh.repair_surface(V, F)
    assert np.mean(opposite_faces(Vr, Fr)[0] >= 0) < PAIRED  # the near search alone would refuse it
    X, T, info = pl.mesh.surface_to_tets(V, F, edge_length=0.008, fill_shell=True)
    assert _volume(X, T) == pytest.approx(_segment(120), rel=0.03)
    assert float(info["shell"][0].split("wall ")[1].split(" m")[0]) == pytest.approx(0.01, rel=0.01)


def test_a_hollow_sphere_with_a_thin_wall_is_filled_to_the_ball():
    """A capsule without openings, its inner sheet a closed surface of its own (a cavity facing in,
    1 mm inside the outer one): the two sheets are one shell, and the solid is the ball (4/3 π R³;
    tolerance 3 %: the icosphere holds 0.6 % less, fTetWild's envelope ~0.6 %)."""
    outer = trimesh.creation.icosphere(subdivisions=4, radius=R)
    inner = trimesh.creation.icosphere(subdivisions=4, radius=R - WALL)
    V = np.vstack([outer.vertices, inner.vertices])
    F = np.vstack([outer.faces, inner.faces[:, ::-1] + len(outer.vertices)])
    X, T, info = pl.mesh.surface_to_tets(V, F, edge_length=0.008, fill_shell=True)
    assert _volume(X, T) == pytest.approx(4 / 3 * math.pi * R**3, rel=0.03)
    note = info["shell"][0]
    assert f"({len(outer.faces)} of {len(F)} faces" in note  # the outer sphere, whole
    assert float(note.split("wall ")[1].split(" m")[0]) == pytest.approx(WALL, rel=0.01)


def test_each_face_of_a_bowl_finds_the_other_sheet_a_wall_away():
    """The rays along the inward normals cross the wall: the distance to the opposite face is the
    wall, 1 mm (to 2 %: the facets of the two sheets lie at slightly different depths), for all
    faces but the rim's."""
    V, F = _bowl(90)
    V, F, _ = pl.mesh.repair_surface(V, F)
    opposite, depth = opposite_faces(V, F)
    found = opposite >= 0
    assert found.mean() > 0.95
    assert np.median(depth[found]) == pytest.approx(WALL, rel=0.02)


def test_a_thin_plate_is_refused_as_not_a_capsule():
    """A disc 10 cm across and 1 mm thick is thin-walled, but its two sheets do not nest (each one's winding
    number at the other is about ½): there is no inside to fill."""
    r = np.linspace(0.0, R, 24)
    profile = np.r_[np.c_[r, np.zeros_like(r)], np.c_[r[::-1], np.full_like(r, WALL)]]
    plate = trimesh.creation.revolve(profile, sections=64)
    with pytest.raises(MeshError, match="do not nest.*thin plate"):
        pl.mesh.surface_to_tets(plate.vertices, plate.faces, edge_length=0.01, fill_shell=True)


def test_a_solid_ball_is_refused_as_not_a_shell():
    """A ball's faces find no face facing them within three edges, nor deeper (their rays cross
    the ball, beyond a tenth of its size): not a shell."""
    ball = trimesh.creation.icosphere(subdivisions=3, radius=0.05)
    with pytest.raises(MeshError, match="not a thin-walled shell: 0 % of its faces"):
        outer_sheet(ball.vertices, ball.faces)


def test_the_liver_capsule_is_filled_to_an_organ():
    """HuBMAP's liver capsule encloses 74 cm³ of wall (two sheets 0.9 mm apart); the solid inside its
    outer sheet must hold far more (over 10 times) and stay within the capsule's convex hull. The
    outer sheet is about half the capsule's faces."""
    V, F = pl.mesh.read_surface(EXAMPLES / "data" / "liver.obj")
    capsule = trimesh.Trimesh(V, F)
    X, T, info = pl.mesh.surface_to_tets(V, F, edge_length=0.02, fill_shell=True)
    vol = _volume(X, T)
    assert 10 * abs(capsule.volume) < vol < capsule.convex_hull.volume
    kept, total = map(int, info["shell"][0].split("(")[1].split(" faces")[0].split(" of "))
    assert 0.45 < kept / total < 0.55


def test_scenes_and_the_command_line_take_fill_shell(tmp_path, pliant_cli):
    """``[mesh] fill_shell = true`` and ``pliant mesh tetrahedralize --fill-shell`` mesh the bowl
    solid, ``pliant mesh repair --fill-shell`` writes that solid's closed surface; the key on a
    primitive is refused by name (it would change nothing)."""
    import meshio

    V, F = _bowl(90)
    trimesh.Trimesh(V, F).export(tmp_path / "bowl.stl")
    material = '[[material]]\ntype = "neo-hookean"\nE = 1e4\nnu = 0.3\ndensity = 1000.0\n'
    scene = tmp_path / "bowl.toml"
    scene.write_text('[mesh]\nfile = "bowl.stl"\nedge_length = 0.008\nfill_shell = true\n' + material)
    m = load_scene(scene).builder.finalize("float64")
    assert float(np.sum(m.element_volumes())) == pytest.approx(_segment(90), rel=0.03)
    r = pliant_cli(
        "mesh",
        "tetrahedralize",
        tmp_path / "bowl.stl",
        tmp_path / "bowl.vtu",
        "--edge-length",
        0.008,
        "--fill-shell",
    )
    assert r.returncode == 0, r.stderr
    out = meshio.read(tmp_path / "bowl.vtu")
    assert _volume(out.points, out.cells_dict["tetra"]) == pytest.approx(_segment(90), rel=0.03)
    r = pliant_cli("mesh", "repair", tmp_path / "bowl.stl", tmp_path / "solid.stl", "--fill-shell")
    assert r.returncode == 0 and "kept the outer sheet" in r.stdout, r.stderr
    solid = trimesh.load(tmp_path / "solid.stl")  # the hemisphere's closed surface
    assert solid.is_watertight and solid.volume == pytest.approx(_segment(90), rel=0.03)
    scene.write_text('[mesh]\nprimitive = "sphere"\nradius = 0.05\nfill_shell = true\n' + material)
    r = pliant_cli("run", scene, "-o", tmp_path / "o")
    assert r.returncode == 2 and "mesh.fill_shell" in r.stderr and "Traceback" not in r.stderr


def test_check_notes_a_thin_walled_surface():
    """`check_surface` (``pliant mesh check``) notes walls of 2 × volume / area under 2 % of the
    diagonal, pointing to fill_shell: the bowl's are its 1 mm wall (to 5 %: the rim's area); a ball
    has none, and the note is no problem."""
    V, F, _ = pl.mesh.repair_surface(*_bowl(90))
    rep = pl.mesh.check_surface(V, F)
    assert rep.ok and len(rep.notes) == 1 and "--fill-shell" in rep.notes[0]
    wall = float(rep.notes[0].split("walls about ")[1].split(" m")[0])
    assert wall == pytest.approx(WALL, rel=0.05)
    ball = trimesh.creation.icosphere(subdivisions=3, radius=0.05)
    assert pl.mesh.check_surface(ball.vertices, ball.faces).notes == []
