"""The [[membrane]] tables of a scene: membrane triangles on the mesh's boundary (an organ's
capsule, a vessel's wall), each table a material with its thickness [m] and density [kg/m³] on the
boundary triangles whose three nodes are all selected (``nodes``; the whole boundary without it).

    [[membrane]]
    type = "neo-hookean"        # or "st-venant-kirchhoff" (E, nu)
    mu = 2e4                    # [Pa]
    thickness = 1e-4            # [m]
    density = 1100.0            # [kg/m^3]
    nodes = { box = [[-1, -1, 0.01], [1, 1, 1]] }
    wrinkling = false           # true: carries no compression (tension-field theory)
    bending = false             # true: a plate of its own E, nu; a number: its bending E [Pa]
    bending_nu = 0.3            # Poisson's ratio of its bending (default the material's)

A membrane on a solid carries compression by default (the solid holds it flat, as NiftySim's do);
a [[sheet]] apart from the tets wrinkles by default (pliant.scene.sheets). A sheet that bends
(rotation-free shell triangles: pliant.StVKMembrane's ``bending``) has its boundary edges clamped
where both their nodes are held in all three directions (a [[fix]] of all DOFs). With a bending
modulus (a number), E or mu may be 0: a sheet that only bends (docs/engine.md, "Bending").
"""

from __future__ import annotations


from ..materials.membrane import NeoHookeanMembrane, StVKMembrane
from ..mesh.topology import boundary_faces
from ..tled import ModelBuilder
from .schema import Ctx, check_keys
from .select import select_faces

__all__ = ["MATERIAL_KEYS", "MEMBRANES", "add_membranes", "membrane_material"]

# Scene type → (class, its parameters besides thickness and density, in the constructor's order).
MEMBRANES = {
    "neo-hookean": (NeoHookeanMembrane, ("mu",)),
    "st-venant-kirchhoff": (StVKMembrane, ("E", "nu")),
}


def add_membranes(ctx: Ctx, tables: list, b: ModelBuilder, X, T, node_sets) -> None:
    """Each [[membrane]] table onto the builder, its errors naming the table's key and line."""
    if not isinstance(tables, list):
        raise ctx.error("membrane", "expected [[membrane]] tables")
    for i, m in enumerate(tables):
        p = f"membrane[{i}]"
        check_keys(ctx, m, p, MATERIAL_KEYS | {"nodes": "table"}, ("type", "thickness", "density"))
        material = membrane_material(ctx, m, p, {"nodes"}, wrinkling=False)
        faces = (
            select_faces(ctx, m["nodes"], f"{p}.nodes", X, T, node_sets)[0]
            if "nodes" in m
            else boundary_faces(T)[0]
        )
        with ctx.under(p):
            b.add_membrane(faces, material)


# The keys of a membrane material in a [[membrane]] or [[sheet]] table.
MATERIAL_KEYS = {
    "type": "str",
    "E": "number",
    "nu": "number",
    "mu": "number",
    "thickness": "number",
    "density": "number",
    "wrinkling": "bool",
    "bending": "bool|number",
    "bending_nu": "number",
}


def membrane_material(ctx: Ctx, m: dict, p: str, other: set[str], wrinkling: bool):
    """The membrane material of table ``m`` (``p``, its key; its keys checked): ``type`` and that
    type's parameters, thickness [m], density [kg/m³], ``bending`` and ``bending_nu``, and
    ``wrinkling`` (default ``wrinkling`` where it does not bend, else false: a sheet that bends
    buckles at a load of its own);
    ``other``: the table's keys that are not the material's."""
    if m["type"] not in MEMBRANES:
        raise ctx.error(
            f"{p}.type", f"unknown membrane {m['type']!r}; expected one of {', '.join(MEMBRANES)}"
        )
    cls, params = MEMBRANES[m["type"]]
    given = set(m) - {"type", "thickness", "density", "wrinkling", "bending", "bending_nu"} - other
    if given != set(params):
        raise ctx.error(
            p, f"{m['type']} takes ({', '.join(params)}); got ({', '.join(sorted(given)) or 'nothing'})"
        )
    with ctx.under(p):
        material = cls(
            *[m[k] for k in params],
            m["thickness"],
            m["density"],
            wrinkling=m.get("wrinkling", wrinkling),
            bending=m.get("bending", False),
            bending_nu=m.get("bending_nu"),
        )
    return material.taut() if material.bends and "wrinkling" not in m else material
