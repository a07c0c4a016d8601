"""NiftySim membranes (<ShellElements> with <ShellElementSet>, user guide v2.4 §3.6;
pliant.io.niftysim_membranes): an H8 bar wrapped in Linear membranes (listed as quadrilaterals and
as triangles) stretched to the uniaxial closed form of both; SURFACE's facets and their mass; the
file's mistakes named; NiftySim's shell test model without bending stiffness against the closed form."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from test_niftysim_h8 import _bar_xml

import pliant as pl
from pliant.io.niftysim import NiftySimError, load_niftysim
from pliant.mesh.topology import boundary_faces

L, A = 0.06, 0.01  # the bar of _bar_xml: 0.06 × 0.01 × 0.01 m, 6 hexahedra along x
nums = lambda a: " ".join(str(v) for v in np.ravel(a))  # noqa: E731


def _long_faces(n=6) -> np.ndarray:
    """The bar's four long faces as quadrilaterals (4 n, 4) over _bar_xml's nodes 4i + 2j + k."""
    node = lambda i, j, k: 4 * i + 2 * j + k  # noqa: E731
    Q = []
    for i in range(n):
        Q += [
            [node(i, 0, 0), node(i + 1, 0, 0), node(i + 1, 0, 1), node(i, 0, 1)],  # y = 0
            [node(i, 1, 0), node(i, 1, 1), node(i + 1, 1, 1), node(i + 1, 1, 0)],  # y = A
            [node(i, 0, 0), node(i, 1, 0), node(i + 1, 1, 0), node(i + 1, 0, 0)],  # z = 0
            [node(i, 0, 1), node(i + 1, 0, 1), node(i + 1, 1, 1), node(i, 1, 1)],  # z = A
        ]
    return np.array(Q)


def _assert_frames_follow(mine: np.ndarray, theirs: np.ndarray, steps_a_frame: int) -> None:
    """pliant's U.txt frames (3N, frames) against NiftySim's from the second on: each within one
    step's motion (pliant's frame k is one step before NiftySim's, docs/scenes.md), estimated as
    NiftySim's motion since its frame before over the steps a frame, plus 0.5 % of NiftySim's
    largest displacement at that frame."""
    for k in range(1, theirs.shape[1]):
        a, b = theirs[:, k].reshape(-1, 3), mine[:, k].reshape(-1, 3)
        one_step = np.linalg.norm(a - theirs[:, k - 1].reshape(-1, 3), axis=1).max() / steps_a_frame
        assert np.linalg.norm(a - b, axis=1).max() < one_step + 0.005 * np.linalg.norm(a, axis=1).max(), k


def _shells(kind: str, facets: np.ndarray, material: str, sets: str | None = None) -> str:
    sets = sets or f'<ShellElementSet Size="all">{material}</ShellElementSet>'
    listed = nums(facets) if kind != "SURFACE" else ""
    return f'<ShellElements Type="{kind}">{listed}</ShellElements>{sets}'


LINEAR = '<Material Type="Linear">6000 0.3<Density>900</Density><Thickness>0.0005</Thickness></Material>'


def _stretched_bar(tmp_path, shells: str, stretch=1.1):
    """_bar_xml's LE bar (E = 3 kPa, ν = 0.3, on rollers) with ``shells``, its end x = L moved to
    ``stretch`` L, relaxed; returns the model, simulation and the end's nodes."""
    xml, X = _bar_xml(material="LE")
    end = np.nonzero(np.abs(X[:, 0] - L) < 1e-12)[0]
    disp = (
        f'<Constraint DOF="0" Type="Disp" NumNodes="{len(end)}" LoadShape="RAMP"><Nodes>{nums(end)}</Nodes>'
        f'<Magnitudes Type="UNIFORM">{(stretch - 1) * L!r}</Magnitudes></Constraint>'
    )
    xml = xml.replace("<SystemParams>", disp + shells + "<SystemParams>")
    p = tmp_path / "bar.xml"
    p.write_text(xml)
    scene = load_niftysim(p)
    model = scene.builder.finalize("float64")
    sim = pl.Simulation(model, dt=scene.dt)
    sim.run(until=scene.duration)
    sim.relax(tol=1e-10, max_steps=200_000)
    return model, sim, end


@pytest.mark.parametrize("kind", ["Q4", "T3"])
def test_a_bar_wrapped_in_linear_membranes_stretches_as_its_closed_form(tmp_path, kind):
    """NiftySim's LE (St Venant–Kirchhoff) bar and Linear membranes of the same ν on its four long
    faces contract alike, so a 10 % stretch stays homogeneous and the end's pull is
    λ E_xx (E A² + E_m h 4 A) (uniaxial stress in Green strain for both; the membranes carry 80 % of
    it). Q4 facets are split in two; T3 lists the same triangles. Relaxed to 1e-10: 1e-6."""
    Q = _long_faces()
    facets = Q if kind == "Q4" else pl.mesh.split.split_quads(Q)
    model, sim, end = _stretched_bar(tmp_path, _shells(kind, facets, LINEAR))
    assert model.n_membranes == 2 * len(Q)
    lam = 1.1
    Exx = (lam**2 - 1) / 2
    expected = lam * Exx * (3000.0 * A * A + 6000.0 * 0.0005 * 4 * A)
    pull = model.internal_forces(sim.state)[end, 0].sum()
    assert pull == pytest.approx(expected, rel=1e-6)
    lateral = np.sqrt(1 - 2 * 0.3 * Exx)
    X = model.reference_positions
    np.testing.assert_allclose(sim.displacements[:, 1], (lateral - 1) * X[:, 1], atol=1e-6 * A)


def test_surface_membranes_cover_the_boundary_and_add_their_mass(tmp_path):
    """Type="SURFACE" wraps the whole boundary of the split mesh (its triangles); the model's mass is
    the bar's ρ V plus ρ h times the bar's surface area, 4 L A + 2 A²."""
    xml, X = _bar_xml()
    nh = '<Material Type="NeoHookean">500<Density>800</Density><Thickness>0.001</Thickness></Material>'
    xml = xml.replace("<SystemParams>", _shells("SURFACE", np.zeros(0), nh) + "<SystemParams>")
    p = tmp_path / "surface.xml"
    p.write_text(xml)
    model = load_niftysim(p).builder.finalize("float64")
    assert model.n_membranes == len(boundary_faces(model.tets)[0])
    expected = 1000.0 * L * A * A + 800.0 * 0.001 * (4 * L * A + 2 * A * A)
    assert model.mass.sum() == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize(
    "shells, match",
    [
        (
            _shells(
                "T3",
                [0, 1, 2],
                '<Material Type="LinearThickShell">1 0.3 1 0.3<Density>1</Density>'
                "<Thickness>1</Thickness></Material>",
            ),
            "unsupported NiftySim feature ShellElementSet Material Type=LinearThickShell: thick shells",
        ),
        (
            _shells(
                "T3",
                [0, 1, 2],
                '<Material Type="NeoHookean"><Density>10</Density><Thickness>1</Thickness></Material>',
            ),
            r"NeoHookean takes 1 parameter\(s\) \(mu\); got 0",
        ),
        (
            _shells("T3", [0, 1, 2], '<Material Type="Linear">1 0.3<Density>1</Density></Material>'),
            "<Thickness> is missing",
        ),
        (_shells("T3", [0, 1, 99], LINEAR), "shell element 0 refers to node 99"),
        (_shells("T3", [0, 1], LINEAR), "holds 2 node numbers; expected 3 per facet"),
        (
            _shells(
                "T3", [0, 1, 2, 0, 2, 3], LINEAR, f'<ShellElementSet Size="1">{LINEAR}0</ShellElementSet>'
            ),
            "shell element 1 is in no <ShellElementSet>",
        ),
        (
            _shells(
                "SURFACE", np.zeros(0), LINEAR, f'<ShellElementSet Size="2">{LINEAR}0 1</ShellElementSet>'
            ),
            'the facets come in no fixed order .*expected Size="all"',
        ),
        (
            _shells(
                "T3",
                [0, 1, 2],
                '<Material Type="Linear">1 0.7<Density>1</Density><Thickness>1</Thickness></Material>',
            ),
            "nu = 0.7; expected -1 < nu <= 0.5",
        ),
        (_shells("T3", [0, 1, 1], LINEAR), "membrane 0 .* is degenerate"),
        (
            _shells(
                "T3",
                [0, 1, 2],
                '<Material Type="Linear">1 1e400<Density>1</Density><Thickness>1</Thickness></Material>',
            ),
            r"'1e400' \(number 2 of 2\) is inf; expected finite numbers",
        ),
        (_shells("Q8", [0, 1, 2], LINEAR), "expected T3, Q4 or SURFACE"),
        (
            _shells(
                "T3",
                [0, 1, 2],
                '<Material Type="LinearShell">1 0.3 0<Density>1</Density><Thickness>1</Thickness></Material>',
            ),
            r"LinearShell takes 4 parameter\(s\) \(E, nu, E_b, nu_b\); got 3",
        ),
        (  # as a solid's <ElasticParams> is checked
            _shells(
                "T3",
                [0, 1, 2],
                '<Material Type="LinearShell"><ElasticParams NumParams="2">1 0.3 0 0</ElasticParams>'
                "<Density>1</Density><Thickness>1</Thickness></Material>",
            ),
            r'<ElasticParams NumParams="2"> holds 4 value\(s\); expected as many as it declares',
        ),
    ],
)
def test_membrane_mistakes_are_named(tmp_path, shells, match):
    """Each mistake in a model's membranes is a NiftySimError naming the file (once), the element
    and what was expected."""
    xml, _ = _bar_xml()
    p = tmp_path / "bad.xml"
    p.write_text(xml.replace("<SystemParams>", shells + "<SystemParams>"))
    with pytest.raises(NiftySimError, match=match) as e:
        load_niftysim(p)
    assert str(e.value).count(str(p)) == 1, str(e.value)


def test_an_ignored_shell_set_runs_the_solid_alone(tmp_path):
    """--ignore for a LinearThickShell set skips its facets with a warning; the bar runs."""
    xml, _ = _bar_xml()
    shell = (
        '<Material Type="LinearThickShell">1 0.3 1 0.3<Density>1</Density><Thickness>1</Thickness></Material>'
    )
    p = tmp_path / "shell.xml"
    p.write_text(xml.replace("<SystemParams>", _shells("T3", [0, 1, 2], shell) + "<SystemParams>"))
    sc = load_niftysim(p, ignore=("ShellElementSet Material Type=LinearThickShell",))
    assert sc.builder.n_membranes == 0 and any("no membrane" in w for w in sc.warnings)


def test_niftysims_membrane_example_runs_as_niftysim_ran_it(tmp_path):
    """NiftySim's models/box_membrane_nonlin.xml (an NH box wrapped in its whole surface of
    NeoHookean membranes, μ = 500 Pa, h = 0.05 m, pushed 0.27 m by nodal forces over 1 s) against
    the U.txt NiftySim itself wrote for it (tests/data/README.md). pliant's frame k is one step
    before NiftySim's (docs/scenes.md), so each frame may differ by one step's motion, estimated as
    a hundredth (100 steps a frame) of NiftySim's motion since its frame before, plus 0.5 % of its
    largest displacement (measured beyond the step: 0.09–0.31 % at frames 1–9, float32 both; the
    first frame, where the motion grows as t³ and the estimate is poor, is left out)."""
    from typer.testing import CliRunner

    from pliant.cli import app

    data = Path(__file__).parent / "data"
    out = tmp_path / "out"
    r = CliRunner().invoke(app, ["run", str(data / "niftysim_box_membrane_nonlin.xml"), "-o", str(out)])
    assert r.exit_code == 0, r.output
    mine = np.loadtxt(out / "U.txt")
    theirs = np.loadtxt(data / "niftysim_box_membrane_nonlin_U.txt")
    assert mine.shape == theirs.shape == (3 * 555, 10)
    import meshio

    frame = meshio.read(sorted(out.glob("frame_*.vtu"))[-1])  # the tets and the membranes, each with theirs
    assert [c.type for c in frame.cells] == ["tetra", "triangle"]
    von_mises, tension = frame.cell_data["von_mises"], frame.cell_data["membrane_max_tension"]
    assert np.isfinite(von_mises[0]).all() and np.isnan(von_mises[1]).all()
    assert np.isnan(tension[0]).all() and np.isfinite(tension[1]).all()
    _assert_frames_follow(mine, theirs, steps_a_frame=100)


def test_linear_membranes_warn_of_niftysims_missing_area_and_thickness(tmp_path):
    """NiftySim's Linear membranes leave the facet's area A and thickness h out of their forces
    (tledElementMembraneSimpleLinear::ComputeForces): the import says by how much NiftySim's differ,
    1/(A h) — for the bar's long-face triangles A = 0.01²/2 m², h = 0.5 mm: 4e7 m⁻³."""
    xml, _ = _bar_xml()
    p = tmp_path / "linear.xml"
    p.write_text(xml.replace("<SystemParams>", _shells("Q4", _long_faces(), LINEAR) + "<SystemParams>"))
    warnings = load_niftysim(p).warnings
    factor = f"{1 / (0.5 * A * A * 0.0005):.4g}"
    assert any(f"here {factor} to {factor}" in w and "NiftySim's Linear membranes" in w for w in warnings)


def test_niftysims_membrane_only_test_model_runs_as_niftysim_ran_it(tmp_path):
    """NiftySim's testing/data/membrane_stretch_nonlinear_irregular.xml: a sheet of NeoHookean
    membrane triangles alone (no tets, <Elements NumEls="0">), irregularly meshed, one edge fixed
    and the other moved 1 cm, against the U.txt NiftySim wrote for it (tests/data/README.md): each
    frame within one step's motion plus 0.5 % of NiftySim's largest displacement (measured
    0.02–0.3 % in all), the frames holding the membranes as triangles (no tets)."""
    import meshio
    from typer.testing import CliRunner

    from pliant.cli import app

    data = Path(__file__).parent / "data"
    out = tmp_path / "out"
    model = data / "niftysim_membrane_stretch_nonlinear_irregular.xml"
    r = CliRunner().invoke(app, ["run", str(model), "-o", str(out)])
    assert r.exit_code == 0, r.output
    mine, theirs = np.loadtxt(out / "U.txt"), np.loadtxt(data / f"{model.stem}_U.txt")
    assert mine.shape == theirs.shape == (360, 10)
    _assert_frames_follow(mine, theirs, steps_a_frame=400)
    frame = meshio.read(sorted(out.glob("frame_*.vtu"))[-1])
    assert [c.type for c in frame.cells] == ["triangle"] and len(frame.cells[0].data) == 198
    tension = frame.cell_data["membrane_max_tension"][0]  # closed-form values: tests/test_membrane.py
    assert tension.shape == (198,) and np.isfinite(tension).all() and np.median(tension) > 0
    # the last frame's membrane energies make up the run's strain energy (no tets; float32 sums)
    energy = frame.cell_data["membrane_energy"][0]
    summary = json.loads((out / "summary.json").read_text())
    np.testing.assert_allclose(energy.sum(), summary["strain_energy"], rtol=1e-5)
    assert summary["strain_energy"] > 0
    assert (out / "result.png").stat().st_size > 0
    # pliant view draws it, live and played back: tests/test_viewer.py


def test_niftysims_shell_test_model_without_bending_stretches_as_its_closed_form(tmp_path):
    """NiftySim's testing/data/membrane_force_stretch_shell.xml: a 1 m square sheet of its
    rotation-free shell triangles ("LinearShell", E = 1000 Pa, ν = 0.495, 1 m thick, no bending
    stiffness: E_b = 0), the edge x = 0 on rollers, 25 N pulling the edge x = 1 (damped, 30 s):
    imported as the St Venant–Kirchhoff membrane it is without bending, it settles at the uniaxial
    closed form, λ (E (λ² − 1)/2) h = 25 N/m with the sides free to contract by
    √(1 − ν (λ² − 1)): both to 1e-5 (float32, settled); and NiftySim's own U.txt for it (its shell
    element, tests/data/README.md): every frame within one step's motion plus 0.5 %, the last
    within 1e-4 of the largest displacement (measured 1.7e-5: both float32); the summary's
    membrane tension is the pull over the contracted width."""
    from scipy.optimize import brentq
    from typer.testing import CliRunner

    from pliant.cli import app

    model = Path(__file__).parent / "data" / "niftysim_membrane_force_stretch_shell.xml"
    out = tmp_path / "out"
    r = CliRunner().invoke(app, ["run", str(model), "-o", str(out)])
    assert r.exit_code == 0, r.output
    mine, theirs = np.loadtxt(out / "U.txt"), np.loadtxt(model.with_name(f"{model.stem}_U.txt"))
    assert mine.shape == theirs.shape == (363, 10)
    _assert_frames_follow(mine, theirs, steps_a_frame=3000)
    assert np.abs(mine[:, -1] - theirs[:, -1]).max() < 1e-4 * np.abs(theirs[:, -1]).max()
    u = mine[:, -1].reshape(-1, 3)  # the last frame, 121 nodes (11 × 11)
    X = np.array([[i / 10, j / 10, 0.0] for i in range(11) for j in range(11)])
    lam = brentq(lambda l: l * 1000 * (l * l - 1) / 2 - 25, 1.0, 2.0)
    pulled = np.isclose(X[:, 0], 1.0)
    np.testing.assert_allclose(u[pulled, 0], lam - 1, rtol=1e-5)
    width = np.ptp((X[:, 1] + u[:, 1])[pulled])
    np.testing.assert_allclose(width, np.sqrt(1 - 0.495 * (lam**2 - 1)), rtol=1e-5)
    # The summary's tension is Cauchy's, per current width: 25 N over the contracted width,
    # uniform (float32, settled: 1e-4; measured 8e-6).
    summary = json.loads((out / "summary.json").read_text())
    np.testing.assert_allclose(
        summary["max_membrane_tension"], 25 / np.sqrt(1 - 0.495 * (lam**2 - 1)), rtol=1e-4
    )
    assert summary["max_von_mises"] == 0.0  # no tets


def test_a_shell_models_step_beyond_its_membranes_is_divided(tmp_path):
    """The same model with NiftySim's TimeStep set to 5 ms, above the stable step of its membranes
    (about 1.9 ms: NiftySim's step suits its own shell elements): `pliant run` runs each step as
    the fewest steps that are stable (3), says so, and writes U.txt at NiftySim's times (every
    3000 of its steps: 15 and 30 s); the
    sheet settles at the same closed form (1e-5)."""
    from scipy.optimize import brentq
    from typer.testing import CliRunner

    from pliant.cli import app

    model = Path(__file__).parent / "data" / "niftysim_membrane_force_stretch_shell.xml"
    out = tmp_path / "out"
    r = CliRunner().invoke(app, ["run", str(model), "-o", str(out), "--set", "SystemParams.TimeStep=5e-3"])
    assert r.exit_code == 0, r.output
    said = json.loads((out / "summary.json").read_text())["warnings"]
    assert any(
        "shell triangles run as constant-strain membranes; each step runs as 3 steps" in w for w in said
    )
    U = np.loadtxt(out / "U.txt")
    assert U.shape == (363, 2)  # Freq = 3000 of its 6000 steps: 15 s and 30 s, as NiftySim's
    lam = brentq(lambda l: l * 1000 * (l * l - 1) / 2 - 25, 1.0, 2.0)
    np.testing.assert_allclose(U[3 * 110 :: 3][:11, -1], lam - 1, rtol=1e-5)


def test_a_sub_models_surface_membranes_run_as_niftysim_ran_them(tmp_path):
    """tests/data/niftysim_box_submodels.xml: box_membrane_nonlin.xml as the second of two
    sub-models, after a fixed cube wrapped in its own SURFACE membranes, against the U.txt NiftySim
    wrote for it: the merged node numbering (the cube's 8 nodes first), each sub-model's surface
    as its membranes, the box's constraints mapped. Each frame within one step's motion plus 0.5 %
    of NiftySim's largest displacement, as for the model written whole above (measured 0.30 % at
    the end); the cube's nodes do not move."""
    from typer.testing import CliRunner

    from pliant.cli import app

    data = Path(__file__).parent / "data"
    sc = load_niftysim(data / "niftysim_box_submodels.xml")
    cube_surface = 12  # a cube of 6 tets: two triangles a face
    assert sc.builder.n_membranes == cube_surface + len(
        boundary_faces(load_niftysim(data / "niftysim_box_membrane_nonlin.xml").builder.tets)[0]
    )
    out = tmp_path / "out"
    r = CliRunner().invoke(app, ["run", str(data / "niftysim_box_submodels.xml"), "-o", str(out)])
    assert r.exit_code == 0, r.output
    mine, theirs = np.loadtxt(out / "U.txt"), np.loadtxt(data / "niftysim_box_submodels_U.txt")
    assert mine.shape == theirs.shape == (3 * (8 + 555), 10)
    assert not mine[:24].any()
    _assert_frames_follow(mine, theirs, steps_a_frame=100)


def test_deformable_contact_takes_a_sheet_apart_and_refuses_one_joined_by_name(tmp_path):
    """NiftySim's deformable contact holds its membranes (two_cubes_sheet.xml drops two cubes onto
    a sheet). A sheet apart from the tets is a body of its own in pliant's soft contact (the
    cube body 0, the sheet body 1; tests/test_sheet_contact.py); a sheet joined to the solid by a
    node (a flap) is not, so bodies would pass through it: refused naming MembraneContact;
    ignored, it runs with a warning from the builder. Membranes on the solid's own surface
    (SURFACE) are no such case."""
    X, T = pl.mesh.box_tets((0.02, 0.02, 0.02), (1, 1, 1))
    sheet = np.array([[0, 0, 0.03], [0.02, 0, 0.03], [0, 0.02, 0.03]])
    nh = '<Material Type="NH"><ElasticParams NumParams="2">1000 20000</ElasticParams></Material>'
    neo = '<Material Type="NeoHookean">500<Density>10</Density><Thickness>0.001</Thickness></Material>'
    system = (
        "<SystemParams><TimeStep>1e-4</TimeStep><TotalTime>0.001</TotalTime><DampingCoeff>10"
        "</DampingCoeff><Density>1000</Density><DoDeformableCollision>1</DoDeformableCollision></SystemParams>"
    )

    def model(nodes, shells):
        return (
            f'<Model><Nodes DOF="3" NumNodes="{len(nodes)}">{nums(nodes)}</Nodes>'
            f'<Elements NumEls="{len(T)}" Type="T4">{nums(T)}</Elements><ElementSet Size="all">{nh}'
            f"</ElementSet>{shells}{system}</Model>"
        )

    p = tmp_path / "sheet.xml"
    p.write_text(model(np.vstack([X, sheet]), _shells("T3", [[8, 9, 10]], neo)))
    assert load_niftysim(p).builder.finalize("float64").contact_pairs == [(0, 1)]
    p.write_text(model(np.vstack([X, sheet]), _shells("T3", [[7, 9, 10]], neo)))  # node 7: the cube's
    with pytest.raises(NiftySimError, match="MembraneContact: 1 membrane"):
        load_niftysim(p)
    sc = load_niftysim(p, ignore=("MembraneContact",))
    with pytest.warns(pl.PliantWarning, match="1 membrane.*joined to them.*take no part in soft contact"):
        sc.builder.finalize("float64")
    p.write_text(model(X, _shells("SURFACE", [], neo)))
    assert load_niftysim(p).builder.n_membranes == 12
