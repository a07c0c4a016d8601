"""Result series for ParaView: OUTDIR/result.pvd + one .vtu per frame. Every file is written to a
temporary name and renamed into place, so a crash or Ctrl-C never leaves a truncated file."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import numpy as np


def atomic_write_text(path, text: str) -> None:
    path = Path(path)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "w") as f:
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


class ResultWriter:
    """Writes frames of a simulation: point data displacement [m], velocity [m/s]; cell data von
    Mises stress [Pa], J, strain-energy density [Pa]. The .pvd index is rewritten after each frame."""

    def __init__(self, out_dir, model):
        self.dir = Path(out_dir)
        self.dir.mkdir(parents=True, exist_ok=True)
        self.model = model
        self.frames: list[tuple[float, str]] = []

    def write(self, state) -> Path:
        import meshio

        res = self.model.element_results(state)
        name = f"frame_{len(self.frames):05d}.vtu"
        mesh = meshio.Mesh(
            self.model.reference_positions, [("tetra", self.model.tets)],
            point_data={"displacement": state.displacements, "velocity": state.velocities},
            cell_data={"von_mises": [res["von_mises"]], "J": [res["J"]],
                       "strain_energy_density": [res["energy_density"]]})
        final = self.dir / name
        tmp = self.dir / f".{name}.tmp.vtu"
        meshio.write(tmp, mesh, binary=True)
        os.replace(tmp, final)
        self.frames.append((state.time, name))
        entries = "\n".join(f'    <DataSet timestep="{t:.9g}" part="0" file="{f}"/>'
                            for t, f in self.frames)
        atomic_write_text(self.dir / "result.pvd",
                          '<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n'
                          f"  <Collection>\n{entries}\n  </Collection>\n</VTKFile>\n")
        return final
