import numpy as np
import pytest

import pliant as pl


def cube_with_symmetry_bcs(material, stretch, cells=3, jitter=0.25, dtype="float32", L=1.0):
    """Unstructured tet cube [0, L]³ under uniaxial stretch along x with symmetry planes x=0, y=0,
    z=0 and free lateral faces: the exact solution is homogeneous, so linear tets represent it."""
    X, T = pl.mesh.box_tets((L, L, L), (cells,) * 3, jitter=jitter, seed=1)
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(material, density=1000.0)
    tol = 1e-9 * L
    b.fix(np.nonzero(X[:, 0] < tol)[0], "x")
    b.fix(np.nonzero(X[:, 1] < tol)[0], "y")
    b.fix(np.nonzero(X[:, 2] < tol)[0], "z")
    right = np.nonzero(X[:, 0] > L - tol)[0]
    b.prescribe(right, (stretch - 1.0) * L, "x", curve=pl.Ramp(1.0))
    return X, b.finalize(dtype), right


@pytest.fixture(params=["float32", "float64"])
def dtype(request):
    return request.param
