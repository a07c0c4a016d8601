"""Scene files (TOML) → a validated :class:`Scene`: the top-level tables, materials, constraints,
loads and outputs (the mesh and the tools have their own modules). See the package docstring."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from .. import _core
from .. import materials as mat
from ..errors import InputError, PliantWarning
from ..tled import Constant, ModelBuilder, Ramp, SmoothRamp, Step, Table
from ..tled.curves import LoadCurve
from ..tled.model import BACKENDS
from ..tled.anp import anp_stabilization
from ..tled.smoothing import strain_smoothing
from ..tled.solver import MAX_INCREMENTS
from ..job import Scene
from ..cutting.cut import check_cuttable
from .bodies import load_bodies, set_contact
from .membranes import add_membranes
from .sheets import load_sheets
from .keys import apply_overrides
from .schema import Ctx, check_keys, read_toml, vector
from .tools import make_tool
from .select import nearest_node, select_elements, select_faces, select_nodes


__all__ = ["load_scene", "make_curve"]


_MATERIALS: dict[str, tuple[Any, tuple[str, ...]]] = {
    "neo-hookean": (mat.NeoHookean, ("mu", "K")),
    "mooney-rivlin": (mat.MooneyRivlin, ("C10", "C01", "K")),
    "neo-hookean-coupled": (mat.NeoHookeanCoupled, ("mu", "lam")),
    "st-venant-kirchhoff": (mat.StVenantKirchhoff, ("mu", "lam")),
    "linear-elastic": (mat.LinearElastic, ("mu", "lam")),
    "polynomial": (
        lambda C10, C01, C20, C02, C11, K: mat.Polynomial(C10, C01, C20, C02, C11, K=K),
        ("C10", "C01", "C20", "C02", "C11", "K"),
    ),
    "arruda-boyce": (mat.ArrudaBoyce, ("mu", "lambda_m", "K")),
    "transversely-isotropic": (mat.TransverselyIsotropic, ("mu", "K", "eta", "direction")),
}
_NO_E_NU = ("mooney-rivlin", "polynomial", "arruda-boyce", "transversely-isotropic")


def make_curve(ctx: Ctx, spec, path: str, duration: float) -> LoadCurve:
    """'constant' | 'step' | 'ramp' | 'smooth-ramp' (0 → 1 over the duration) or a table
    {type = 'ramp' | 'smooth-ramp', t0, t1} | {type = 'step', t0} | {type = 'table', times, values}."""
    if spec is None:
        return Constant()
    if isinstance(spec, str):
        spec = {"type": spec}
    check_keys(
        ctx,
        spec,
        path,
        {"type": "str", "t0": "number", "t1": "number", "times": "list", "values": "list"},
        ("type",),
    )
    kind = spec["type"]
    with ctx.under(path):
        if kind == "constant":
            return Constant()
        if kind == "step":
            return Step(spec.get("t0", 0.0))
        if kind in ("ramp", "smooth-ramp"):
            cls = Ramp if kind == "ramp" else SmoothRamp
            return cls(spec.get("t1", duration), spec.get("t0", 0.0))
        if kind == "table":
            if "times" not in spec or "values" not in spec:
                raise ctx.error(path, "a table curve needs 'times' and 'values'")
            return Table(spec["times"], spec["values"])
    raise ctx.error(
        f"{path}.type", f"unknown curve {kind!r}; expected constant, step, ramp, smooth-ramp or table"
    )


def load_scene(path, overrides: dict | None = None) -> Scene:
    """Read and validate a scene file (TOML). Raises SceneError naming file, key and line.

    ``overrides`` maps dotted key paths (``'material.liver.E'``, ``'tool[1].keyframes[2].position[2]'``,
    see :mod:`pliant.scene.keys`) to values set before validation (a sweep's parameters)."""
    path = Path(path)
    text, data = read_toml(path)
    data = apply_overrides(data, overrides, str(path))
    ctx = Ctx(str(path), text)
    if isinstance(data, dict) and "base" in data and ("parameter" in data or "design" in data):
        raise ctx.error(
            "base",
            "this is a sweep file (a base scene, a design, parameters), not a scene: "
            "run it with `pliant sweep`",
        )
    check_keys(
        ctx,
        data,
        "",
        {
            "title": "str",
            "mesh": "table",
            "material": "list",
            "solver": "table",
            "constraint": "list",
            "load": "list",
            "tool": "list",
            "output": "table",
            "body": "list",
            "contact": "table",
            "membrane": "list",
            "sheet": "list",
        },
    )
    _check_bodies_given(ctx, data)
    b = ModelBuilder()
    scene = Scene(str(path), b, title=data.get("title", path.stem))
    _solver_settings(ctx, data.get("solver", {}), scene)
    X, T, sets, names, scene.node_sets = load_bodies(ctx, data, path.parent, scene, b)
    _materials(ctx, data.get("material", []), b, X, T, sets)
    add_membranes(ctx, data.get("membrane", []), b, X, T, scene.node_sets)
    X, sheets = load_sheets(ctx, data.get("sheet", []), path.parent, b, X, names, scene.node_sets)
    if "contact" in data:
        set_contact(ctx, data["contact"], b, sets, names, sheets)
    _constraints(ctx, data.get("constraint", []), b, X, T, scene)
    _loads(ctx, data.get("load", []), b, X, T, scene)
    _tools(ctx, data.get("tool", []), b, X, T, path.parent, scene)
    _output(ctx, data, scene, X)
    if scene.blades and scene.static:
        raise ctx.error(
            "tool", "a blade cuts while a dynamic run steps; a quasi-static solve has no motion to cut along"
        )
    if scene.blades:
        try:
            check_cuttable(b)
        except InputError as e:
            raise ctx.error("solver.strain_smoothing", str(e)) from None
    return scene


def _check_bodies_given(ctx: Ctx, data: dict) -> None:
    """A scene simulates a body of tets ([mesh], with its [[material]]) or sheets alone ([[sheet]],
    each with its own membrane material: a drape on a tool); [[body]] tables add to a [mesh]."""
    if "mesh" in data:
        if "material" not in data:
            raise ctx.error("", "missing key 'material' (the [[material]] of the [mesh]'s tets)")
        return
    if not data.get("sheet"):  # (no sheets in an empty list either)
        raise ctx.error(
            "", "missing key 'mesh': a scene needs a body of tets ([mesh]) or a sheet ([[sheet]])"
        )
    for key, what in (
        ("body", "[[body]] tables add bodies to a [mesh]"),
        ("material", "[[material]] gives the material of a [mesh]'s tets"),
    ):
        if key in data:
            raise ctx.error(
                key,
                f"{what}; this scene has no [mesh] (give the first body as [mesh]; "
                "a sheet's material is in its [[sheet]] table)",
            )


def _solver_settings(ctx: Ctx, solver: dict, scene: Scene) -> None:
    """The [solver] table: time, step, precision, backend, threads, quasi-static options, damping."""
    check_keys(
        ctx,
        solver,
        "solver",
        {
            "dt": "number|str",
            "safety": "number",
            "damping": "number",
            "duration": "number",
            "stiffness_damping": "number",
            "nodal_pressure": "bool",
            "nodal_pressure_stabilization": "number|str",
            "strain_smoothing": "str",
            "dtype": "str",
            "threads": "int",
            "static": "bool",
            "tol": "number",
            "increments": "int",
            "check_every": "int",
            "backend": "str",
        },
    )
    scene.duration = float(solver.get("duration", 1.0))
    if not scene.duration > 0:
        raise ctx.error("solver.duration", "expected a duration > 0 [s]")
    dt = solver.get("dt", "auto")
    if isinstance(dt, str):
        if dt != "auto":
            raise ctx.error("solver.dt", f"dt = {dt!r}: expected 'auto' or a time step [s]")
    elif not dt > 0:
        raise ctx.error("solver.dt", f"dt = {dt!r}: expected a time step > 0 [s]")
    else:
        scene.dt = float(dt)
    scene.safety = float(solver.get("safety", 0.8))
    if not 0 < scene.safety <= 1:
        raise ctx.error("solver.safety", "expected 0 < safety <= 1")
    scene.dtype = solver.get("dtype", "float32")
    if scene.dtype not in ("float32", "float64"):
        raise ctx.error("solver.dtype", f"dtype = {scene.dtype!r}: expected 'float32' or 'float64'")
    scene.backend = solver.get("backend", "cpu")
    if scene.backend not in BACKENDS:
        raise ctx.error(
            "solver.backend", f"backend = {scene.backend!r}: expected one of {', '.join(BACKENDS)}"
        )
    scene.threads = solver.get("threads")
    if scene.threads is not None and not 1 <= scene.threads <= _core.thread_limit():
        raise ctx.error(
            "solver.threads",
            f"threads = {scene.threads}; expected 1 to "
            f"{_core.thread_limit()} on this machine (leave it out for automatic)",
        )
    scene.static = bool(solver.get("static", False))
    scene.tol = float(solver.get("tol", 1e-5))
    scene.increments = int(solver.get("increments", 1))
    scene.check_every = int(solver.get("check_every", 16))
    if not 1 <= scene.increments <= MAX_INCREMENTS:
        raise ctx.error(
            "solver.increments", f"increments = {scene.increments}; expected 1 to {MAX_INCREMENTS}"
        )
    if not 1 <= scene.check_every <= 10**6:
        raise ctx.error("solver.check_every", f"check_every = {scene.check_every}; expected 1 to 1000000")
    damping = float(solver.get("damping", 0.0))
    if damping < 0:
        raise ctx.error("solver.damping", "expected damping >= 0 [1/s]")
    scene.builder.damping = damping
    beta = float(solver.get("stiffness_damping", 0.0))
    if beta < 0:
        raise ctx.error("solver.stiffness_damping", "expected stiffness_damping >= 0 [s]")
    scene.builder.stiffness_damping = beta
    scene.builder.nodal_pressure = bool(solver.get("nodal_pressure", False))
    gamma = solver.get("nodal_pressure_stabilization", scene.builder.nodal_pressure_stabilization)
    try:
        anp_stabilization(gamma)
    except InputError as e:
        raise ctx.error("solver.nodal_pressure_stabilization", str(e)) from None
    scene.builder.nodal_pressure_stabilization = gamma
    try:
        scene.builder.strain_smoothing = strain_smoothing(solver.get("strain_smoothing", "element"))
    except InputError as e:
        raise ctx.error("solver.strain_smoothing", str(e)) from None


def _materials(ctx: Ctx, tables: list, b: ModelBuilder, X, T, sets) -> None:
    """The [[material]] tables: a model from native constants or (E, nu), optionally viscoelastic,
    on a region or on every element not yet assigned."""
    for i, m in enumerate(tables):
        p = f"material[{i}]"
        check_keys(
            ctx,
            m,
            p,
            {
                "type": "str",
                "region": "table",
                "density": "number",
                "E": "number",
                "nu": "number",
                "mu": "number",
                "K": "number",
                "lam": "number",
                "lambda": "number",
                "C10": "number",
                "C01": "number",
                "C20": "number",
                "C02": "number",
                "C11": "number",
                "lambda_m": "number",
                "eta": "number",
                "direction": "list [x, y, z]",
                "prony_iso": "list",
                "prony_vol": "list",
                "name": "str",
            },
            ("type", "density"),
        )
        if m["type"] not in _MATERIALS:
            raise ctx.error(
                f"{p}.type", f"unknown material {m['type']!r}; expected one of {', '.join(_MATERIALS)}"
            )
        with ctx.under(p):
            material = _material(ctx, m, p)
            elems = select_elements(ctx, m["region"], f"{p}.region", X, T, sets) if "region" in m else None
            b.set_material(material, m["density"], elements=elems, name=m.get("name", p))


def _material(ctx: Ctx, m: dict, p: str):
    cls, native = _MATERIALS[m["type"]]
    if "lambda" in m:  # the key's old name: one name per parameter across Python and scenes
        import warnings

        warnings.warn(
            f"{ctx.file}: {p}.lambda is deprecated; name it 'lam' (as in Python)", PliantWarning, stacklevel=2
        )
        m = {("lam" if k == "lambda" else k): v for k, v in m.items()}
    given = {k for k in m if k not in ("type", "region", "density", "name", "prony_iso", "prony_vol")}
    if m["type"] == "polynomial":  # higher-order constants default to 0
        given |= {"C01", "C20", "C02", "C11"}
        m = {"C01": 0.0, "C20": 0.0, "C02": 0.0, "C11": 0.0, **m}
    if given == {"E", "nu"} and m["type"] not in _NO_E_NU:
        material = cls(E=m["E"], nu=m["nu"])
    elif given == set(native):
        material = cls(*[m[k] for k in native])
    else:
        alt = " or (E, nu)" if m["type"] not in _NO_E_NU else ""
        raise ctx.error(
            p, f"{m['type']} takes ({', '.join(native)}){alt}; got ({', '.join(sorted(given)) or 'nothing'})"
        )
    if "prony_iso" in m or "prony_vol" in m:  # visco-hyperelastic: (alpha, tau [s]) pairs
        material = mat.Viscoelastic(material, m.get("prony_iso", []), m.get("prony_vol", []))
    return material


def _constraints(ctx: Ctx, tables: list, b: ModelBuilder, X, T, scene: Scene) -> None:
    """The [[constraint]] tables: 'fix' or 'displacement' (value [m], optional curve)."""
    for i, c in enumerate(tables):
        p = f"constraint[{i}]"
        check_keys(
            ctx,
            c,
            p,
            {
                "type": "str",
                "nodes": "table",
                "dofs": "str",
                "value": "number|list",
                "curve": "str|table",
                "name": "str",
            },
            ("type", "nodes"),
        )
        ids = select_nodes(ctx, c["nodes"], f"{p}.nodes", X, T, scene.node_sets)
        dofs = c.get("dofs", "xyz")
        name = c.get("name") or p  # its reaction's label (reactions.json)
        with ctx.under(p):
            if c["type"] == "fix":
                if "value" in c or "curve" in c:
                    raise ctx.error(p, "a 'fix' constraint takes no value or curve")
                b.fix(ids, dofs, name=name)
            elif c["type"] == "displacement":
                if "value" not in c:
                    raise ctx.error(p, "a 'displacement' constraint needs 'value' [m]")
                b.prescribe(
                    ids,
                    c["value"],
                    dofs,
                    make_curve(ctx, c.get("curve"), f"{p}.curve", scene.duration),
                    name=name,
                )
            else:
                raise ctx.error(
                    f"{p}.type", f"unknown constraint {c['type']!r}; expected 'fix' or 'displacement'"
                )


def _loads(ctx: Ctx, tables: list, b: ModelBuilder, X, T, scene: Scene) -> None:
    """The [[load]] tables."""
    for i, ld in enumerate(tables):
        p = f"load[{i}]"
        check_keys(
            ctx,
            ld,
            p,
            {
                "type": "str",
                "nodes": "table",
                "force": "list [fx, fy, fz] [N]",
                "total_force": "list [fx, fy, fz] [N]",
                "g": "list [gx, gy, gz] [m/s²]",
                "value": "number",
                "traction": "list [tx, ty, tz] [Pa]",
                "curve": "str|table",
                "name": "str",
            },
            ("type",),
        )
        with ctx.under(p):
            _add_load(ctx, b, ld, p, X, T, scene)


def _tools(ctx: Ctx, tables: list, b: ModelBuilder, X, T, base: Path, scene: Scene) -> None:
    """The [[tool]] tables, each optionally restricted to a node selection; blades go to the
    scene (they cut; they are not contact tools)."""
    from ..cutting import Blade

    for i, t in enumerate(tables):
        p = f"tool[{i}]"
        if not isinstance(t, dict):
            raise ctx.error(p, f"expected a table, got {type(t).__name__}")
        with ctx.under(p):
            only = (
                select_nodes(ctx, t["nodes"], f"{p}.nodes", X, T, scene.node_sets) if "nodes" in t else None
            )
            tool = make_tool(ctx, t, p, base)
            if isinstance(tool, Blade):
                if only is not None:
                    raise ctx.error(
                        f"{p}.nodes", "a blade cuts whatever it sweeps; expected no node selection"
                    )
                scene.blades.append(tool)
            else:
                b.add_tool(tool, nodes=only)


def _add_load(ctx: Ctx, b: ModelBuilder, ld: dict, p: str, X, T, scene: Scene) -> None:
    """One [[load]] table: gravity (on every node, or on the selected ones), force, pressure or
    traction."""
    curve = make_curve(ctx, ld.get("curve"), f"{p}.curve", scene.duration)
    if ld["type"] == "gravity":
        g = vector(ctx, ld.get("g", [0.0, 0.0, -9.81]), f"{p}.g")
        if "nodes" in ld:
            b.add_gravity(g, select_nodes(ctx, ld["nodes"], f"{p}.nodes", X, T, scene.node_sets), curve)
        else:
            b.set_gravity(g, curve)
    elif ld["type"] == "force":
        if "nodes" not in ld or (("force" in ld) == ("total_force" in ld)):
            raise ctx.error(
                p,
                "a 'force' load needs 'nodes' and one of 'force' (per node [N]) "
                "or 'total_force' (shared equally [N])",
            )
        ids = select_nodes(ctx, ld["nodes"], f"{p}.nodes", X, T, scene.node_sets)
        if "force" in ld:
            f = np.array(vector(ctx, ld["force"], f"{p}.force"))
        else:
            f = np.array(vector(ctx, ld["total_force"], f"{p}.total_force")) / ids.size
        b.add_force(ids, f, curve)
    elif ld["type"] in ("pressure", "traction"):
        key, unit = ("value", "[Pa]") if ld["type"] == "pressure" else ("traction", "[tx, ty, tz] [Pa]")
        if "nodes" not in ld or key not in ld:
            raise ctx.error(
                p,
                f"a '{ld['type']}' load needs '{key}' {unit} and 'nodes' (the boundary "
                "triangles whose three nodes are all selected)",
            )
        # The tets' boundary triangles and the sheets' (membranes apart from the tets, as wound).
        sheets = b.membrane_faces()[b.free_membranes()]
        faces, on_sheets = select_faces(ctx, ld["nodes"], f"{p}.nodes", X, T, scene.node_sets, sheets)
        for F, solid in ((faces, True), (on_sheets, False)):
            if not len(F):
                continue
            if ld["type"] == "pressure":  # a solid's faces point out of it; a sheet's as wound
                b.add_pressure(F, float(ld["value"]), curve, orient=solid)
            else:
                b.add_traction(F, vector(ctx, ld["traction"], f"{p}.traction"), curve)
    else:
        raise ctx.error(
            f"{p}.type",
            f"unknown load {ld['type']!r}; expected 'force', 'pressure', 'traction' or 'gravity'",
        )


def _output(ctx: Ctx, data: dict, scene: Scene, X: np.ndarray) -> None:
    """The [output] table; its points (probes) resolved to the nodes nearest them in X [m]."""
    out = check_keys(
        ctx,
        data.get("output", {}),
        "output",
        {
            "every": "int",
            "interval": "number",
            "frames": "int",
            "png": "bool",
            "fields": "list",
            "points": "table",
        },
    )
    scene.points = {
        str(name): nearest_node(ctx, vector(ctx, v, f"output.points.{name}"), f"output.points.{name}", X)
        for name, v in out.get("points", {}).items()
    }
    from ..io.results import FIELDS

    fields = out.get("fields", list(FIELDS[:5]))
    bad = [x for x in fields if x not in FIELDS]
    if bad:
        raise ctx.error("output.fields", f"unknown field(s) {bad}; expected some of {list(FIELDS)}")
    scene.fields = tuple(fields)
    if sum(k in out for k in ("every", "interval", "frames")) > 1:
        raise ctx.error("output", "give at most one of 'every' (steps), 'interval' [s], 'frames'")
    if (
        "every" in out
        and out["every"] < 1
        or "frames" in out
        and out["frames"] < 1
        or "interval" in out
        and not out["interval"] > 0
    ):
        raise ctx.error("output", "every, frames and interval must be positive")
    scene.output_every = out.get("every")
    scene.output_interval = out.get("interval")
    scene.frames = int(out.get("frames", 20))
    scene.meta["frames_given"] = "frames" in out  # the runner says so if there are fewer steps
    scene.png = bool(out.get("png", True))
