"""fTetWild (Hu et al. 2020, ACM TOG 39(4)) through the ``pytetwild`` wheel (MPL-2.0), run in a child
process. fTetWild is a large C++ code fed users' surfaces, and it can crash on some of them
(segmentation faults in its preprocessing: wildmeshing/fTetWild#75; here, on a sphere a nanometre
across before tetra.py scaled it): in the caller's process that would take the user's Python, a
notebook's kernel or a viewer with it. In a child, a crash is a MeshError naming the signal. The
child also writes fTetWild's scratch file (``__tracked_surface.stl``) into its own working
directory, a temporary one, where an in-process run had to change the whole process's.

Child: ``python -m pliant.mesh.ftetwild IN.npz OUT.npz`` (run() writes IN and reads OUT).
"""

from __future__ import annotations

import glob
import importlib.machinery
import importlib.util
import os
import signal
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from ..errors import MeshError


def wrapper():
    """fTetWild's compiled wrapper. pytetwild's package __init__ imports pyvista (a large optional
    dependency we do not need), so load the extension module directly when that import fails."""
    try:
        from pytetwild import PyfTetWildWrapper  # noqa: F401

        return PyfTetWildWrapper
    except ImportError:
        pass
    spec = importlib.util.find_spec("pytetwild")
    if spec is None or spec.origin is None:
        raise MeshError("tetrahedralization needs the 'pytetwild' package (pip install pytetwild)")
    so = glob.glob(os.path.join(os.path.dirname(spec.origin), "PyfTetWildWrapper*.so"))
    if not so:
        raise MeshError("pytetwild is installed but its fTetWild extension was not found")
    loader = importlib.machinery.ExtensionFileLoader("pytetwild.PyfTetWildWrapper", so[0])
    mspec = importlib.util.spec_from_file_location("pytetwild.PyfTetWildWrapper", so[0], loader=loader)
    mod = importlib.util.module_from_spec(mspec)
    loader.exec_module(mod)
    return mod


def run(
    V: np.ndarray, F: np.ndarray, edge_r: float, epsilon: float, optimize: bool, threads: int
) -> tuple[np.ndarray, np.ndarray]:
    """fTetWild's tets of the surface V (n, 3), F (f, 3) uint32: nodes (N, 3) and tets (M, 4), as
    fTetWild orients them. ``edge_r`` and ``epsilon``: the tet edge and the envelope relative to
    the bounding-box diagonal; ``threads``: 0 for all cores. Raises MeshError when the child fails
    (its signal, or the last line it wrote)."""
    wrapper()  # a missing wheel is named here, not by the child
    with tempfile.TemporaryDirectory(prefix="pliant-ftetwild-") as scratch:
        src, out = Path(scratch) / "in.npz", Path(scratch) / "out.npz"
        params = np.array([edge_r, epsilon, float(bool(optimize)), float(threads)])
        np.savez(
            src, V=np.ascontiguousarray(V, np.float64), F=np.ascontiguousarray(F, np.uint32), params=params
        )
        # The child finds this pliant even where the caller put it on sys.path by hand.
        here = str(Path(__file__).resolve().parents[2])
        env = {
            **os.environ,
            "PYTHONPATH": os.pathsep.join(filter(None, [here, os.environ.get("PYTHONPATH")])),
        }
        r = subprocess.run(
            [sys.executable, "-m", "pliant.mesh.ftetwild", str(src), str(out)],
            cwd=scratch,
            env=env,
            stdin=subprocess.DEVNULL,
            capture_output=True,
            text=True,
        )
        if r.returncode != 0 or not out.exists():
            raise MeshError(f"tetrahedralize: fTetWild {_how(r)} on this surface; {_advice()}")
        with np.load(out) as d:
            return d["nodes"], d["tets"]


def _how(r: subprocess.CompletedProcess) -> str:
    """How the child ended, in words."""
    if r.returncode < 0:
        try:
            name = signal.Signals(-r.returncode).name
        except ValueError:
            name = f"signal {-r.returncode}"
        return f"stopped with {name}" + (" (out of memory?)" if name == "SIGKILL" else "")
    said = (r.stderr or r.stdout or "").strip().splitlines()
    return f"failed (exit code {r.returncode}" + (f": {said[-1]}" if said else "") + ")"


def _advice() -> str:
    return (
        "repair or simplify the surface (pliant mesh repair / simplify), or give another edge "
        "length or envelope (fTetWild fails on some inputs: wildmeshing/fTetWild#75)"
    )


def _main(argv: list[str]) -> int:
    src, out = argv
    with np.load(src) as d:
        V, F, (edge_r, epsilon, optimize, threads) = d["V"], d["F"], d["params"]
    nodes, tets = wrapper().tetrahedralize_mesh(
        V,
        F,
        bool(optimize),
        False,  # skip_simplify
        float(edge_r),
        0.0,  # edge_length_abs: none, edge_r rules
        float(epsilon),
        10.0,  # stop_energy
        False,  # coarsen
        int(threads),
        80,  # num_opt_iter
        6,  # loglevel
        True,  # quiet
        False,  # vtk_ordering
        False,  # disable_filtering
        np.zeros((0, 3)),
        np.zeros((0, 4), np.int32),
        np.zeros(0),
    )
    tmp = Path(out).with_name("out.tmp.npz")
    np.savez(tmp, nodes=np.asarray(nodes, float), tets=np.asarray(tets, np.int64))
    os.replace(tmp, out)
    return 0


if __name__ == "__main__":
    sys.exit(_main(sys.argv[1:]))
