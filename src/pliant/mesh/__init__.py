"""Mesh generation and processing: primitives, surfaces, tetrahedralization."""

from .primitives import box_tets, orient_positive
from .surface import primitive_surface, read_surface, write_surface
from .tetra import tetrahedralize

__all__ = ["box_tets", "orient_positive", "read_surface", "write_surface", "primitive_surface",
           "tetrahedralize"]
