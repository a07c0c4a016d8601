"""The [[tool]] tables of a scene: rigid tools with friction and keyframes (docs/scenes.md)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .schema import Ctx, check_keys, vector


def make_tool(ctx: Ctx, t: dict, p: str, base: Path):
    """A rigid tool (or a blade, which cuts) from a [[tool]] table (see docs/scenes.md). Call it
    under ``ctx.under(p)``: the tool classes' InputErrors then name this file and key."""
    from .. import contact as ct
    from ..cutting import Blade

    check_keys(
        ctx,
        t,
        p,
        {
            "type": "str",
            "name": "str",
            "mu_s": "number",
            "mu_k": "number",
            "radius": "number",
            "length": "number",
            "depth": "number",
            "half_extents": "list [hx, hy, hz] [m]",
            "point": "list [x, y, z] [m]",
            "normal": "list [nx, ny, nz]",
            "file": "str",
            "scale": "number",
            "spacing": "number",
            "position": "list [x, y, z] [m]",
            "rotation": "list",
            "keyframes": "list",
            "nodes": "table",
            "grip": "list",
            "reach": "number",
        },
        ("type",),
    )
    kw = {"mu_s": t.get("mu_s", 0.0), "mu_k": t.get("mu_k"), "name": t.get("name")}

    def rot(v, key):
        if len(v) == 3:  # rotation vector in degrees: axis × angle
            a = np.radians(np.array(vector(ctx, v, key)))
            ang = float(np.linalg.norm(a))
            return ct.quat_from_axis_angle(a / ang, ang) if ang > 0 else np.array([1.0, 0, 0, 0])
        return np.array(vector(ctx, v, key, 4))

    kind = t["type"]
    pose = {}
    if "position" in t:
        pose["position"] = vector(ctx, t["position"], f"{p}.position")
    if "rotation" in t:
        pose["rotation"] = rot(t["rotation"], f"{p}.rotation")
    tool: ct.RigidTool
    if kind == "plane":
        tool = ct.Plane(
            vector(ctx, t.get("point", [0, 0, 0]), f"{p}.point"),
            vector(ctx, t.get("normal", [0, 0, 1]), f"{p}.normal"),
            **kw,
        )
    elif kind == "sphere":
        tool = ct.Sphere(t.get("radius", 0.0), **pose, **kw)
    elif kind == "capsule":
        tool = ct.Capsule(t.get("radius", 0.0), t.get("length", 0.0), **pose, **kw)
    elif kind == "cylinder":
        tool = ct.Cylinder(t.get("radius", 0.0), t.get("length", 0.0), **pose, **kw)
    elif kind == "box":
        tool = ct.Box(vector(ctx, t.get("half_extents", [0, 0, 0]), f"{p}.half_extents"), **pose, **kw)
    elif kind == "blade":
        tool = Blade(t.get("length", 0.0), t.get("depth", 0.0), **pose, name=t.get("name"))
    elif kind == "mesh":
        from ..mesh import read_surface

        f = Path(t.get("file", ""))
        f = f if f.is_absolute() else base / f
        V, F = read_surface(f)
        tool = ct.MeshTool(V * float(t.get("scale", 1.0)), F, t.get("spacing"), **pose, **kw)
    else:
        raise ctx.error(
            f"{p}.type",
            f"unknown tool {kind!r}; expected plane, sphere, capsule, cylinder, box, mesh or blade",
        )
    for j, k in enumerate(t.get("keyframes", [])):
        kp = f"{p}.keyframes[{j}]"
        check_keys(ctx, k, kp, {"t": "number", "position": "list", "rotation": "list"}, ("t", "position"))
        tool.at(
            k["t"],
            vector(ctx, k["position"], f"{kp}.position"),
            rot(k["rotation"], f"{kp}.rotation")
            if "rotation" in k
            else tool.keys[-1][4:]
            if tool.keys
            else (1.0, 0, 0, 0),
        )
    if "grip" in t or "reach" in t:
        if isinstance(tool, Blade):
            raise ctx.error(f"{p}.grip", "a blade cuts; it does not grasp")
        times = t.get("grip", [])
        for j, g in enumerate(times):
            if isinstance(g, bool) or not isinstance(g, (int, float)):
                raise ctx.error(f"{p}.grip[{j}]", f"expected a time [s], got {g!r}")
            if j % 2 == 0:
                tool.grasp(g, t.get("reach"))
            else:
                tool.release(g)
        if "reach" in t and not times:
            tool.set_reach(t["reach"])
    return tool
