"""Hertz indentation: a rigid sphere pressed into a thick elastic block, against the closed form
F = 4/3 E* √R δ^1.5, E* = E / (1 − ν²) (Johnson, Contact Mechanics, 1985, §4.2, eq. 4.22-4.23).

Quarter model (symmetry planes x = 0 and y = 0), frictionless, small-strain linear elasticity,
float64, quasi-static (dynamic relaxation with the sphere's keyframed depth as the load step)."""

import numpy as np
import pytest

from pliant.validate.models import hertz_indentation
from pliant.validate.references import hertz_force

R, E, NU = 0.01, 1e4, 0.3  # sphere radius [m], Young's modulus [Pa], Poisson ratio
DEPTHS = np.array([0.0025, 0.005, 0.01]) * R  # δ [m]: contact radius a = √(Rδ) = 0.05–0.1 R


@pytest.fixture(scope="module")
def hertz_forces():
    """(tool forces, support reactions) at DEPTHS; the model checks symmetry and no penetration
    (a node off its symmetry plane or inside the sphere raises)."""
    return hertz_indentation(DEPTHS, R, E, NU)


def _hertz(delta):
    return hertz_force(delta, R, E, NU)


def test_force_matches_hertz_prefactor(hertz_forces):
    F, _ = hertz_forces
    ratio = F / _hertz(DEPTHS)
    # Tolerance 5 % (measured: 1.032, 1.034, 1.042). What separates this model from Hertz's
    # half-space: the finite block (about +0.9 a/L: +0.5 to +1 %); the tool acting on the deformed
    # surface while the linear theory applies the gap on the undeformed one (about +0.15 a/R: +0.4
    # to +1.5 %, measured by scaling R at fixed a/h); linear tets (+2 %, converging slowly: at
    # δ/R = 0.005, cells of R/200 or a grading of 1.2 instead of 1.3 give 1.032, a block twice as
    # large 1.031).
    np.testing.assert_allclose(ratio, 1.0, atol=0.05)


def test_force_grows_as_depth_to_the_three_halves(hertz_forces):
    F, _ = hertz_forces
    exponent = np.polyfit(np.log(DEPTHS), np.log(F), 1)[0]
    # 1.5 ± 0.03: the depth-dependent errors above (a/L and a/R grow with δ, a/h too) tilt the
    # fit by about log(1.02)/log(4) ≈ 0.015.
    assert abs(exponent - 1.5) < 0.03


def test_tool_force_is_what_the_supports_carry(hertz_forces):
    F, reaction = hertz_forces
    # Global equilibrium: the tool's reported force equals the supports' reaction, to the
    # dynamic-relaxation tolerance (1e-5 relative out-of-balance force; measured: 2e-4).
    np.testing.assert_allclose(reaction, F, rtol=2e-3)
