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


# --- backends: every test taking `backend` runs on each, and the summary counts them ----------------
BACKENDS = ("cpu", "cuda-emulated", "cuda")
_backend_of: dict[str, str] = {}


@pytest.fixture(params=BACKENDS)
def backend(request):
    """A backend name; "cuda" is skipped, with the reason, where there is no device."""
    if request.param == "cuda":
        from pliant import _core

        names, why = _core.cuda_devices()
        if not names:
            pytest.skip(f"backend cuda: no CUDA device here ({why})")
    return request.param


def pytest_collection_modifyitems(items):
    for item in items:
        cs = getattr(item, "callspec", None)
        if cs is not None and "backend" in cs.params:
            _backend_of[item.nodeid] = cs.params["backend"]


def pytest_terminal_summary(terminalreporter):
    counts = {b: {} for b in BACKENDS}
    for outcome in ("passed", "failed", "skipped", "error"):
        for rep in terminalreporter.stats.get(outcome, []):
            b = _backend_of.get(getattr(rep, "nodeid", ""))
            if b and (outcome != "passed" or rep.when == "call"):
                counts[b][outcome] = counts[b].get(outcome, 0) + 1
    if any(counts.values()):
        terminalreporter.section("tests per backend")
        for b, c in counts.items():
            terminalreporter.write_line(f"{b:>14}: " + (", ".join(f"{n} {o}" for o, n in c.items())
                                                        or "none run"))
