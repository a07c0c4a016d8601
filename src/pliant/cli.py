"""Command line: ``pliant run | demo | sweep | validate | view | mesh | bench | info``.

Exit codes: 0 success; 1 the simulation failed (instability, no convergence) or ``mesh check``
found problems; 2 bad input (one line naming the file, key or element and what was expected);
3 an internal error (a bug: one line says where the full traceback was written); 130 interrupted.
"""

from __future__ import annotations

import json
import os
import platform
import sys
import time
from pathlib import Path
from typing import Any, Optional

import typer
from rich.console import Console
from rich.markup import escape
from rich.table import Table

from . import __version__, _core
from .errors import InputError, PliantError
from .guard import one_line

app = typer.Typer(
    add_completion=False,
    rich_markup_mode=None,  # help text as written: units such as [m] are no markup
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    help="pliant: soft-body simulation by nonlinear FEM (TLED) on tetrahedra.",
    epilog="Exit codes: 0 done; 1 the simulation failed (unstable, not converged) "
    "or mesh check found problems; 2 bad input (one line names the file, key "
    "or element); 3 internal error (a bug: the line names the log with the "
    "traceback); 130 interrupted (Ctrl-C or SIGTERM).",
)
console = Console(soft_wrap=True)
err_console = Console(stderr=True, soft_wrap=True)


def _print_version(value: bool):
    if value:
        console.print(f"pliant {__version__}")
        raise typer.Exit()


@app.callback()
def _main(
    version: bool = typer.Option(
        False, "--version", callback=_print_version, is_eager=True, help="Print the version and exit."
    ),
):
    """pliant: soft-body simulation by nonlinear FEM (TLED) on tetrahedra."""


def _speed(summary: dict) -> str:
    """ " (Nx real time)" for a run's summary line; empty for a quasi-static solve."""
    rtf = summary.get("real_time_factor")
    return f" ({rtf:.2g}x real time)" if rtf is not None else ""


def _add_mesh_commands():
    from .cli_mesh import mesh_app

    app.add_typer(mesh_app, name="mesh")


_add_mesh_commands()


def _fail(e: Exception, code: int) -> None:
    err_console.print(f"[bold red]error:[/] {escape(one_line(str(e)))}", highlight=False)
    raise typer.Exit(code)


def load_any(path: Path, ignore: list[str] | None = None, overrides: dict | None = None):
    """A scene (.toml) or a NiftySim model (.xml), with optional overrides by key path."""
    from .job import load_job

    return load_job(path, ignore, overrides)


@app.command()
def run(
    scene: Path = typer.Argument(..., help="Scene file (.toml) or NiftySim model (.xml)."),
    out: Path = typer.Option(..., "-o", "--out", help="Output folder."),
    threads: Optional[int] = typer.Option(None, help="CPU threads (default: scene or all)."),
    ignore: Optional[list[str]] = typer.Option(
        None, "--ignore", help="Unsupported NiftySim feature to skip."
    ),
    allow_unstable: bool = typer.Option(False, help="Accept a Δt above the critical step."),
    progress: bool = typer.Option(True, help="Show a progress bar."),
    backend: Optional[str] = typer.Option(None, help="cpu, cuda or cuda-emulated (default: the scene's)."),
    set_: Optional[list[str]] = typer.Option(
        None,
        "--set",
        help="KEY=VALUE set before loading, repeatable: a scene key (solver.dt=1e-4, "
        "material.liver.E=3000) or a NiftySim element path (SystemParams.TimeStep=1e-4).",
    ),
):
    """Run a scene or a NiftySim model; write result.pvd, frames, summary.json and result.png."""
    from .job import parse_overrides
    from .runner import run_scene

    try:
        sc = load_any(scene, ignore, parse_overrides(set_))  # its warnings print once the model is built
        summary = run_scene(
            sc,
            out,
            progress=progress,
            allow_unstable=allow_unstable,
            threads=threads,
            echo=console.print,
            backend=backend,
        )
    except InputError as e:
        _fail(e, 2)
    except PliantError as e:
        _fail(e, 1)
    if summary["interrupted"]:
        err_console.print(
            f"interrupted at t = {summary['simulated_time']:.4g} s; {summary['frames']} frames kept in {out}"
        )
        raise typer.Exit(130)
    console.print(
        f"{summary['steps']:,} steps, t = {summary['simulated_time']:.4g} s in "
        f"{summary['wall_time']:.2f} s{_speed(summary)}; results in [bold]{escape(str(out))}[/] "
        f"(result.pvd for ParaView, "
        f"{', '.join(f for f in summary['files'] if f != 'result.pvd')})",
        highlight=False,
    )


@app.command()
def demo(
    out: Path = typer.Option(Path("pliant-demo"), "-o", "--out", help="Output folder."),
    duration: Optional[float] = typer.Option(None, help="Simulated time [s] (default 1 s)."),
    threads: Optional[int] = typer.Option(None, help="CPU threads (default: all)."),
    progress: bool = typer.Option(True, help="Show a progress bar."),
):
    """Run the embedded default: Spot the cow on the ground, indented by a tool."""
    from .demo import run_demo

    try:
        summary = run_demo(out, duration=duration, threads=threads, progress=progress, echo=console.print)
    except InputError as e:
        _fail(e, 2)
    except PliantError as e:
        _fail(e, 1)
    console.print(
        f"{summary['steps']:,} steps, t = {summary['simulated_time']:.3g} s in "
        f"{summary['wall_time']:.1f} s{_speed(summary)}. Results in [bold]{escape(str(out))}[/]: "
        "result.pvd (open it "
        "in ParaView), result.png, summary.json"
    )


@app.command()
def sweep(
    spec: Path = typer.Argument(..., help="Sweep file (.toml): base scene, parameters, design."),
    out: Path = typer.Option(..., "-o", "--out", help="Output folder (resumed if it holds this sweep)."),
    scheduler: Optional[str] = typer.Option(
        None, help="Dask scheduler address (default: a local cluster sized to this machine)."
    ),
    workers: Optional[int] = typer.Option(None, help="Local workers (default: cores // threads per run)."),
    analyze: bool = typer.Option(
        False,
        "--analyze",
        help="Sobol indices of every output (a 'saltelli' design): sensitivity.csv and .png.",
    ),
    retry_failed: bool = typer.Option(False, help="Run the failed runs again on resume."),
    progress: bool = typer.Option(True, help="Show a progress bar."),
):
    """Run a parameter sweep on Dask: OUT/results.parquet (a row per run), resumable."""
    from .sweep import load_sweep, run_sweep

    limit = int(_core.thread_limit())
    if workers is not None and not 1 <= workers <= limit:
        _fail(InputError(f"--workers {workers}: expected 1 to {limit} on this machine"), 2)
    t0 = time.perf_counter()
    try:
        sp = load_sweep(spec)
        if workers is not None and workers * sp.threads > limit:
            raise InputError(
                f"--workers {workers} × threads {sp.threads} = {workers * sp.threads} "
                f"threads; expected at most {limit} on this machine"
            )
        if analyze and sp.design.type != "saltelli":
            raise InputError(
                f"{spec}: --analyze computes Sobol indices from a 'saltelli' design; "
                f"this sweep's design is '{sp.design.type}'"
            )
        result = run_sweep(
            sp,
            out,
            scheduler=scheduler,
            workers=workers,
            analyze=analyze,
            retry_failed=retry_failed,
            progress=progress,
        )
    except InputError as e:
        _fail(e, 2)
    for note in result.notes:
        err_console.print(f"[yellow]note:[/] {escape(note)}", highlight=False)
    bad = result.failed
    for _, row in bad.head(5).iterrows():
        err_console.print(f"run {row['run']} failed: {escape(str(row['error']))}", highlight=False)
    console.print(
        f"{len(result.table)} runs: {len(result.table) - len(bad)} done, {len(bad)} failed, "
        f"in {time.perf_counter() - t0:.1f} s; results in [bold]{escape(str(out))}[/] "
        f"({', '.join(result.files)})",
        highlight=False,
    )
    if len(bad):
        raise typer.Exit(1)


@app.command()
def validate(
    out: Path = typer.Option(Path("pliant-validation"), "-o", "--out", help="Output folder."),
    quick: bool = typer.Option(False, "--quick", help="The CI subset (under two minutes)."),
    niftysim: Optional[str] = typer.Option(
        None,
        "--niftysim",
        help="A NiftySim executable: run the cross-check models with it (else its stored results).",
    ),
):
    """Verify pliant against closed forms, NiftySim's results and peers: OUT/report.md,
    results.json and plots; exit 1 if a check fails."""
    from .validate import run_validation

    try:
        rows = run_validation(out, quick=quick, echo=console.print, niftysim=niftysim)
    except InputError as e:
        _fail(e, 2)
    failed = [r for r in rows if not r.passed]
    for r in failed:
        err_console.print(
            f"failed: {escape(r.case)}, {escape(r.quantity)}: {r.value:.6g} against {r.reference:.6g}",
            highlight=False,
        )
    console.print(
        f"{len(rows) - len(failed)} of {len(rows)} checks passed; report in "
        f"[bold]{escape(str(out))}[/]/report.md",
        highlight=False,
    )
    if failed:
        raise typer.Exit(1)


@app.command()
def view(
    target: Path = typer.Argument(
        ..., help="Scene (.toml), NiftySim model (.xml) or a results folder to play back."
    ),
    host: str = typer.Option("127.0.0.1", help="Address to listen on (0.0.0.0 exposes it)."),
    port: int = typer.Option(8080, help="Port."),
    threads: Optional[int] = typer.Option(None, help="CPU threads."),
):
    """Interactive 3-D view in the browser: live simulation with draggable tools, or playback."""
    from .view.viewer import LiveViewer, PlaybackViewer

    if not 1 <= port <= 65535:
        _fail(InputError(f"--port {port}: expected 1 to 65535"), 2)
    try:
        v: PlaybackViewer | LiveViewer
        if target.is_dir():
            v = PlaybackViewer(target, host, port)
        else:
            v = LiveViewer(load_any(target), host, port, threads)
    except InputError as e:
        _fail(e, 2)
    except OSError as e:
        _fail(InputError(f"cannot listen on {host}:{port}: {e}"), 2)
    bound = v.server.get_port()
    if bound != port:
        err_console.print(f"[yellow]warning:[/] port {port} is in use: the viewer took {bound}")
    console.print(f"pliant viewer on http://{host}:{bound} (Ctrl-C to stop)")
    try:
        v.serve()
    except KeyboardInterrupt:
        pass


@app.command()
def bench(
    json_out: Optional[Path] = typer.Option(None, "--json", help="Write figures as JSON."),
    sizes: str = typer.Option("7456,12584,27918,100000,1000000", help="Tet counts."),
    steps: int = typer.Option(8000, help="Steps for the study's sizes."),
    large_steps: int = typer.Option(200, help="Steps for the other sizes."),
    threads: Optional[int] = typer.Option(None, help="CPU threads (default: all)."),
    dtype: str = typer.Option("float32", help="float32 or float64."),
    contact: bool = typer.Option(False, help="Also time the contact cases (demo, liver)."),
    materials: bool = typer.Option(False, help="Only the per-material table (27,648-tet box)."),
    batch: Optional[int] = typer.Option(
        None, help="Only the batch figure: this many 2,000-tet bodies one by one, then as one batch."
    ),
    backend: str = typer.Option(
        "cpu", help="cpu, cuda (a GPU; e.g. --sizes up to 10000000) or cuda-emulated."
    ),
):
    """Reproduce the study's timing table (8,000 steps of 0.025 ms, Neo-Hookean) and larger meshes."""
    from .bench import bench_contact, run_benchmark
    from .mesh.primitives import MAX_BOX_TETS
    from .tled.solver import MAX_STEPS

    try:
        n = [int(s) for s in sizes.split(",")]  # an empty entry ("3,,4", "3,") is a typo: refused
    except ValueError:
        _fail(InputError(f"--sizes {sizes!r}: expected comma-separated integers"), 2)
    if steps < 1 or large_steps < 1 or not n or any(v < 1 for v in n):
        _fail(InputError("--steps, --large-steps and --sizes must be positive"), 2)
    if max(steps, large_steps) > MAX_STEPS or max(n) > MAX_BOX_TETS:
        _fail(
            InputError(
                f"--steps and --large-steps at most {MAX_STEPS:.0e}, --sizes at most {MAX_BOX_TETS:.0e} tets"
            ),
            2,
        )
    if dtype not in ("float32", "float64"):
        _fail(InputError(f"--dtype {dtype!r}: expected float32 or float64"), 2)
    if json_out is not None:
        from .io.files import check_output_file

        try:
            check_output_file(json_out, "benchmark JSON")
        except InputError as e:
            _fail(e, 2)
    from .tled.model import BACKENDS

    if backend not in BACKENDS:
        _fail(InputError(f"--backend {backend!r}: expected one of {', '.join(BACKENDS)}"), 2)
    if os.getloadavg()[0] > 0.5:
        err_console.print(
            f"[yellow]warning:[/] load average {os.getloadavg()[0]:.1f}: other work is "
            "running, timings will suffer"
        )
    if materials:
        _bench_materials(steps if steps != 8000 else 2000, threads, dtype, json_out, backend)
        return
    if batch is not None:
        _bench_batch(batch, steps if steps != 8000 else 2000, threads, dtype, json_out, backend)
        return
    table = Table(title=f"pliant {backend.upper()} backend, {dtype}, Δt = 0.025 ms")
    for c in (
        "tets",
        "nodes",
        "steps",
        "threads",
        "s (8000 steps)",
        "kernel 1 %",
        "Melem-steps/s",
        "bytes/tet",
        "× study GPU",
        "× study CPU",
    ):
        table.add_column(c, justify="right")

    def echo(r):
        f = lambda v: "-" if v is None else f"{v:,.1f}"  # noqa: E731
        table.add_row(
            f"{r.tets:,}",
            f"{r.nodes:,}",
            f"{r.steps:,}",
            "GPU" if r.threads is None else str(r.threads),
            f"{r.seconds_per_8000:.3f}",
            _percent(None if r.element_seconds is None else r.element_seconds / r.seconds),
            f"{r.element_steps_per_second / 1e6:,.1f}",
            f"{r.bytes_per_tet:.0f}",
            f(r.speedup_vs_study_gpu),
            f(r.speedup_vs_study_cpu),
        )
        console.print(f"  {r.tets:,} tets: {r.seconds:.3f} s for {r.steps} steps")

    try:
        run_benchmark(
            n, steps, large_steps, threads, dtype, str(json_out) if json_out else None, echo, backend=backend
        )
    except InputError as e:
        _fail(e, 2)
    Console(width=max(console.width, 140)).print(table)
    if contact:
        rows = bench_contact(
            echo=lambda r: (
                console.print(f"  {r['case']}: {r['skipped']}")
                if "skipped" in r
                else console.print(
                    f"  {r['case']}: {r['tets']:,} tets, {r['contact_nodes']:,} contact nodes, "
                    f"{r['steps']} steps in {r['seconds']:.2f} s; "
                    f"contact {_percent(r['contact_share'], 1)} %, "
                    f"kernel 1 {_percent(r['element_share'])} %, kernel 2 {_percent(r['node_share'])} %"
                )
            ),
            backend=backend,
        )
        if json_out:
            from .io.files import atomic_write_text

            data = json.loads(Path(json_out).read_text())
            data["contact"] = rows
            atomic_write_text(json_out, json.dumps(data, indent=2), "benchmark JSON")


def _percent(share, digits=0):
    """A share of the step as a percentage; "-" where it was not measured (GPU, emulated device)."""
    return "-" if share is None else f"{100 * share:.{digits}f}"


def _bench_batch(copies, steps, threads, dtype, json_out, backend):
    from .bench import bench_batch

    if copies < 1:
        _fail(InputError(f"--batch {copies}: expected at least 1 body"), 2)
    r = bench_batch(copies, steps=steps, threads=threads, dtype=dtype, backend=backend)
    where = "GPU" if r["threads"] is None else f"{r['threads']} threads"
    console.print(
        f"{r['copies']} bodies of {r['tets']:,} tets, {r['steps']:,} steps, {backend}, "
        f"{where}: one by one {r['one_by_one_s']:.3f} s, as one batch "
        f"{r['batch_s']:.3f} s ({r['gain']:.2f}x; "
        f"{r['batch_element_steps_per_second'] / 1e6:,.1f} M element-steps/s)"
    )
    if json_out:
        from .io.files import atomic_write_text

        atomic_write_text(json_out, json.dumps(r, indent=2), "benchmark JSON")


def _bench_materials(steps, threads, dtype, json_out, backend):
    from .bench import bench_materials

    table = Table(
        title=f"pliant per material, {backend}, {dtype}, 27,648-tet box, Δt = 0.025 ms",
        caption="each case in 5 chunks, each after one of the Neo-Hookean: the median ratio and its range",
    )
    for c in ("material", "ms / step", "× NeoHookean", "range", "kernel 1 %"):
        table.add_column(c, justify="right")
    rows = bench_materials(
        steps,
        threads,
        dtype,
        echo=lambda r: console.print(f"  {r['material']}: {r['ms_per_step']:.3f} ms per step"),
        backend=backend,
    )
    for r in rows:
        table.add_row(
            r["material"],
            f"{r['ms_per_step']:.3f}",
            f"{r['relative']:.2f}",
            f"{r['relative_min']:.2f}–{r['relative_max']:.2f}",
            _percent(r["element_share"]),
        )
    console.print(table)
    if json_out:
        from .io.files import atomic_write_text

        atomic_write_text(
            json_out, json.dumps({"backend": backend, "materials": rows}, indent=2), "benchmark JSON"
        )


@app.command()
def info(as_json: bool = typer.Option(False, "--json", help="Machine-readable output.")):
    """Version, compiled backends, threads, devices."""
    names, why = _core.cuda_devices()
    cuda = {"compiled": bool(_core.cuda_compiled()), "usable": bool(names), "devices": list(names)}
    if not names:
        cuda["reason"] = why
    data: dict[str, Any] = {
        "version": __version__,
        "python": sys.version.split()[0],
        "platform": platform.platform(),
        "backends": {
            "cpu": {
                "compiled": True,
                "usable": True,
                "threads": _core.max_threads(),
                "simd_lanes": int(_core.lanes),
                "isa": _core.isa,
                "isas_built": list(_core.isas),
            },
            "cuda": cuda,
            "cuda-emulated": {
                "compiled": True,
                "usable": True,
                "note": "the CUDA engine on the host, for tests (slow)",
            },
        },
        "cpu_count": os.cpu_count(),
    }
    if as_json:
        typer.echo(json.dumps(data, indent=2))
        return
    console.print(f"pliant {data['version']} (Python {data['python']}, {data['platform']})")
    cpu = data["backends"]["cpu"]
    console.print(
        f"  cpu : compiled, usable, {cpu['threads']} threads, {cpu['simd_lanes']} lanes per block, "
        f"instruction set {cpu['isa']} (built: {', '.join(cpu['isas_built'])}; PLIANT_ISA "
        "forces one)"
    )
    c = data["backends"]["cuda"]
    if not c["compiled"]:
        console.print(f"  cuda: not compiled ({c['reason']})")
    elif c["usable"]:
        console.print(f"  cuda: compiled, {len(c['devices'])} device(s): {', '.join(c['devices'])}")
    else:
        console.print(f"  cuda: compiled, no device present ({c['reason']})")
    console.print(f"  cuda-emulated: usable ({data['backends']['cuda-emulated']['note']})")


def main(argv: list[str] | None = None) -> None:
    """The ``pliant`` program: runs the app and turns every outcome into one line and an exit code
    (module docstring); never a traceback on the terminal."""
    from .guard import run_guarded

    sys.exit(run_guarded(app, argv, err_console))
