"""Sweep files (TOML): a base scene or NiftySim model, the parameters to vary by key path, the
design that picks their values, fixed settings, the outputs to collect and the thread budget.
See docs/sweeps.md for the reference; :func:`load_sweep` validates and names file, key and line.

Example::

    base = "liver_indentation.toml"      # relative to this file
    threads = 1                          # per run
    [design]
    type = "lhs"                         # grid | list | lhs | sobol | saltelli
    samples = 16
    seed = 7
    [[parameter]]
    key = "material[0].E"
    range = [2.0e3, 8.0e3]               # lhs, sobol, saltelli (uniform; scale = "log" for log-uniform)
    [[parameter]]
    key = "tool.probe.keyframes[1].position[2]"
    values = [0.01, 0.02]                # grid, list
    [set]
    "solver.duration" = 0.05             # every run
    [output]
    points = { tip = [0.0, 0.0, 0.05] }  # displacement at the node nearest each point [m]
    tool_history = true
    fields = false                       # per-run result folders and OUT/dataset.h5
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .. import _core
from ..io.files import file_problem
from ..scene.schema import Ctx, SceneError, check_keys, read_toml, vector
from ..scene.select import nearest_node


__all__ = ["Parameter", "Design", "Outputs", "SweepSpec", "load_sweep", "DESIGNS"]

DESIGNS = ("grid", "list", "lhs", "sobol", "saltelli")
_SAMPLED = ("lhs", "sobol", "saltelli")
MAX_RUNS = 1_000_000  # a sweep's runs are listed in memory and on disk (a record each)


@dataclass(frozen=True)
class Parameter:
    """One varied input: its key path, and either explicit ``values`` (grid, list designs) or a
    ``range`` [low, high] sampled uniformly (``scale='log'``: log-uniform; lhs, sobol, saltelli)."""

    key: str
    values: tuple | None = None
    range: tuple[float, float] | None = None
    scale: str = "linear"

    @property
    def choices(self) -> tuple:
        """The explicit values (empty for a sampled parameter)."""
        return self.values or ()

    @property
    def bounds(self) -> tuple[float, float]:
        """[low, high] of a sampled parameter; ValueError for one with explicit values."""
        if self.range is None:
            raise ValueError(f"parameter {self.key!r} has explicit values, no range")
        return self.range


@dataclass(frozen=True)
class Design:
    """How parameter values are combined: ``grid`` (every combination of the values), ``list``
    (the i-th value of each parameter together), ``lhs`` (Latin hypercube), ``sobol`` (scrambled
    Sobol' sequence), ``saltelli`` (Saltelli's scheme for Sobol indices: samples·(D + 2) runs).
    ``samples`` counts runs for lhs and sobol, base samples for saltelli; ``seed`` fixes them."""

    type: str = "grid"
    samples: int = 0
    seed: int = 0


@dataclass(frozen=True)
class Outputs:
    """What each run reports beyond its summary (max displacement, max von Mises, energies, tool
    forces): displacement at the node nearest each named point [m], tool force histories, and
    ``fields`` (per-run result folders, and OUT/dataset.h5 with final fields for all runs)."""

    points: dict[str, tuple[float, float, float]] = field(default_factory=dict)
    tool_history: bool = False
    fields: bool = False


@dataclass
class SweepSpec:
    """A validated sweep: ``base`` (scene or NiftySim model), ``parameters``, ``design``, ``fixed``
    settings (key path → value for every run), ``outputs``, ``threads`` per run, NiftySim features
    to ``ignore``, and ``source`` (the sweep file)."""

    base: Path
    parameters: list[Parameter]
    design: Design = field(default_factory=Design)
    fixed: dict[str, Any] = field(default_factory=dict)
    outputs: Outputs = field(default_factory=Outputs)
    threads: int = 1
    ignore: tuple[str, ...] = ()
    source: str = ""
    batch: int = 1  # runs stepped together in one model (pliant.sweep.batched)

    def fingerprint(self) -> str:
        """A hash of everything that decides the runs' results (the spec and the base file's
        bytes), so that a resumed sweep can tell whether its finished runs still hold."""
        base = self.base.read_bytes() if self.base.is_file() else b""
        spec = json.dumps(
            {
                "parameters": [p.__dict__ for p in self.parameters],
                "design": self.design.__dict__,
                "fixed": self.fixed,
                "outputs": self.outputs.__dict__,
                "ignore": self.ignore,
                "batch": self.batch,
            },
            sort_keys=True,
            default=str,
        )
        return hashlib.sha256(spec.encode() + b"\0" + base).hexdigest()[:16]


def load_sweep(path) -> SweepSpec:
    """Read and validate a sweep file. Raises SceneError naming file, key and line."""
    path = Path(path)
    text, data = read_toml(path, "sweep")
    ctx = Ctx(str(path), text)
    check_keys(
        ctx,
        data,
        "",
        {
            "base": "str",
            "threads": "int",
            "ignore": "list",
            "design": "table",
            "parameter": "list",
            "set": "table",
            "output": "table",
            "batch": "int",
        },
        ("base", "parameter"),
    )
    base = (path.parent / data["base"]).resolve()
    problem = file_problem(base)
    if problem:
        raise ctx.error(
            "base", f"{'no such scene or NiftySim model' if problem == 'no such file' else problem}: {base}"
        )
    threads = data.get("threads", 1)
    limit = int(_core.thread_limit())
    if not 1 <= threads <= limit:
        raise ctx.error("threads", f"threads = {threads}: expected 1 to {limit} threads per run")
    design = _design(ctx, data.get("design", {}))
    params = [_parameter(ctx, p, f"parameter[{i}]", design) for i, p in enumerate(data["parameter"])]
    if not params:
        raise ctx.error("parameter", "expected at least one [[parameter]]")
    keys = [p.key for p in params]
    dup = next((k for k in keys if keys.count(k) > 1), None)
    if dup:
        raise ctx.error("parameter", f"key {dup!r} is varied twice; expected each key once")
    if design.type == "list" and len({len(p.choices) for p in params}) > 1:
        raise ctx.error(
            "parameter",
            "a 'list' design pairs the i-th values of every parameter; "
            f"expected lists of one length (got {[len(p.choices) for p in params]})",
        )
    n = _run_count(design, params)
    if n > MAX_RUNS:
        raise ctx.error("design", f"the design makes {n:.3g} runs; expected at most {MAX_RUNS:,}")
    ignore = data.get("ignore", [])
    if not all(isinstance(x, str) for x in ignore):
        raise ctx.error("ignore", "expected a list of NiftySim feature names")
    spec = SweepSpec(
        base,
        params,
        design,
        dict(data.get("set", {})),
        _outputs(ctx, data.get("output", {})),
        threads,
        tuple(ignore),
        str(path),
        _batch(ctx, data),
    )
    _check_key_paths(ctx, spec)
    return spec


def _check_key_paths(ctx: Ctx, spec: SweepSpec) -> None:
    """Every varied and set key path reaches into the base file (before any run starts: a wrong
    path would otherwise fail every run alike)."""
    from ..errors import InputError

    if spec.base.suffix.lower() == ".xml":
        import xml.etree.ElementTree as ET

        from ..io.niftysim import set_xml_key

        try:
            root = ET.parse(spec.base).getroot()
        except (ET.ParseError, OSError) as e:
            raise ctx.error("base", f"{spec.base}: not a readable XML file ({e})") from None

        def put(key, value):
            set_xml_key(root, key, value, str(spec.base))
    else:
        from ..scene.keys import set_key

        data = read_toml(spec.base)[1]  # a SceneError names the base file

        def put(key, value):
            set_key(data, key, value, str(spec.base))

    where = {
        **{k: f"set.{k}" for k in spec.fixed},
        **{p.key: f"parameter[{i}].key" for i, p in enumerate(spec.parameters)},
    }
    for key, value in {
        **spec.fixed,
        **{p.key: p.choices[0] if p.choices else p.bounds[0] for p in spec.parameters},
    }.items():
        try:
            put(key, value)
        except InputError as e:
            raise SceneError(
                f"{key!r} does not fit the base file: {e}",
                ctx.file,
                where[key],
                ctx.line_of(where[key].split(".")[0]),
            ) from None
    _check_values(ctx, spec)


def _check_values(ctx: Ctx, spec: SweepSpec) -> None:
    """The base file loads with the [set] values and every parameter at its first choice or the
    low end of its range (a value the base file refuses would fail every run, or the runs near
    that end, each with the base file's line: named here once, in the sweep file). If it does not,
    a second load with the [set] values alone tells which of the two to name."""
    from ..errors import InputError
    from ..job import load_job

    first = {p.key: p.choices[0] if p.choices else p.bounds[0] for p in spec.parameters}
    if not (spec.fixed or first):
        return
    try:
        _check_points(ctx, spec, load_job(spec.base, spec.ignore, {**spec.fixed, **first}).builder.nodes)
        return
    except InputError as e:
        key, what, error = "parameter", "the parameters at their first choice or low end", e
    if spec.fixed:
        try:
            load_job(spec.base, spec.ignore, spec.fixed)
        except InputError as e:
            key, what, error = "set", "the [set] values", e
    raise SceneError(f"the base file with {what} does not load: {error}", ctx.file, key, ctx.line_of(key))


def _check_points(ctx: Ctx, spec: SweepSpec, X: np.ndarray) -> None:
    """Warn of an output point farther than a tenth of the body's size from every node of the base
    mesh X [m] (N, 3) (scene.select.nearest_node)."""
    for name, p in spec.outputs.points.items():
        nearest_node(ctx, p, f"output.points.{name}", X)


def _run_count(design: Design, params: list[Parameter]) -> int:
    """Runs the design makes (counted, not listed)."""
    if design.type == "grid":
        return math.prod(len(p.choices) for p in params)
    if design.type == "list":
        return len(params[0].choices)
    return design.samples * (len(params) + 2) if design.type == "saltelli" else design.samples


def _batch(ctx: Ctx, data: dict) -> int:
    """Runs per batch: 1 (alone) or more, without per-run fields or force histories (a batch
    reports each run's closing figures)."""
    batch = data.get("batch", 1)
    if not 1 <= batch <= MAX_RUNS:
        raise ctx.error("batch", f"batch = {batch}: expected 1 to {MAX_RUNS:,} runs per batch")
    out = data.get("output", {})
    for key in ("fields", "tool_history"):
        if batch > 1 and out.get(key):
            raise ctx.error(
                f"output.{key}",
                f"{key} = true needs each run alone; expected batch "
                "= 1 (a batch reports each run's closing figures)",
            )
    return batch


def _design(ctx: Ctx, d: dict) -> Design:
    check_keys(ctx, d, "design", {"type": "str", "samples": "int", "seed": "int"})
    kind = d.get("type", "grid")
    if kind not in DESIGNS:
        raise ctx.error("design.type", f"type = {kind!r}: expected one of {', '.join(DESIGNS)}")
    samples = d.get("samples", 0)
    if kind in _SAMPLED and samples < 1:
        raise ctx.error("design.samples", f"a '{kind}' design needs samples >= 1")
    if kind == "saltelli" and samples & (samples - 1):
        raise ctx.error(
            "design.samples",
            f"samples = {samples}: Saltelli's scheme on a Sobol' sequence needs a power of 2",
        )
    seed = d.get("seed", 0)
    if seed < 0:
        raise ctx.error("design.seed", f"seed = {seed}: expected an integer >= 0")
    return Design(kind, samples, seed)


def _parameter(ctx: Ctx, p: dict, where: str, design: Design) -> Parameter:
    check_keys(ctx, p, where, {"key": "str", "values": "list", "range": "list", "scale": "str"}, ("key",))
    if design.type in _SAMPLED:
        if "range" not in p:
            raise ctx.error(where, f"a '{design.type}' design samples a range; expected range = [low, high]")
        low, high = vector(ctx, p["range"], f"{where}.range", 2)
        scale = p.get("scale", "linear")
        if scale not in ("linear", "log"):
            raise ctx.error(f"{where}.scale", f"scale = {scale!r}: expected 'linear' or 'log'")
        if not low < high or (scale == "log" and not low > 0):
            raise ctx.error(
                f"{where}.range",
                f"range = [{low:g}, {high:g}]: expected low < high"
                + (" and low > 0 for a log scale" if scale == "log" else ""),
            )
        return Parameter(p["key"], range=(low, high), scale=scale)
    if "values" not in p or not p["values"]:
        raise ctx.error(
            where, f"a '{design.type}' design takes explicit values; expected values = [...] (non-empty)"
        )
    for v in p["values"]:
        if isinstance(v, float) and not math.isfinite(v):
            raise ctx.error(f"{where}.values", f"{v!r}: expected finite numbers")
    return Parameter(p["key"], values=tuple(p["values"]))


def _outputs(ctx: Ctx, o: dict) -> Outputs:
    check_keys(ctx, o, "output", {"points": "table", "tool_history": "bool", "fields": "bool"})
    points: dict[str, Any] = {
        name: tuple(vector(ctx, v, f"output.points.{name}")) for name, v in o.get("points", {}).items()
    }
    return Outputs(points, o.get("tool_history", False), o.get("fields", False))
