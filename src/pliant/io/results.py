"""Result series for ParaView: OUTDIR/result.pvd + one .vtu per frame. Every file is written to a
temporary name and renamed into place, so a crash or Ctrl-C never leaves a truncated file."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from .files import atomic_write, atomic_write_text, deferred_interrupt, make_output_dir


# A series' files: its indexes, and frame i's volume and fine-surface files (ParaView's .pvd lists).
INDEX, SURFACE_INDEX = "result.pvd", "surface.pvd"
FRAME, SURFACE_FRAME = "frame_{:05d}.vtu", "surface_{:05d}.vtu"
_FRAME_FILE = re.compile(
    "|".join(re.escape(f.split("{")[0]) + r"\d{5,}\.vtu" for f in (FRAME, SURFACE_FRAME))
)


def is_frame_file(name: str) -> bool:
    """Whether a file name is one a ResultWriter gives a frame (FRAME or SURFACE_FRAME, any i)."""
    return _FRAME_FILE.fullmatch(name) is not None


FIELDS = ("displacement", "velocity", "von_mises", "J", "strain_energy_density", "cauchy", "green_strain")


class ResultWriter:
    """Writes frames of a simulation. Point data: displacement [m], velocity [m/s]; cell data:
    von_mises [Pa], J, strain_energy_density [Pa], and on request cauchy [Pa] and green_strain
    (6 components xx, yy, zz, xy, yz, xz). ``fields`` chooses (default: the first five). A model
    with membranes adds them as triangles, with membrane_max_tension [N/m], membrane_area_ratio and
    membrane_energy [J] (Model.membrane_results; NaN on the tets, the tets' fields NaN on them). With an
    ``embedding`` (pliant.mesh.embed_surface), each frame also writes the fine surface that follows
    the deformation, as surface_NNNNN.vtu in surface.pvd. The .pvd indexes are rewritten after each
    frame. Each frame is written with its state's model: after a cut, frames have the new
    topology (ParaView reads a series whose meshes differ)."""

    def __init__(self, out_dir, model, fields=FIELDS[:5], embedding=None):
        self.dir = make_output_dir(out_dir)
        self.model = model
        unknown = set(fields) - set(FIELDS)
        if unknown:
            from ..errors import InputError

            raise InputError(f"unknown output field(s) {sorted(unknown)}; expected some of {FIELDS}")
        self.fields = tuple(fields)
        self.embedding = embedding
        self.frames: list[tuple[float, str]] = []

    def _pvd(self, name: str, files: list[tuple[float, str]]):
        entries = "\n".join(f'    <DataSet timestep="{t:.9g}" part="0" file="{f}"/>' for t, f in files)
        atomic_write_text(
            self.dir / name,
            '<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n'
            f"  <Collection>\n{entries}\n  </Collection>\n</VTKFile>\n",
        )

    def write(self, state) -> Path:
        import meshio

        model = state.model  # the state's: after a cut (pliant.cutting), a new topology
        res = model.element_results(state)
        i = len(self.frames)
        name = FRAME.format(i)
        f = self.fields
        point = {
            k: v for k, v in (("displacement", state.displacements), ("velocity", state.velocities)) if k in f
        }
        cell_src = {
            "von_mises": res["von_mises"],
            "J": res["J"],
            "strain_energy_density": res["energy_density"],
            "cauchy": res["cauchy"],
            "green_strain": res["green_strain"],
        }
        # Tets with their fields; membranes (if any) as triangles with theirs (max_tension [N/m],
        # area_ratio, energy [J]), each block's fields NaN on the other; membranes alone: no tet block.
        cells = {k: v for k, v in cell_src.items() if k in f}
        K, M = model.n_membranes, len(model.tets)
        blocks = [("tetra", model.tets)] if M else []
        data = {k: [v] if M else [] for k, v in cells.items()}
        if K:
            mem = model.membrane_results(state)
            blocks.append(("triangle", model.membrane_faces))
            for k, v in cells.items():
                data[k].append(np.full((K, *np.shape(v)[1:]), np.nan))
            for k in ("max_tension", "area_ratio", "energy"):
                data["membrane_" + k] = ([np.full(M, np.nan)] if M else []) + [mem[k]]
        mesh = meshio.Mesh(model.reference_positions, blocks, point_data=point, cell_data=data)
        # Ctrl-C is held from the first file of the frame to the last index, so that result.pvd
        # always lists exactly the frames on disk.
        with deferred_interrupt():
            if self.embedding is not None:
                emb = self.embedding
                Vs = emb.positions(model.tets, state.positions)
                atomic_write(
                    self.dir / SURFACE_FRAME.format(i),
                    lambda tmp: meshio.write(tmp, meshio.Mesh(Vs, [("triangle", emb.faces)]), binary=True),
                    "surface frame",
                )
            final = atomic_write(
                self.dir / name, lambda tmp: meshio.write(tmp, mesh, binary=True), "result frame"
            )
            self.frames.append((state.time, name))
            self._pvd(INDEX, self.frames)
            if self.embedding is not None:
                self._pvd(
                    SURFACE_INDEX, [(t, SURFACE_FRAME.format(j)) for j, (t, _) in enumerate(self.frames)]
                )
        return final
