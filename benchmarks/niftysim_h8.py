"""NiftySim H8 models as pliant runs them (hexahedra split into tetrahedra) against NiftySim's own
H8 elements: NiftySim's models/cubehex10.xml set-up (a 0.1 m cube of n³ hexahedra, NH μ = 1 kPa,
K = 50 kPa, its x faces clamped in y and z, one pulled 0.03 m along x by POLY345 over 0.5 s,
damping 5/s, density 1000) at n = 10 and 20. Prints the necking (u_y at the middle of the face
y = 0.1 m, the last frame, t = 0.501 s: NiftySim's) of each element option, and the largest
nodal ‖u − u_NiftySim‖ over the largest ‖u_NiftySim‖. Prints figures; it is not a test.

    python benchmarks/niftysim_h8.py --niftysim PATH/TO/niftysim     # NiftySim built from source
    python benchmarks/niftysim_h8.py                                 # pliant's options alone
"""

from __future__ import annotations

import argparse
import subprocess
import tempfile
from pathlib import Path

import numpy as np

import pliant as pl
from pliant.io.niftysim import load_niftysim
from pliant.mesh.primitives import grid_hexahedra
from pliant.tled.solver import stable_substeps

L = 0.1  # cube edge [m]


def cube_model(n: int, path: Path) -> np.ndarray:
    """Writes the n³ H8 model; returns its nodes [m] (N, 3)."""
    X, H = grid_hexahedra(*(np.linspace(0, L, n + 1),) * 3)
    x0, x1 = np.nonzero(X[:, 0] < 1e-9)[0], np.nonzero(X[:, 0] > L - 1e-9)[0]
    ends = np.concatenate([x0, x1])

    def ints(a) -> str:
        return " ".join(str(int(v)) for v in np.ravel(a))

    def con(kind, dof, ids, extra=""):
        return (
            f'<Constraint DOF="{dof}" Type="{kind}" NumNodes="{len(ids)}"{extra}><Nodes>{ints(ids)}</Nodes>'
        )

    path.write_text(
        f'<?xml version="1.0"?><Model><Nodes DOF="3" NumNodes="{len(X)}">'
        + " ".join(repr(float(v)) for v in X.ravel())
        + f'</Nodes><Elements NumEls="{len(H)}" Type="H8">{ints(H)}</Elements>'
        '<ElementSet Size="all"><Material Type="NH"><ElasticParams NumParams="2">1000 50000'
        "</ElasticParams></Material>0</ElementSet>"
        + con("Disp", 0, x1, ' LoadShape="POLY345"')
        + '<Magnitudes Type="UNIFORM">0.03</Magnitudes></Constraint>'
        + con("Fix", 0, x0)
        + "</Constraint>"
        + con("Fix", 1, ends)
        + "</Constraint>"
        + con("Fix", 2, ends)
        + "</Constraint>"
        + f"<SystemParams><TimeStep>{0.01 / n!r}</TimeStep><TotalTime>0.5</TotalTime><DampingCoeff>5"
        "</DampingCoeff><HGKappa>0.075</HGKappa><Density>1000</Density></SystemParams>"
        f'<Output Freq="{50 * n}"><Variable>U</Variable></Output></Model>'
    )
    return X


def pliant_run(path: Path, anp: bool, smoothing: str) -> np.ndarray:
    """pliant's displacements [m] (N, 3) after NiftySim's NumSteps + 1 steps (float64)."""
    scene = load_niftysim(path)
    scene.builder.nodal_pressure = anp
    scene.builder.strain_smoothing = smoothing
    model = scene.builder.finalize("float64")
    k = stable_substeps(model, scene.dt)  # as `pliant run` divides an H8 model's step
    sim = pl.Simulation(model, dt=scene.dt / k)
    sim.run(steps=(round(scene.duration / scene.dt) + 1) * k)
    return sim.displacements


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--niftysim", help="a NiftySim executable (its U.txt is the reference)")
    ap.add_argument("--n", default="10,20", help="hexahedra along an edge")
    a = ap.parse_args()
    print("n | elements | u_y at (L/2, L, L/2) [mm] | largest |u - u_NiftySim| / largest |u_NiftySim|")
    for n in (int(v) for v in a.n.split(",")):
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / "cube.xml"
            X = cube_model(n, path)
            probe = int(np.argmin(np.linalg.norm(X - [L / 2, L, L / 2], axis=1)))
            ref = None
            if a.niftysim:
                subprocess.run([a.niftysim, "-x", path.name], cwd=tmp, check=True, capture_output=True)
                ref = np.loadtxt(Path(tmp) / "U.txt", ndmin=2)[:, -1].reshape(-1, 3)
                print(f"{n} | NiftySim H8 | {1e3 * ref[probe, 1]:.4f} | -")
            for name, anp, sm in (
                ("T4", False, "element"),
                ("T4ANP", True, "element"),
                ("ES+T4ANP", True, "edge"),
            ):
                u = pliant_run(path, anp, sm)
                dev = (
                    "-"
                    if ref is None
                    else f"{np.linalg.norm(u - ref, axis=1).max() / np.linalg.norm(ref, axis=1).max():.4f}"
                )
                print(f"{n} | pliant {name} | {1e3 * u[probe, 1]:.4f} | {dev}", flush=True)


if __name__ == "__main__":
    main()
