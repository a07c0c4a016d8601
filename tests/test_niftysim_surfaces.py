"""NiftySim's moving rigid contact surfaces: <ContactSurface> with <Motion> and <SlvNodes>.

Reference: NiftySim's motion (tledMovingRigidContactSurface: vertices y go to
R(s)(y − c) + c + s·t at the fraction s of the analysis, R = Rz Ry Rx) evaluated here in closed
form, and a block pressed by the moving surface: kinematic contact leaves the nodes under it on
its face, so their displacement is the surface's travel beyond the first touch."""

from __future__ import annotations

import math

import numpy as np
import pytest

import pliant as pl
from pliant.io.niftysim import NiftySimError, load_niftysim
from pliant.mesh import box_tets
from pliant.mesh.topology import boundary_faces

SYSTEM = (
    "<SystemParams><TimeStep>2e-5</TimeStep><TotalTime>{T}</TotalTime>"
    "<DampingCoeff>200</DampingCoeff><Density>1000</Density></SystemParams>"
)


def _text(a, fmt=repr):
    return " ".join(fmt(float(v)) if fmt is repr else str(int(v)) for v in np.ravel(a))


def _block():
    X, T = box_tets((0.02, 0.02, 0.01), (4, 4, 2))
    bottom = np.nonzero(X[:, 2] < 1e-9)[0]
    return (
        X,
        f'<Nodes DOF="3" NumNodes="{len(X)}">{_text(X)}</Nodes>'
        f'<Elements NumEls="{len(T)}" Type="T4">{_text(T, int)}</Elements>'
        f'<ElementSet Size="all"><Material Type="NH"><ElasticParams NumParams="2">3000 30000'
        "</ElasticParams></Material></ElementSet>"
        f'<Constraint DOF="all" NumNodes="{len(bottom)}" Type="Fix"><Nodes>{_text(bottom, int)}</Nodes>'
        "</Constraint>",
    )


def _surface(lo, hi, motion=""):
    """A closed box surface (T3) from lo to hi [m], with <Motion>s."""
    V, T = box_tets(np.subtract(hi, lo), (1, 1, 1), origin=lo)
    F, _ = boundary_faces(T)
    return (
        f"<ContactSurface><Nodes>{_text(V)}</Nodes>"
        f'<Elements Type="T3">{_text(F, int)}</Elements>{motion}</ContactSurface>',
        V,
    )


def test_a_moving_surface_follows_niftysims_motion(tmp_path):
    X, block = _block()
    t, angles, centre = (
        np.array([0.001, -0.002, 0.003]),
        np.array([0.3, -0.2, 0.5]),
        np.array([0.05, 0.0, 0.1]),
    )
    motion = (
        f'<Motion Type="Translation">{_text(t)}</Motion>'
        f'<Motion Type="Rotation">{_text(angles)} {_text(centre)}</Motion>'
    )
    surface, V = _surface((0.0, 0.0, 0.05), (0.02, 0.02, 0.06), motion)
    f = tmp_path / "m.xml"
    f.write_text(f"<Model>{block}{surface}{SYSTEM.format(T=0.1)}</Model>")
    tool = load_niftysim(f).builder.tools[0]
    for s in (0.0, 0.137, 0.5, 0.91, 1.0):
        R = np.eye(3)
        for axis in range(3):
            c, sn = math.cos(s * angles[axis]), math.sin(s * angles[axis])
            i, j = (axis + 1) % 3, (axis + 2) % 3
            G = np.eye(3)
            G[i, i], G[i, j], G[j, i], G[j, j] = c, -sn, sn, c
            R = G @ R
        expected = (V - centre) @ R.T + centre + s * t
        Rt, p = tool.pose(s * 0.1)
        # 1e-6 m: nlerp between keyframes 0.01 of the motion apart, on a 10 cm lever.
        np.testing.assert_allclose(V @ Rt.T + p, expected, atol=1e-6)


def test_a_surface_moving_down_presses_the_block_by_its_travel(tmp_path):
    X, block = _block()
    gap, travel = 0.001, 0.004  # the surface starts 1 mm above the block and moves down 4 mm
    top = 0.01
    surface, _ = _surface(
        (0.005, 0.005, top + gap),
        (0.015, 0.015, top + gap + 0.01),
        '<Motion Type="Translation">0 0 -0.004</Motion>',
    )
    f = tmp_path / "press.xml"
    f.write_text(f"<Model>{block}{surface}{SYSTEM.format(T=0.05)}</Model>")
    scene = load_niftysim(f)
    sim = pl.Simulation(scene.builder.finalize("float64"), damping=200.0)
    sim.run(until=0.05)
    under = np.nonzero((np.abs(X[:, 2] - top) < 1e-9) & np.all(np.abs(X[:, :2] - 0.01) < 0.004, axis=1))[0]
    # Kinematic contact puts them on the surface's face: pushed by travel − gap; 2 % for the
    # signed-distance grid's interpolation near the box's edges and the elastic rebound within
    # a step.
    np.testing.assert_allclose(sim.displacements[under, 2], -(travel - gap), rtol=0.02)


def test_slave_nodes_restrict_the_surface(tmp_path):
    X, block = _block()
    surface, _ = _surface((0.0, 0.0, 0.05), (0.02, 0.02, 0.06))
    surface = surface.replace("</ContactSurface>", '<SlvNodes NumNodes="2">3 7</SlvNodes></ContactSurface>')
    f = tmp_path / "slv.xml"
    f.write_text(f"<Model>{block}{surface}{SYSTEM.format(T=0.1)}</Model>")
    assert load_niftysim(f).builder.tool_nodes[0].tolist() == [3, 7]


@pytest.mark.parametrize(
    "motion", ['<Motion Type="Spin">1 2 3</Motion>', '<Motion Type="Rotation">1 2 3</Motion>']
)
def test_bad_motions_are_refused_naming_them(tmp_path, motion):
    X, block = _block()
    surface, _ = _surface((0.0, 0.0, 0.05), (0.02, 0.02, 0.06), motion)
    f = tmp_path / "bad.xml"
    f.write_text(f"<Model>{block}{surface}{SYSTEM.format(T=0.1)}</Model>")
    with pytest.raises(NiftySimError, match=r"ContactSurface\[0\]/Motion"):
        load_niftysim(f)
