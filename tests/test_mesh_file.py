"""A mesh file no one here wrote (NiftySim's tetrahedral sphere, BSD) read through meshio."""

from pathlib import Path

import numpy as np

import pliant as pl

SPHERE = Path(__file__).parent / "data" / "niftysim_sphere.vtk"


def _boundary_nodes(T):
    faces = np.sort(
        np.concatenate([T[:, [0, 1, 2]], T[:, [0, 1, 3]], T[:, [0, 2, 3]], T[:, [1, 2, 3]]]), axis=1
    )
    uniq, count = np.unique(faces, axis=0, return_counts=True)
    return np.unique(uniq[count == 1])


def _sphere_builder(material):
    X, T, _ = pl.io.read_volume_mesh(SPHERE)
    b = pl.ModelBuilder()
    b.add_mesh(X, pl.mesh.orient_positive(X, T), source=str(SPHERE))
    b.set_material(material, density=1000.0)
    return X, T, b


def test_sphere_file_reads_and_is_valid():
    X, T, _ = pl.io.read_volume_mesh(SPHERE)
    assert X.shape == (278, 3) and T.shape == (789, 4)  # as NiftySim's README states
    _, _, b = _sphere_builder(pl.NeoHookean(mu=100.0, K=800.0))
    model = b.finalize()
    # A tet mesh inscribed in the unit sphere: volume below 4π/3, and within 10 % of it.
    V = model.element_volumes().sum()
    assert 0.9 * 4 / 3 * np.pi < V < 4 / 3 * np.pi


def test_patch_test_on_sphere_mesh():
    """Affine displacement of the surface nodes ⇒ the same affine field inside (NH, NiftySim's
    material constants μ = 100 Pa, K = 800 Pa)."""
    X, T, b = _sphere_builder(pl.NeoHookean(mu=100.0, K=800.0))
    A = np.array([[0.08, 0.02, 0.0], [0.0, -0.05, 0.03], [0.01, 0.0, 0.06]])
    surface = _boundary_nodes(T)
    inner = np.setdiff1d(np.arange(len(X)), surface)
    b.prescribe(surface, (X @ A.T)[surface], curve=pl.Ramp(1.0))
    model = b.finalize("float64")
    sim = pl.Simulation(model)
    sim.relax(tol=1e-10)
    # Residual 1e-10 relative ⇒ displacement error far below 1e-7 of |u| ~ 0.1.
    assert np.abs(sim.displacements[inner] - (X @ A.T)[inner]).max() < 1e-7


def test_free_fall_under_gravity():
    """An unconstrained body under gravity falls rigidly: u = ½ g t² (central differences started
    at rest add ½ g t Δt, the start-up offset of u⁻ = u⁰), with no stress."""
    X, T, b = _sphere_builder(pl.NeoHookean(mu=1e4, K=8e4))
    b.set_gravity((0.0, 0.0, -9.81))
    model = b.finalize("float64")
    sim = pl.Simulation(model)
    sim.run(steps=400)
    t, dt = sim.time, sim.solver.dt
    expected = -0.5 * 9.81 * t * (t + dt)
    assert np.allclose(sim.displacements[:, 2], expected, rtol=1e-9)
    assert np.allclose(sim.displacements[:, :2], 0.0, atol=1e-12)
    assert np.abs(sim.element_results()["cauchy"]).max() < 1e-6 * 1e4
