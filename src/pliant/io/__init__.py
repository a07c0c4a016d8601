"""Reading volume meshes and writing results (ParaView-ready .vtu/.pvd series, JSON), atomically."""

from .mesh import read_volume_mesh
from .results import ResultWriter, atomic_write_text

__all__ = ["read_volume_mesh", "ResultWriter", "atomic_write_text"]
