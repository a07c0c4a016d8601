"""Reading volume meshes and VTK POLYDATA surfaces, and writing results (ParaView-ready .vtu/.pvd
series, JSON), atomically."""

from .files import (
    atomic_write,
    atomic_write_text,
    check_output_dir,
    check_output_file,
    make_output_dir,
    read_meshio,
)
from .mesh import read_volume_mesh
from .results import ResultWriter
from .vtk_polydata import is_vtk_polydata, read_vtk_polydata

__all__ = [
    "read_volume_mesh",
    "read_vtk_polydata",
    "is_vtk_polydata",
    "ResultWriter",
    "atomic_write",
    "atomic_write_text",
    "read_meshio",
    "check_output_file",
    "check_output_dir",
    "make_output_dir",
]
