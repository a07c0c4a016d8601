"""Mesh generation and processing (primitives here; the QEM / Loop / Delaunay pipeline builds on it)."""

from .primitives import box_tets, orient_positive

__all__ = ["box_tets", "orient_positive"]
