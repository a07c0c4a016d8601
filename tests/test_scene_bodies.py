"""Scenes with several bodies ([[body]]) and soft contact between them ([contact])."""

from __future__ import annotations

import numpy as np
import pytest

import pliant as pl
from pliant.scene import load_scene
from pliant.scene.schema import SceneError

SCENE = """
title = "two blocks"
[mesh]
name = "base"
primitive = "box"
size = [0.04, 0.04, 0.01]
cells = [8, 8, 2]
[[body]]
name = "block"
primitive = "box"
size = [0.02, 0.02, 0.01]
cells = [4, 4, 2]
translate = [0.0, 0.0, 0.0101]
[[material]]
type = "neo-hookean"
E = 1.0e5
nu = 0.3
density = 1000.0
region = { set = "base" }
[[material]]
type = "neo-hookean"
E = 2.0e4
nu = 0.3
density = 500.0
region = { set = "block" }
[solver]
duration = 0.3
damping = 60.0
[[constraint]]
type = "fix"
nodes = { plane = { point = [0, 0, -0.005], normal = [0, 0, 1] } }
[[load]]
type = "gravity"
[contact]
friction = [0.4, 0.3]
pairs = [["block", "base"]]
"""


def _write(tmp_path, text):
    p = tmp_path / "s.toml"
    p.write_text(text)
    return p


def test_two_bodies_rest_one_on_the_other(tmp_path):
    sc = load_scene(_write(tmp_path, SCENE))
    b = sc.builder
    assert np.bincount(b.bodies()).tolist() == [8 * 8 * 2 * 6, 4 * 4 * 2 * 6]  # two bodies
    c = b.soft_contact
    assert (c.mu_s, c.mu_k, c.pairs, c.self_contact) == (0.4, 0.3, ((1, 0),), False)
    assert [s.density for s in b.sets] == [1000.0, 500.0]  # materials by body name
    sim = pl.Simulation(b.finalize("float64"))
    sim.run(until=sc.duration)
    pair = sim.solver.contact_report().pairs[0]
    weight = 500.0 * 0.02 * 0.02 * 0.01 * 9.81
    # Statics: the base receives the block's weight (1 % for the last ripple at α = 60 /s).
    np.testing.assert_allclose(pair.force[-100:].mean(axis=0), [0, 0, -weight], atol=0.01 * weight)


def test_a_static_scene_reports_the_pairs_equilibrium_force(tmp_path):
    """The same scene solved quasi-statically (`static = true`): summary.json's pair force is the
    equilibrium's, the base receiving the block's weight, down (1e-4 of it: relaxed to 1e-5 of the
    force scale; measured 1.2e-5). It read [0, 0, 0], there being no step to take it from."""
    from pliant.runner import run_scene

    text = SCENE.replace("duration = 0.3", 'duration = 0.3\nstatic = true\ndtype = "float64"')
    summary = run_scene(load_scene(_write(tmp_path, text)), tmp_path / "out", progress=False)
    (pair,) = summary["contact_pairs"]
    weight = 500.0 * 0.02 * 0.02 * 0.01 * 9.81
    assert summary["converged"] and pair["names"] == ["base", "block"]
    np.testing.assert_allclose(pair["force"], [0.0, 0.0, -weight], atol=1e-4 * weight)
    assert pair["max_force"] == pytest.approx(weight, rel=1e-4)


@pytest.mark.parametrize(
    "edit, key, words",
    [
        (('name = "block"\n', ""), "body[0].name", "needs a name"),
        (('name = "block"', 'name = "base"'), "body[0].name", "two bodies are named"),
        (('pairs = [["block", "base"]]', 'pairs = [["block", "liver"]]'), "contact.pairs[0]", "unknown body"),
        (("friction = [0.4, 0.3]", "friction = [0.3, 0.4]"), "contact", "kinetic"),
        (("friction = [0.4, 0.3]", "frictoin = 0.3"), "contact.frictoin", ""),
    ],
)
def test_bad_bodies_and_contact_name_the_key(tmp_path, edit, key, words):
    with pytest.raises(SceneError) as e:
        load_scene(_write(tmp_path, SCENE.replace(*edit)))
    assert e.value.key == key and words in str(e.value)


def test_bodies_that_start_inside_each_other_are_named_by_the_scene(tmp_path):
    """The block sunk 5 mm into the base (elements 5 mm thick, band 1.2 mm): refused when the
    model is built, the bodies named as the scene names them; the deepest node, on the block's
    bottom face, lies 5 mm under the base's top (the closed form of the overlap)."""
    sc = load_scene(
        _write(tmp_path, SCENE.replace("translate = [0.0, 0.0, 0.0101]", "translate = [0.0, 0.0, 0.005]"))
    )
    with pytest.raises(pl.InputError, match=r"of body 1 \('block'\) starts 0.005 m inside body 0 \('base'\)"):
        sc.builder.finalize("float64")
