"""NiftySim's element types as pliant runs them (user guide v2.4 §3.2.2): T4 and T4ANP are
pliant's linear tetrahedra, without and with average nodal pressure; H8, NiftySim's reduced-
integration hexahedron with hourglass control (tledElementH8), has no counterpart in pliant's
engine, so each hexahedron is split into 6 tetrahedra (pliant.mesh.split: conforming across shared
faces, the model's nodes unchanged), its element sets and faces mapped onto them. The split mesh
runs as T4ANP where every material allows it: H8's one volumetric constraint per element is about
one per node, as T4ANP's nodal pressure has, where plain T4 on 6 tets a hexahedron would have 6 and
lock (docs/scenes.md). A model with LE or viscoelastic materials runs as T4, and says so."""

from __future__ import annotations

import numpy as np

from ..errors import MeshError
from ..mesh.split import split_cells
from .niftysim import NiftySimError

__all__ = ["ELEMENT_NODES", "as_tets", "h8_as_t4anp"]

# Nodes per element of each <Elements Type>.
ELEMENT_NODES = {"T4": 4, "T4ANP": 4, "H8": 8}


def as_tets(X: np.ndarray, E: np.ndarray, f: str, key: str) -> tuple[np.ndarray, np.ndarray]:
    """Tetrahedra (M, 4) of the model's elements E (tets (M, 4), or H8 (M, 8) in VTK's node order,
    the user guide's) on nodes X [m] (N, 3), and the element each comes from (M,)."""
    E = np.asarray(E, np.int64)
    if E.shape[1] == 4:
        return E, np.arange(len(E))
    try:
        return split_cells(X, "hexahedron", E, what="element")
    except MeshError as e:
        raise NiftySimError(str(e), f, key) from None


def h8_as_t4anp(b, hexahedra: int, tets: int, f: str, warnings: list[str]) -> bool:
    """Whether the split H8 model (builder b, its materials set) runs with average nodal pressure
    (every material decoupled and elastic), with the warning that says how it runs."""
    plain = [s for s in b.sets if not s.material.decoupled or getattr(s.material, "prony", None)]
    head = (
        f"{f}: {hexahedra:,} H8 element{'s' if hexahedra != 1 else ''} split into {tets:,} tetrahedra "
        "(pliant has no hexahedral "
        "element; NiftySim's H8 integrates at one point with hourglass control): "
    )
    if not plain:
        warnings.append(head + "run as T4ANP (one pressure a node, as H8 has about one an element)")
        return True
    warnings.append(
        head + f"run as T4, since {plain[0].name} ({type(plain[0].material).__name__}) has no "
        "average nodal pressure; T4 locks where the material is nearly incompressible"
    )
    return False
