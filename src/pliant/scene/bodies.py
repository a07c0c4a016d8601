"""Several bodies in a scene, and contact between them: the [[body]] tables (each a mesh like
[mesh], with a name) and the [contact] table (soft contact: friction, pairs, self contact)::

    [mesh]                      # the first body; name = "..." optional (default "body0")
    [[body]]                    # every further body: name and the keys of [mesh]
    name = "kidney"
    file = "kidney.vtu"
    translate = [0.0, 0.0, -0.05]
    [contact]
    friction = 0.2              # μ, or [μs, μk]
    pairs = [["liver", "kidney"]]   # default: every pair of bodies (sheets too: [[sheet]])
    self = ["liver"]            # or true (every body); default false
    skin = 0.001                # [m], optional (ModelBuilder.set_soft_contact)

Each body's elements form an element set of its name (``region = { set = "kidney" }``); element
sets and node sets of a body's file are named "<body>.<set>" (the first body's as in its file).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..errors import InputError, MeshError
from .mesh import load_mesh
from .schema import Ctx, check_keys

if TYPE_CHECKING:
    from ..job import Scene
    from ..tled import ModelBuilder


def load_bodies(ctx: Ctx, data: dict, base: Path, scene: Scene, b: ModelBuilder) -> tuple:
    """The first body ([mesh]) and every [[body]] into the builder; returns the combined nodes
    (N, 3), tets (M, 4), the element sets (each body's by its name), the body names and the node
    sets of the bodies' files: none for a scene of sheets alone (no [mesh])."""
    if "mesh" not in data:
        scene.meta["mesh_source"] = ctx.file
        return np.zeros((0, 3)), np.zeros((0, 4), np.int64), {}, [], {}
    with ctx.under("mesh"):
        X, T, sets, node_sets = load_mesh(ctx, data["mesh"], base, scene)
    names = [str(data["mesh"].get("name", "body0"))]
    _add(ctx, b, X, T, scene.meta["mesh_source"], "mesh")
    sets = {**sets, names[0]: np.arange(len(T))}
    first_meta = dict(scene.meta)
    tables = data.get("body", [])
    if not isinstance(tables, list):
        raise ctx.error("body", "expected [[body]] tables")
    for i, spec in enumerate(tables):
        p = f"body[{i}]"
        if not isinstance(spec, dict):
            raise ctx.error(p, f"expected a table, got {type(spec).__name__}")
        name = spec.get("name")
        if not isinstance(name, str) or not name:
            raise ctx.error(f"{p}.name", "every [[body]] needs a name (a string)")
        if name in names:
            raise ctx.error(f"{p}.name", f"two bodies are named {name!r}; expected unique names")
        if spec.get("embed") or spec.get("embed_subdivide"):
            raise ctx.error(f"{p}.embed", "an embedded visual surface is for the first body ([mesh]) only")
        with ctx.under(p):
            Xi, Ti, si, ni = load_mesh(ctx, spec, base, scene, key=p)
        source = scene.meta["mesh_source"]
        scene.meta.clear()
        scene.meta.update(first_meta)  # the first body's pipeline report and source
        elems = _add(ctx, b, Xi, Ti, source, p)
        sets[name] = elems
        sets.update({f"{name}.{k}": v + elems[0] for k, v in si.items()})
        node_sets.update({f"{name}.{k}": v + len(X) for k, v in ni.items()})
        T = np.vstack([T, Ti + len(X)])
        X = np.vstack([X, Xi])
        names.append(name)
    return X, T, sets, names, node_sets


def _add(ctx: Ctx, b: ModelBuilder, X, T, source: str, key: str) -> np.ndarray:
    try:
        return b.add_mesh(X, T, source=source)
    except MeshError as e:
        raise ctx.error(key, str(e)) from None


def set_contact(ctx: Ctx, spec, b: ModelBuilder, sets: dict, names: list[str], sheets: dict) -> None:
    """The [contact] table: soft contact between the named bodies and sheets
    (ModelBuilder.set_soft_contact); ``sheets``: each sheet's membranes (scene.sheets)."""
    check_keys(
        ctx,
        spec,
        "contact",
        {"friction": "list|number", "pairs": "list", "self": "bool|list", "skin": "number"},
    )
    labels = b.bodies()
    apart, sheet_labels = b.sheet_bodies()

    def body_numbers(name, key: str) -> list[int]:
        if name not in names:
            raise ctx.error(key, f"unknown body {name!r}; the scene has: {', '.join(names)}")
        if name in sheets:
            return sorted({int(x) for x in sheet_labels[np.isin(apart, sheets[name])]})
        return sorted({int(x) for x in labels[sets[name]]})

    pairs = None
    if "pairs" in spec:
        pairs = []
        for k, pr in enumerate(spec["pairs"]):
            key = f"contact.pairs[{k}]"
            if not (isinstance(pr, list) and len(pr) == 2 and all(isinstance(n, str) for n in pr)):
                raise ctx.error(key, f"expected a pair of body names, got {pr!r}")
            pairs += [(a, c) for a in body_numbers(pr[0], key) for c in body_numbers(pr[1], key)]
    selfs = spec.get("self", False)
    if isinstance(selfs, list):
        selfs = [n for k, name in enumerate(selfs) for n in body_numbers(name, f"contact.self[{k}]")]
    try:
        b.set_soft_contact(spec.get("friction", 0.0), pairs=pairs, self_contact=selfs, skin=spec.get("skin"))
    except InputError as e:
        raise ctx.error("contact", str(e)) from None
    b.soft_contact.names = {int(x): name for name in names for x in body_numbers(name, "contact")}
