"""Cutting: blades that cut the elements they sweep through, by separating elements at their
shared faces and splitting nodes (see split.py for the method and its sources). A cut rebuilds
the model over the new topology (masses, gather map, contact surfaces, critical step) and carries
the state across; the embedded visual surface opens along it."""

from .blade import Blade
from .cut import Cut, cut, cut_embedding
from .cutter import CutEvent, Cutter
from .split import Split, crossed_faces, interior_faces, split_nodes

__all__ = [
    "Blade",
    "Cut",
    "cut",
    "cut_embedding",
    "Cutter",
    "CutEvent",
    "Split",
    "crossed_faces",
    "interior_faces",
    "split_nodes",
]
