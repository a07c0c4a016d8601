"""The [mesh] table of a scene: a volume mesh file, a surface file (through the mesh pipeline) or a
primitive, then scale, rotation and translation."""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..errors import MeshError
from ..io.files import file_problem
from ..mesh.surface import SURFACE_SUFFIXES, metres_hint
from ..mesh.tetra import MAX_ENVELOPE, MIN_ENVELOPE, edge
from .schema import Ctx, check_keys, vector

if TYPE_CHECKING:
    from .loader import Scene


def _rotation(deg) -> np.ndarray:
    R = np.eye(3)
    for axis, a in enumerate(np.radians(deg)):
        c, s = math.cos(a), math.sin(a)
        i, j = [(1, 2), (0, 2), (0, 1)][axis]
        Q = np.eye(3)
        Q[i, i], Q[i, j], Q[j, i], Q[j, j] = c, -s, s, c
        if axis == 1:
            Q[i, j], Q[j, i] = s, -s
        R = Q @ R
    return R


def placed(ctx: Ctx, spec: dict, key: str, X: np.ndarray) -> np.ndarray:
    """Points X [m] (N, 3) of a [mesh], [[body]] or [[sheet]] table ``spec`` (``key``) placed as it
    says: turned by ``rotate`` (degrees about x, then y, then z), then moved by ``translate`` [m]."""
    if "rotate" in spec:
        X = X @ _rotation(vector(ctx, spec["rotate"], f"{key}.rotate")).T
    if "translate" in spec:
        X = X + np.array(vector(ctx, spec["translate"], f"{key}.translate"))
    return X


def _split_note(f, split: dict[str, int], tets: int) -> str:
    """The note that a mesh file's cells other than linear tets were split into tetrahedra."""
    from ..io.mesh import LINEARIZED

    plural = {"hexahedron": "hexahedra", "wedge": "wedges", "pyramid": "pyramids"}
    cells = ", ".join(f"{n:,} {plural.get(kind, kind) if n > 1 else kind}" for kind, n in split.items())
    quadratic = sorted(set(split) & set(LINEARIZED))
    by_corners = f"; the {', '.join(quadratic)} by their corners, mid-edge nodes dropped" if quadratic else ""
    return (
        f"{f}: {cells} split into tetrahedra (pliant.mesh.split; {tets:,} tets in all{by_corners}): "
        "pliant simulates linear tetrahedra; with a nearly incompressible material set solver.nodal_pressure"
    )


def load_mesh(ctx: Ctx, spec: dict, base: Path, scene: Scene, key: str = "mesh"):
    """The mesh of a [mesh] table (or of a [[body]] table: ``key`` names it in errors): nodes [m]
    (N, 3), tets (M, 4), and a mesh file's element sets and node sets (pliant.io.mesh)."""
    from .. import mesh as pm
    from ..io.mesh import read_volume_mesh_file
    from ..io.vtk_polydata import is_vtk_polydata

    check_keys(
        ctx,
        spec,
        key,
        {
            "name": "str",
            "file": "str",
            "primitive": "str",
            "size": "list|number",
            "cells": "list [nx, ny, nz]",
            "radius": "number",
            "height": "number",
            "major_radius": "number",
            "minor_radius": "number",
            "edge_length": "number",
            "scale": "number",
            "rotate": "list [ax, ay, az] (degrees about x, then y, then z)",
            "translate": "list [dx, dy, dz] [m]",
            "jitter": "number",
            "segments": "int",
            "minor_segments": "int",
            "target_tets": "int",
            "embed": "bool",
            "embed_subdivide": "int",
            "bodies": "str",
            "envelope": "number",
            "fill_shell": "bool",
        },
    )
    if ("file" in spec) == ("primitive" in spec):
        raise ctx.error(key, "give exactly one of 'file' or 'primitive'")
    sets: dict[str, np.ndarray] = {}
    node_sets: dict[str, np.ndarray] = {}
    scale = float(spec.get("scale", 1.0))
    if not scale > 0:
        raise ctx.error(f"{key}.scale", "expected a scale > 0")

    def pos(name):
        v = spec.get(name)
        if v is None:
            raise ctx.error(key, f"primitive {spec['primitive']!r} needs '{name}' [m]")
        if not v > 0:
            raise ctx.error(f"{key}.{name}", f"{name} = {v!r}: expected a length > 0 [m]")
        return float(v)

    el = spec.get("edge_length")
    if el is not None and not el > 0:
        raise ctx.error(f"{key}.edge_length", "expected a length > 0 [m]")
    if "file" in spec:
        f = Path(spec["file"])
        f = f if f.is_absolute() else base / f
        problem = file_problem(f)
        if problem:
            raise ctx.error(f"{key}.file", f"{problem}: {f}")
        try:
            surface = f.suffix.lower() in SURFACE_SUFFIXES or is_vtk_polydata(f)
            _surface_keys_only(ctx, key, spec, surface)
            if surface:  # a surface: tetrahedralized
                V, F = pm.read_surface(f)
                from ..mesh.pipeline import BODIES

                if spec.get("bodies", "union") not in BODIES:
                    raise ctx.error(
                        f"{key}.bodies", f"bodies = {spec['bodies']!r}; expected one of {', '.join(BODIES)}"
                    )
                env = spec.get("envelope")
                if env is not None and not MIN_ENVELOPE <= env <= MAX_ENVELOPE:
                    raise ctx.error(
                        f"{key}.envelope",
                        f"envelope = {env}; expected {MIN_ENVELOPE:g} to {MAX_ENVELOPE:g} (a fraction of "
                        "the bounding-box diagonal: a smaller one runs fTetWild for minutes, a larger "
                        "one makes it abort)",
                    )
                _edge_fits(ctx, key, el, V * scale)
                X, T, info = pm.surface_to_tets(
                    V * scale,
                    F,
                    edge_length=el,
                    target_tets=spec.get("target_tets", 10000),
                    epsilon=env,
                    bodies=spec.get("bodies", "union"),
                    fill_shell=bool(spec.get("fill_shell", False)),
                )
                scene.meta["mesh_pipeline"] = info
                scene.warnings += [f"{f}: {note}" for note in info["warnings"]]
                if spec.get("embed") or spec.get("embed_subdivide"):
                    Ve, Fe = pm.subdivide_loop(V * scale, F, int(spec.get("embed_subdivide", 0)))
                    scene.meta["embed_surface"] = [Ve, Fe]
                scale = 1.0
            else:
                X, T, sets, node_sets, split = read_volume_mesh_file(f)
                if split:
                    scene.warnings.append(_split_note(f, split, len(T)))
        except MeshError as e:
            raise ctx.error(f"{key}.file", str(e)) from None
        scene.meta["mesh_source"] = str(f)
    else:
        _surface_keys_only(ctx, key, spec, False)
        kind = spec["primitive"]
        if kind == "box":
            size = spec.get("size", [0.1, 0.1, 0.1])
            size = vector(ctx, size, f"{key}.size") if isinstance(size, list) else [float(size)] * 3
            if min(size) <= 0:
                raise ctx.error(f"{key}.size", "expected lengths > 0 [m]")
            h = el or min(size) / 4
            cells = spec.get("cells") or [max(1, round(s / h)) for s in size]
            if not (
                len(cells) == 3
                and all(isinstance(c, int) and not isinstance(c, bool) and c >= 1 for c in cells)
            ):
                raise ctx.error(f"{key}.cells", "expected three integers >= 1")
            X, T = pm.box_tets(
                size, cells, origin=[-s / 2 for s in size], jitter=float(spec.get("jitter", 0.0))
            )
        elif kind in ("sphere", "cylinder", "torus"):
            if kind == "sphere":
                V, F = pm.primitive_surface("sphere", radius=pos("radius"))
            elif kind == "cylinder":
                V, F = pm.primitive_surface(
                    "cylinder", radius=pos("radius"), height=pos("height"), segments=spec.get("segments", 48)
                )
            else:
                V, F = pm.primitive_surface(
                    "torus",
                    major_radius=pos("major_radius"),
                    minor_radius=pos("minor_radius"),
                    segments=spec.get("segments", 48),
                    minor_segments=spec.get("minor_segments", 24),
                )
            _edge_fits(ctx, key, el, V)
            X, T, info = pm.surface_to_tets(V, F, edge_length=el, target_tets=spec.get("target_tets", 10000))
            scene.meta["mesh_pipeline"] = info
            scene.warnings += [f"primitive {kind}: {note}" for note in info["warnings"]]
        else:
            raise ctx.error(
                f"{key}.primitive", f"unknown primitive {kind!r}; expected box, sphere, cylinder or torus"
            )
        scene.meta["mesh_source"] = f"primitive {kind}"
    X = placed(ctx, spec, key, np.asarray(X, float) * scale)
    emb = scene.meta.get("embed_surface")
    if emb:
        emb[0] = placed(ctx, spec, key, emb[0])
    hint = metres_hint(X, str(ctx.file), "set mesh.scale = 0.001")
    if hint:
        scene.warnings.append(hint)
    return X, np.asarray(T, np.int64), sets, node_sets


# Keys that only a surface file's tetrahedralization reads.
SURFACE_KEYS = ("bodies", "envelope", "fill_shell")


def _edge_fits(ctx: Ctx, key: str, el, V: np.ndarray) -> None:
    """A tet edge ``el`` [m] (or None) at most the surface's bounding-box diagonal: tetra.edge's
    check, its refusal named by the key (surface_to_tets names none)."""
    if el is None:
        return
    try:
        edge(el, float(np.linalg.norm(np.ptp(V, axis=0))), "")
    except MeshError as e:
        raise ctx.error(f"{key}.edge_length", str(e)) from None


def _surface_keys_only(ctx, key: str, spec: dict, surface: bool) -> None:
    """Refuse a surface-meshing key on a primitive or a volume mesh, which it would not change."""
    given = [k for k in SURFACE_KEYS if k in spec]
    if given and not surface:
        what = f"primitive {spec['primitive']!r}" if "primitive" in spec else "a volume mesh file"
        raise ctx.error(
            f"{key}.{given[0]}",
            f"'{given[0]}' applies to a surface file ({', '.join(SURFACE_SUFFIXES)}, VTK polydata) that is "
            f"tetrahedralized, not to {what}",
        )
