"""Mesh pipeline: primitives, surfaces (read/write, check, repair, QEM simplification, Loop
subdivision), tetrahedralization (fTetWild), hexahedra, wedges and pyramids split into
tetrahedra, quality, embedding of fine surfaces."""

from .embed import Embedding, embed_surface
from .pipeline import default_edge_length, surface_to_tets
from .primitives import box_tets, graded_coordinates, grid_hexahedra, grid_tets, orient_positive
from .quality import critical_time_steps, quality_summary, tet_quality
from .split import split_cells, split_quads
from .repair import check_surface, repair_surface, simplify, subdivide_loop
from .surface import primitive_surface, read_surface, write_surface
from .tetra import tetrahedralize

__all__ = [
    "box_tets",
    "grid_tets",
    "grid_hexahedra",
    "graded_coordinates",
    "orient_positive",
    "split_cells",
    "split_quads",
    "read_surface",
    "write_surface",
    "primitive_surface",
    "tetrahedralize",
    "check_surface",
    "repair_surface",
    "simplify",
    "subdivide_loop",
    "surface_to_tets",
    "default_edge_length",
    "tet_quality",
    "quality_summary",
    "critical_time_steps",
    "embed_surface",
    "Embedding",
]
