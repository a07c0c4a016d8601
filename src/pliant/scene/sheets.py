"""The [[sheet]] tables of a scene: sheets of membranes apart from the tets (a drape, a sheet of
tissue, a free capsule), each a triangle surface or a rectangle with a membrane material::

    [[sheet]]
    name = "drape"              # unique among bodies and sheets
    file = "drape.obj"          # a triangle surface (open or closed), or:
    # primitive = "rectangle"   # in the xy plane, centred on the origin
    # size = [0.1, 0.08]        # [m]
    # cells = [20, 16]          # squares across (or edge_length = 0.005 [m]), two triangles each
    scale = 1.0                 # the file's units to metres
    rotate = [90, 0, 0]         # degrees about x, then y, then z; then
    translate = [0, 0, 0.05]    # [m]
    type = "neo-hookean"        # or "st-venant-kirchhoff" (E, nu)
    mu = 2e4                    # [Pa]
    thickness = 1e-4            # [m]
    density = 1100.0            # [kg/m^3]
    wrinkling = true            # default without bending: it carries no compression
    bending = false             # true: it also bends, a plate of its E, nu (a number: bending E)
    bending_nu = 0.3            # Poisson's ratio of its bending (default the material's)

A sheet without bending stiffness (the default) buckles under compression into wrinkles at almost
no load, so by default a sheet wrinkles (tension-field theory, docs/engine.md "Wrinkling"): it
carries tension only, where a sheet that carries compression stiffens as it crumples until its step
is unstable (a drape on a ball). With ``bending`` it is a thin plate (rotation-free shell triangles,
docs/engine.md "Bending"), its edges held in all three directions clamped, and it does not wrinkle
unless told to (its bending carries compression until it buckles). A scene may be sheets alone (no
[mesh]).

Each sheet's nodes form the node set of its name, and those on its open edges "<name>.rim"
(constraints: ``nodes = { set = "drape.rim" }``). With a [contact] table a sheet touches the other
bodies from either side, at half its thickness (docs/contact.md); [contact] pairs and self name it
as a body.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..errors import MeshError
from .membranes import MATERIAL_KEYS, membrane_material
from .mesh import placed
from .schema import Ctx, check_keys, vector

if TYPE_CHECKING:
    from ..tled import ModelBuilder

__all__ = ["load_sheets"]

# The keys of a [[sheet]] table besides its membrane material's.
_PLACE_KEYS = {
    "name": "str",
    "file": "str",
    "primitive": "str",
    "size": "list [lx, ly] [m]",
    "cells": "list [nx, ny]",
    "edge_length": "number",
    "scale": "number",
    "rotate": "list [ax, ay, az] (degrees about x, then y, then z)",
    "translate": "list [dx, dy, dz] [m]",
}


def load_sheets(
    ctx: Ctx, tables, base: Path, b: ModelBuilder, X: np.ndarray, names: list[str], node_sets: dict
) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Each [[sheet]] table's nodes and membranes into the builder (after the bodies: ``X`` [m]
    (N, 3), the scene's nodes so far; ``names``, the bodies' names, to which the sheets' are
    appended; ``node_sets``, to which each sheet's and its rim's are added). Returns the scene's
    nodes with the sheets' and, per sheet name, its membranes (indices into
    ModelBuilder.membrane_faces())."""
    if not isinstance(tables, list):
        raise ctx.error("sheet", "expected [[sheet]] tables")
    membranes: dict[str, np.ndarray] = {}
    for i, spec in enumerate(tables):
        p = f"sheet[{i}]"
        check_keys(ctx, spec, p, _PLACE_KEYS | MATERIAL_KEYS, ("name", "type", "thickness", "density"))
        name = spec["name"]
        if not name or name in names:
            raise ctx.error(f"{p}.name", f"name {name!r}: expected a name no body or sheet has")
        material = membrane_material(ctx, spec, p, set(_PLACE_KEYS), wrinkling=True)
        V, F, source = _geometry(ctx, spec, p, base)
        V = placed(ctx, spec, p, V)
        first_node, first_membrane = b.n_nodes, b.n_membranes
        with ctx.under(p):
            b.add_mesh(V, np.zeros((0, 4), np.int64), source=source)
            b.add_membrane(F + first_node, material)
        membranes[name] = np.arange(first_membrane, b.n_membranes)
        node_sets[name] = first_node + np.arange(len(V))
        rim = _rim(F)
        if rim.size:
            node_sets[f"{name}.rim"] = first_node + rim
        names.append(name)
        X = np.vstack([X, V])
    return X, membranes


def _geometry(ctx: Ctx, spec: dict, p: str, base: Path) -> tuple[np.ndarray, np.ndarray, str]:
    """A sheet table's triangles before placing: vertices [m] (n, 3) each used by a triangle,
    triangles (k, 3), and where they came from (for messages)."""
    from ..mesh.surface import read_surface

    if ("file" in spec) == ("primitive" in spec):
        raise ctx.error(p, "give exactly one of 'file' or 'primitive'")
    scale = float(spec.get("scale", 1.0))
    if not scale > 0:
        raise ctx.error(f"{p}.scale", "expected a scale > 0")
    if "file" in spec:
        for k in ("size", "cells", "edge_length"):
            if k in spec:
                raise ctx.error(f"{p}.{k}", f"'{k}' sizes a primitive rectangle, not a surface file")
        f = Path(spec["file"])
        f = f if f.is_absolute() else base / f
        try:
            V, F = read_surface(f)
        except MeshError as e:
            raise ctx.error(f"{p}.file", str(e)) from None
        used = np.unique(F)  # a vertex no triangle uses would be a node without mass
        index = np.full(len(V), -1, np.int64)
        index[used] = np.arange(used.size)
        return np.asarray(V, float)[used] * scale, index[F], str(f)
    if spec["primitive"] != "rectangle":
        raise ctx.error(
            f"{p}.primitive", f"unknown sheet primitive {spec['primitive']!r}; expected rectangle"
        )
    size = spec.get("size")
    if not (isinstance(size, list) and len(size) == 2):
        raise ctx.error(f"{p}.size", "a rectangle needs size = [lx, ly] [m]")
    size = vector(ctx, size, f"{p}.size", 2)
    if not min(size) > 0:
        raise ctx.error(f"{p}.size", "expected lengths > 0 [m]")
    cells, key = spec.get("cells"), f"{p}.cells"
    if cells is None:
        key = f"{p}.edge_length"
        el = spec.get("edge_length", min(size) / 10)
        if not el > 0:
            raise ctx.error(f"{p}.edge_length", "expected a length > 0 [m]")
        cells = [max(1, round(s / el)) for s in size]
    elif "edge_length" in spec:
        raise ctx.error(f"{p}.cells", "give cells or edge_length, not both")
    if not (
        len(cells) == 2 and all(isinstance(c, int) and not isinstance(c, bool) and c >= 1 for c in cells)
    ):
        raise ctx.error(f"{p}.cells", "expected two integers >= 1")
    if (cells[0] + 1) * (cells[1] + 1) > MAX_SHEET_NODES:
        raise ctx.error(key, f"{cells} cells: expected at most {MAX_SHEET_NODES:,} nodes")
    V, F = rectangle(size[0] * scale, size[1] * scale, cells[0], cells[1])
    return V, F, f"{ctx.file} [{p}]"


# The most nodes a primitive rectangle may have (a typo in cells fails at once, not after the memory).
MAX_SHEET_NODES = 10_000_000


def rectangle(lx: float, ly: float, nx: int, ny: int) -> tuple[np.ndarray, np.ndarray]:
    """A rectangle lx × ly [m] in the plane z = 0, centred on the origin, of nx × ny cells, each
    split into two triangles by the diagonal that alternates from cell to cell (a union jack, so
    that the sheet has no preferred direction). Returns vertices [m] ((nx + 1)(ny + 1), 3), row by
    row in x, and triangles (2 nx ny, 3), counter-clockwise seen from +z."""
    x, y = np.linspace(-lx / 2, lx / 2, nx + 1), np.linspace(-ly / 2, ly / 2, ny + 1)
    V = np.stack([*np.meshgrid(x, y), np.zeros((ny + 1, nx + 1))], axis=-1).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(nx), np.arange(ny))
    a = (j * (nx + 1) + i).ravel()  # each cell's corners: a, b = a + 1 along x; c, d above them
    b, c = a + 1, a + nx + 1
    d = c + 1
    even = ((i + j) % 2 == 0).ravel()
    t1 = np.where(even[:, None], np.stack([a, b, d], 1), np.stack([a, b, c], 1))
    t2 = np.where(even[:, None], np.stack([a, d, c], 1), np.stack([b, d, c], 1))
    return V, np.vstack([t1, t2]).astype(np.int64)


def _rim(F: np.ndarray) -> np.ndarray:
    """The vertices on a triangle surface's open edges (edges of one triangle), ascending."""
    from ..mesh.repair import edge_counts

    edges, count = edge_counts(F)
    return np.unique(edges[count == 1])
