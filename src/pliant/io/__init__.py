"""Reading volume meshes (tetrahedra, and hexahedra, wedges and pyramids split into them; legacy
VTK grids meshio refuses too) and VTK POLYDATA surfaces, and writing results (ParaView-ready
.vtu/.pvd series, JSON), atomically."""

from .files import (
    atomic_write,
    atomic_write_text,
    check_output_dir,
    check_output_file,
    make_output_dir,
    read_meshio,
)
from .mesh import VolumeMeshFile, read_volume_mesh, read_volume_mesh_file, read_volume_mesh_sets
from .results import ResultWriter
from .vtk_grid import is_vtk_grid, read_vtk_grid
from .vtk_polydata import is_vtk_polydata, read_vtk_polydata

__all__ = [
    "read_volume_mesh",
    "read_volume_mesh_sets",
    "read_volume_mesh_file",
    "VolumeMeshFile",
    "read_vtk_polydata",
    "is_vtk_polydata",
    "read_vtk_grid",
    "is_vtk_grid",
    "ResultWriter",
    "atomic_write",
    "atomic_write_text",
    "read_meshio",
    "check_output_file",
    "check_output_dir",
    "make_output_dir",
]
