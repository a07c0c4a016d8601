"""NiftySim H8 models (user guide v2.4 §3.2.2), run as tetrahedra: each hexahedron split into 6
(pliant.mesh.split), element sets, Quad faces and sub-models mapped onto them, T4ANP where the
materials allow it.

References: the user guide's own first example (read from ../shared/niftysim/userguide.txt: one
H8 stretched by 30 %) against the closed-form stress and energy of its homogeneous stretch; a bar on
rollers under an end pressure or traction on Quad faces, whose uniaxial stress state is exact for
any element, u(L) = (λ − 1) L with λ the uniaxial stretch of the material's closed form; hexahedra's
volumes in closed form."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

import pliant as pl
from pliant.cli import app
from pliant.io.niftysim import load_niftysim
from pliant.mesh.primitives import tet_volumes

GUIDE = Path(__file__).resolve().parents[2] / "shared" / "niftysim" / "userguide.txt"
BOX8 = Path(__file__).parent / "data" / "niftysim_box8.msh"  # NiftySim's own H8 test mesh
runner = CliRunner()
# Relative tolerance on a relaxed displacement: relax() stops at a residual of 1e-10 of the load.
RELAXED = 1e-6


def _guide_example() -> str:
    """The XML of the user guide's §3.1 example ("A simple example is given below"), as printed
    there, less the page break and page number of the text rendering inside it."""
    if not GUIDE.exists():
        pytest.skip(f"NiftySim's user guide {GUIDE} not available (../shared beside the checkout)")
    text = GUIDE.read_text(encoding="utf-8", errors="replace")
    start = text.index("<?xml", text.index("A simple example is given below"))
    body = text[start : text.index("</Model>", start) + len("</Model>")]
    lines = [ln.replace("\f", "") for ln in body.split("\n")]
    return "\n".join(ln for ln in lines if ln.strip() and not re.fullmatch(r"\s*\d+\s*", ln))


def _nh_cauchy(F, mu, K):
    """σ = μ J^(−5/3) dev(F Fᵀ) + K (J − 1) I: NiftySim's NH (decoupled Neo-Hookean), Voigt order."""
    J = np.linalg.det(F)
    b = F @ F.T
    sig = mu * J ** (-5 / 3) * (b - np.trace(b) / 3 * np.eye(3)) + K * (J - 1) * np.eye(3)
    return sig[[0, 1, 2, 0, 1, 0], [0, 1, 2, 1, 2, 2]]


def test_the_user_guides_h8_example_runs_as_its_closed_form(tmp_path):
    """§3.1: a 0.1 m cube, one H8 element, NH (μ = 1052, K = 52249 Pa), x stretched by 0.03 m
    (POLY345) with y and z held: F = diag(1.3, 1, 1) at the end, whatever the element. Every tet's
    Cauchy stress and the strain energy V W(F) = V (μ/2 (Ī₁ − 3) + K/2 (J − 1)²) against the
    closed form (1e-9 relative: float64 round-off); the run says it split the element and runs it
    as T4ANP; `pliant run` exits 0 (it crashed, exit 3, when no DOF was left free)."""
    p = tmp_path / "guide.xml"
    p.write_text(_guide_example())
    scene = load_niftysim(p)
    said = " ".join(scene.warnings)
    assert "1 H8 element split into 6 tetrahedra" in said and "T4ANP" in said and "HGKappa ignored" in said
    model = scene.builder.finalize("float64")
    sim = pl.Simulation(model, dt=scene.dt)
    sim.run(until=scene.duration)
    X = model.reference_positions
    np.testing.assert_allclose(sim.displacements[:, 0], 0.3 * X[:, 0], atol=1e-12)
    np.testing.assert_allclose(sim.displacements[:, 1:], 0.0, atol=0)
    F = np.diag([1.3, 1.0, 1.0])
    mu, K = 1052.0, 52249.0
    sig = model.element_results(sim.state)["cauchy"]
    np.testing.assert_allclose(sig, np.tile(_nh_cauchy(F, mu, K), (6, 1)), rtol=1e-9, atol=1e-9 * K)
    J = 1.3
    W = mu / 2 * (J ** (-2 / 3) * np.trace(F @ F.T) - 3) + K / 2 * (J - 1) ** 2
    assert sim.strain_energy() == pytest.approx(1e-3 * W, rel=1e-9)
    r = runner.invoke(app, ["run", str(p), "-o", str(tmp_path / "out")])
    assert r.exit_code == 0, r.output


def _uniaxial_stretch(sigma, material="NH"):
    """The axial stretch of a bar in uniaxial Cauchy stress σ [Pa] (closed form, solved here): F =
    diag(λ, t, t) with σ22 = 0 and σ11 = σ, for NiftySim's NH (μ = 1000, K = 20000: σ = μ J^(−5/3)
    dev(b) + K (J − 1) I) or LE (E = 3000, ν = 0.3: St Venant–Kirchhoff, S = λ tr(E) I + 2μ E,
    σ = F S Fᵀ / J)."""
    from scipy.optimize import fsolve

    def residual(v):
        lam, t = v
        J = lam * t * t
        if material == "NH":
            mu, K = 1000.0, 20000.0
            c = mu * J ** (-5 / 3)
            return [c * 2 * (lam**2 - t**2) / 3 + K * (J - 1) - sigma, c * (t**2 - lam**2) / 3 + K * (J - 1)]
        E, nu = 3000.0, 0.3
        la, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
        e1, e2 = (lam**2 - 1) / 2, (t**2 - 1) / 2
        S1, S2 = la * (e1 + 2 * e2) + 2 * mu * e1, la * (e1 + 2 * e2) + 2 * mu * e2
        return [lam**2 * S1 / J - sigma, t**2 * S2 / J]

    lam, t = fsolve(residual, [1.0, 1.0], xtol=1e-14)
    assert np.allclose(residual([lam, t]), 0, atol=1e-9 * abs(sigma))
    return lam


def _bar_xml(n=6, material="NH", load="", sets=None, quads_at_end=False) -> tuple[str, np.ndarray]:
    """An H8 bar 0.06 × 0.01 × 0.01 m of n hexahedra along x on rollers (x held at x = 0, y at
    y = 0, z at z = 0: a uniaxial stress state is exact), with ``load`` (constraints) added."""
    xs = np.linspace(0, 0.06, n + 1)
    X = np.array([[x, y, z] for x in xs for y in (0, 0.01) for z in (0, 0.01)])
    node = lambda i, j, k: 4 * i + 2 * j + k  # noqa: E731
    H = np.array(
        [
            [node(i, 0, 0), node(i + 1, 0, 0), node(i + 1, 1, 0), node(i, 1, 0)]
            + [node(i, 0, 1), node(i + 1, 0, 1), node(i + 1, 1, 1), node(i, 1, 1)]
            for i in range(n)
        ]
    )
    params = {"NH": "1000 20000", "LE": "3000 0.3"}[material]
    nums = lambda a: " ".join(str(v) for v in np.ravel(a))  # noqa: E731
    sets = sets or [(np.arange(n), material, params)]
    es = "".join(
        f'<ElementSet Size="{len(e)}"><Material Type="{m}"><ElasticParams NumParams="2">{p}</ElasticParams>'
        f"</Material>{nums(e)}</ElementSet>"
        for e, m, p in sets
    )

    def fix(dof, ids):
        head = f'<Constraint DOF="{dof}" Type="Fix" NumNodes="{len(ids)}">'
        return f"{head}<Nodes>{nums(ids)}</Nodes></Constraint>"

    at = lambda d, v: np.nonzero(np.abs(X[:, d] - v) < 1e-12)[0]  # noqa: E731
    xml = (
        f'<?xml version="1.0"?><Model><Nodes DOF="3" NumNodes="{len(X)}">{nums(X)}</Nodes>'
        f'<Elements NumEls="{n}" Type="H8">{nums(H)}</Elements>{es}'
        + fix(0, at(0, 0.0))
        + fix(1, at(1, 0.0))
        + fix(2, at(2, 0.0))
        + load
        + "<SystemParams><TimeStep>2e-5</TimeStep><TotalTime>0.2</TotalTime><DampingCoeff>200</DampingCoeff>"
        "<Density>1000</Density><HGKappa>0.075</HGKappa></SystemParams></Model>"
    )
    return xml, X


def _end_face(n=6) -> np.ndarray:
    """The bar's x = L face as a quad wound outward (+x): nodes (L,0,0), (L,.01,0), (L,.01,.01),
    (L,0,.01)."""
    i = n
    return np.array([4 * i, 4 * i + 2, 4 * i + 3, 4 * i + 1])


def _relaxed(tmp_path, xml, name="bar.xml"):
    p = tmp_path / name
    p.write_text(xml)
    scene = load_niftysim(p)
    model = scene.builder.finalize("float64")
    sim = pl.Simulation(model, dt=scene.dt)
    sim.run(until=scene.duration)  # the load ramps in; then hold
    sim.relax(tol=1e-10, max_steps=200_000)
    return scene, model, sim


@pytest.mark.parametrize("load", ["pressure", "traction"])
def test_quad_faces_of_an_h8_bar_carry_its_end_load(tmp_path, load):
    """A Pressure (p = 10 Pa, on the end face listed as one Quad) compresses the roller-supported
    NH bar, a DIFFORM Traction of 10 Pa along −x (NiftySim pulls against its vector) stretches it:
    u(L) = (λ − 1) L with λ the uniaxial stretch under σ = ∓10 Pa (closed form, _uniaxial_stretch;
    RELAXED: the relaxation's residual)"""
    q = " ".join(str(v) for v in _end_face())
    if load == "pressure":
        c = (
            '<Constraint Type="Pressure" LoadShape="RAMP" NumFaces="1" FaceType="Quad">'
            f"<Faces>{q}</Faces><Magnitude>10</Magnitude></Constraint>"
        )
    else:
        c = (
            '<Constraint Type="Traction" LoadShape="RAMP" NumFaces="1" FaceType="Quad">'
            f'<Faces>{q}</Faces><Magnitudes Type="DIFFORM">-10 0 0</Magnitudes></Constraint>'
        )
    xml, X = _bar_xml(load=c)
    scene, model, sim = _relaxed(tmp_path, xml)
    expected = (_uniaxial_stretch(-10.0 if load == "pressure" else 10.0) - 1) * 0.06
    end = np.abs(X[:, 0] - 0.06) < 1e-12
    assert sim.displacements[end, 0].mean() == pytest.approx(expected, rel=RELAXED)
    assert np.ptp(sim.displacements[end, 0]) < 1e-3 * abs(expected)  # the face moves as one


def test_element_sets_of_an_h8_model_hold_their_hexahedras_tetrahedra(tmp_path):
    """Two element sets (hexahedra 0-2 and 3-5) of different materials: each set's tets fill its
    three hexahedra (volume 3 × 1e-6 m³, closed form; their centroids in its half of the bar), and
    the bar runs."""
    n = 6
    sets = [(np.arange(3), "NH", "1000 20000"), (np.arange(3, 6), "NH", "3000 60000")]
    xml, X = _bar_xml(n=n, sets=sets)
    p = tmp_path / "sets.xml"
    p.write_text(xml)
    b = load_niftysim(p).builder
    assert len(b.tets) == 6 * n
    for s, (lo, hi) in zip(b.sets, [(0.0, 0.03), (0.03, 0.06)]):
        T = b.tets[s.elements]
        assert tet_volumes(X, T).sum() == pytest.approx(3e-6, rel=1e-12)
        c = X[T].mean(axis=1)[:, 0]
        assert c.min() > lo and c.max() < hi


def test_an_le_h8_model_runs_as_t4_and_says_so(tmp_path):
    """LE (NiftySim's St Venant–Kirchhoff) has no separate volumetric term: the split model runs
    as plain T4 and the warning says why; a homogeneous stretch is still exact (u(L) = (λ − 1) L,
    RELAXED as above)."""
    c = (
        '<Constraint Type="Traction" LoadShape="RAMP" NumFaces="1" FaceType="Quad">'
        f"<Faces>{' '.join(str(v) for v in _end_face())}</Faces>"
        '<Magnitudes Type="UNIFORM">-10 0 0</Magnitudes></Constraint>'
    )
    xml, X = _bar_xml(material="LE", load=c)
    scene, model, sim = _relaxed(tmp_path, xml)
    assert not model.nodal_pressure
    assert any("run as T4, since" in w and "StVenantKirchhoff" in w for w in scene.warnings)
    end = np.abs(X[:, 0] - 0.06) < 1e-12
    expected = (_uniaxial_stretch(10.0, "LE") - 1) * 0.06
    assert sim.displacements[end, 0].mean() == pytest.approx(expected, rel=RELAXED)


def test_h8_sub_models_merge_and_carry_their_quad_loads(tmp_path):
    """Two H8 sub-models, the bar's halves (three hexahedra each, with their own element sets and
    the end pressure on a Quad face of the second), merged at their shared face by
    SubModelNodeMergerDistance: the bar of the one-model test, u(L) = (λ − 1) L (RELAXED as there)."""
    xml, X = _bar_xml()
    nodes = re.search(r"<Nodes[^>]*>([^<]*)</Nodes>", xml).group(1).split()
    Xall = np.array(nodes, float).reshape(-1, 3)
    halves = []
    for part in (0, 1):
        ids = np.arange(12 * part, 12 * part + 16)  # 4 layers of 4 nodes
        H = np.array(
            [
                [4 * i, 4 * i + 4, 4 * i + 6, 4 * i + 2, 4 * i + 1, 4 * i + 5, 4 * i + 7, 4 * i + 3]
                for i in range(3)
            ]
        )
        load = ""
        if part == 1:
            load = (
                '<Constraint Type="Pressure" LoadShape="RAMP" NumFaces="1" FaceType="Quad">'
                "<Faces>12 14 15 13</Faces><Magnitude>10</Magnitude></Constraint>"
            )
        halves.append(
            '<SubModel><Nodes DOF="3" NumNodes="16">'
            f"{' '.join(repr(float(v)) for v in Xall[ids].ravel())}</Nodes>"
            f'<Elements NumEls="3" Type="H8">{" ".join(str(v) for v in H.ravel())}</Elements>'
            '<ElementSet Size="all"><Material Type="NH"><ElasticParams NumParams="2">1000 20000'
            f"</ElasticParams></Material>0</ElementSet>{load}</SubModel>"
        )
    fixes = "".join(re.findall(r'<Constraint DOF="\d" Type="Fix".*?</Constraint>', xml))
    system = re.search(r"<SystemParams>.*</SystemParams>", xml).group(0)
    merged = (
        f'<?xml version="1.0"?><Model>{"".join(halves)}<SubModelNodeMergerDistance>1e-6'
        f"</SubModelNodeMergerDistance>{fixes}{system}</Model>"
    )
    scene, model, sim = _relaxed(tmp_path, merged, "merged.xml")
    assert len(model.reference_positions) == len(Xall)  # the shared face's nodes merged
    end = np.abs(model.reference_positions[:, 0] - 0.06) < 1e-12
    assert end.sum() == 4
    expected = (_uniaxial_stretch(-10.0) - 1) * 0.06
    assert sim.displacements[end, 0].mean() == pytest.approx(expected, rel=RELAXED)


def test_niftysims_box8_h8_mesh_file_stretches_homogeneously(tmp_path):
    """NiftySim's box8.msh (12 hexahedra) as <MSHMesh Type="H8">, on rollers chosen by normal
    (SpecType="NORMAL" on the split mesh's boundary facets), its +x face pulled 10 % of the box's
    length: every node moves as the homogeneous stretch diag(λ, t, t), λ = 1.1 and t from σ22 = 0
    of NH (closed form), to RELAXED of the largest displacement."""
    import shutil

    from scipy.optimize import brentq

    shutil.copy(BOX8, tmp_path / "box8.msh")
    L = 1 / 6 + 0.5

    def on(normal, dof, kind="Fix", mag=""):
        spec = f'SpecType="NORMAL"><Normal ToleranceAngle="10">{normal}</Normal>'
        return f'<Constraint DOF="{dof}" Type="{kind}" LoadShape="RAMP" {spec}{mag}</Constraint>'

    xml = (
        '<?xml version="1.0"?><Model><MSHMesh Type="H8">box8.msh</MSHMesh><ElementSet Size="all">'
        '<Material Type="NH"><ElasticParams NumParams="2">1000 20000</ElasticParams></Material>0'
        "</ElementSet>"
        + on("-1 0 0", 0)
        + on("0 -1 0", 1)
        + on("0 0 -1", 2)
        + on("1 0 0", 0, "Disp", f'<Magnitudes Type="UNIFORM">{0.1 * L!r}</Magnitudes>')
        + "<SystemParams><TimeStep>1e-3</TimeStep><TotalTime>0.5</TotalTime><DampingCoeff>20"
        "</DampingCoeff><Density>1000</Density></SystemParams></Model>"
    )
    scene, model, sim = _relaxed(tmp_path, xml, "box8.xml")
    assert model.nodal_pressure and len(model.tets) == 72
    mu, K, lam = 1000.0, 20000.0, 1.1

    def sigma22(t):
        J = lam * t * t
        return mu * J ** (-5 / 3) * (t * t - lam * lam) / 3 + K * (J - 1)

    t = brentq(sigma22, 0.8, 1.0, xtol=1e-15)
    X = model.reference_positions
    expected = (X - X.min(axis=0)) * [lam - 1, t - 1, t - 1]
    np.testing.assert_allclose(sim.displacements, expected, atol=RELAXED * 0.1 * L)


def test_an_h8_time_step_too_large_for_the_split_tets_is_divided(tmp_path):
    """NiftySim's TimeStep suits its hexahedra; their tetrahedra can need a smaller one. `pliant
    run` divides it by the least integer k that is stable (the exact 2/ω_max check of the solver),
    keeps the output at NiftySim's times (Freq × TimeStep) and says so. The solver itself still
    refuses TimeStep and TimeStep / (k − 1), and takes TimeStep / k (k is the least)."""
    import json

    xml, X = _bar_xml(material="LE")
    big = xml.replace("<TimeStep>2e-5</TimeStep>", "<TimeStep>0.004</TimeStep>")
    big = big.replace("</SystemParams>", '</SystemParams><Output Freq="10"><Variable>U</Variable></Output>')
    p = tmp_path / "big.xml"
    p.write_text(big)
    r = runner.invoke(app, ["run", str(p), "-o", str(tmp_path / "out")])
    assert r.exit_code == 0, r.output
    s = json.loads((tmp_path / "out" / "summary.json").read_text())
    said = [w for w in s["warnings"] if "each step runs as" in w]
    assert len(said) == 1
    k = int(re.search(r"runs as (\d+) steps", said[0]).group(1))
    assert k >= 2 and s["dt"] == pytest.approx(0.004 / k, rel=1e-12) and s["steps"] == 50 * k
    assert s["frames"] == 6  # t = 0, 0.04, ..., 0.2 s: NiftySim's output times
    scene = load_niftysim(p)
    model = scene.builder.finalize("float64")
    for refused in {0.004, 0.004 / (k - 1)}:
        with pytest.raises(pl.errors.TimeStepError):
            pl.Simulation(model, dt=refused)
    pl.Simulation(model, dt=0.004 / k).run(steps=5)
    # The viewer asks as `pliant run` does, once per scene however often it resets.
    from pliant.runner import scene_step

    scene = load_niftysim(p)
    assert scene_step(scene, model) == scene_step(scene, model) == pytest.approx(0.004 / k, rel=1e-12)
    assert sum("each step runs as" in w for w in scene.warnings) == 1 and scene.output_every == 10 * k
    # A step no count of steps could divide (a fuzzed file's 1e308 s): refused as it was, exit 2.
    p.write_text(big.replace("<TimeStep>0.004</TimeStep>", "<TimeStep>1e308</TimeStep>"))
    r = runner.invoke(app, ["run", str(p), "-o", str(tmp_path / "out2")])
    assert r.exit_code == 2 and "exceeds the stable time step" in r.output, r.output
