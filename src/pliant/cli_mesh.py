"""`pliant mesh ...`: the mesh pipeline on the command line. Bad input exits with code 2."""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Optional

import numpy as np
import typer
from rich.console import Console
from rich.markup import escape

from .errors import InputError, PliantError
from .guard import one_line

mesh_app = typer.Typer(
    no_args_is_help=True,
    rich_markup_mode=None,  # help text as written: units such as [m] are no markup
    add_completion=False,
    help="Mesh pipeline: simplify, subdivide, repair, check, tetrahedralize, quality.",
)
console = Console(soft_wrap=True, markup=False, highlight=False)
err = Console(stderr=True, soft_wrap=True)


def _guard(fn):
    import functools

    @functools.wraps(fn)
    def wrapper(*a, **k):
        try:
            return fn(*a, **k)
        except InputError as e:
            err.print(f"[bold red]error:[/] {escape(one_line(str(e)))}", highlight=False)
            raise typer.Exit(2) from None
        except PliantError as e:
            err.print(f"[bold red]error:[/] {escape(one_line(str(e)))}", highlight=False)
            raise typer.Exit(1) from None

    return wrapper


@mesh_app.command("simplify")
@_guard
def simplify_cmd(
    inp: Path,
    out: Path,
    target_faces: Optional[int] = typer.Option(None, "--target-faces", help="Faces to keep."),
    ratio: Optional[float] = typer.Option(None, "--ratio", help="Fraction of faces to keep."),
):
    """QEM simplification (Garland–Heckbert, via fast-simplification)."""
    from .mesh.surface import check_surface_output
    from .mesh import read_surface, simplify, write_surface

    check_surface_output(out)
    V, F = read_surface(inp)
    t = time.perf_counter()
    Vs, Fs = simplify(V, F, target_faces=target_faces, ratio=ratio)
    write_surface(out, Vs, Fs)
    console.print(
        f"{len(V):,} vertices / {len(F):,} faces → {len(Vs):,} / {len(Fs):,} in "
        f"{time.perf_counter() - t:.2f} s: {out}"
    )


@mesh_app.command("subdivide")
@_guard
def subdivide_cmd(inp: Path, out: Path, levels: int = typer.Option(1, "--levels", help="Levels.")):
    """Loop subdivision (with Loop's boundary rules)."""
    from .mesh.surface import check_surface_output
    from .mesh import read_surface, subdivide_loop, write_surface

    check_surface_output(out)
    if not 0 <= levels <= 6:
        raise InputError(f"--levels {levels}: expected 0 to 6 (each level multiplies the faces by 4)")
    V, F = read_surface(inp)
    Vs, Fs = subdivide_loop(V, F, levels)
    write_surface(out, Vs, Fs)
    console.print(f"{len(V):,} vertices → {len(Vs):,} vertices, {len(Fs):,} faces: {out}")


@mesh_app.command("check")
@_guard
def check_cmd(inp: Path, as_json: bool = typer.Option(False, "--json")):
    """Watertightness, holes, non-manifold edges, self-intersections, degenerate faces, winding,
    bodies. Exit code 0 if clean, 1 if problems were found."""
    from .mesh import check_surface, read_surface

    V, F = read_surface(inp)
    rep = check_surface(V, F)
    if as_json:
        typer.echo(json.dumps(rep.as_dict(), indent=2))
    else:
        bodies = f"{rep.bodies} {'body' if rep.bodies == 1 else 'bodies'}"
        if rep.cavities:
            bodies += f" with {rep.cavities} {'cavity' if rep.cavities == 1 else 'cavities'}"
        console.print(f"{inp}: {rep.vertices:,} vertices, {rep.faces:,} faces, {bodies}")
        console.print("  ok" if rep.ok else "  problems: " + "; ".join(rep.problems))
        for note in rep.notes:
            console.print(f"  note: {note}")
    raise typer.Exit(0 if rep.ok else 1)


# --fill-shell of repair and tetrahedralize: what it is for (each command then says what it makes).
FILL_SHELL_HELP = "The surface is a thin-walled shell (an organ's capsule: two sheets a wall apart): "


@mesh_app.command("repair")
@_guard
def repair_cmd(
    inp: Path,
    out: Path,
    keep_largest: bool = typer.Option(False, help="Keep only the largest body."),
    bodies: str = typer.Option(
        "all", help="Several closed bodies: all (keep each, closed and outward), largest, or one (refuse)."
    ),
    fill_shell: bool = typer.Option(
        False,
        help=FILL_SHELL_HELP + "write its outer sheet, openings closed: the surface of the solid inside.",
    ),
):
    """Fill holes, fix winding, drop fragments, split bodies touching at an edge; refuse with the
    reason where it cannot."""
    from .mesh.surface import check_surface_output
    from .mesh import check_surface, read_surface, repair_surface, write_surface

    check_surface_output(out)
    V, F = read_surface(inp)
    Vr, Fr, actions = repair_surface(V, F, keep_largest=keep_largest, bodies=bodies)
    if fill_shell:
        from .mesh.shell import outer_sheet

        Vr, Fr, kept = outer_sheet(Vr, Fr)
        Vr, Fr, more = repair_surface(Vr, Fr, keep_largest=keep_largest, bodies=bodies)
        actions += kept + more
    write_surface(out, Vr, Fr)
    rep = check_surface(Vr, Fr)
    console.print(f"{out}: " + ("; ".join(actions) or "nothing to repair"))
    if rep.self_intersections:
        console.print(
            f"  note: {rep.self_intersections} self-intersecting face pairs remain; "
            "tetrahedralize handles them (fTetWild's envelope)"
        )


@mesh_app.command("tetrahedralize")
@_guard
def tetrahedralize_cmd(
    inp: Path,
    out: Path,
    edge_length: Optional[float] = typer.Option(None, help="Target tet edge [m]."),
    max_volume: Optional[float] = typer.Option(None, help="Target tet volume [m³]."),
    target_tets: int = typer.Option(20000, help="Tets wanted when no size is given."),
    quality: Optional[float] = typer.Option(None, help="Refuse if the worst radius–edge ratio exceeds this."),
    repair: bool = typer.Option(True, help="Repair the surface first."),
    bodies: str = typer.Option(
        "union",
        help="Several closed bodies: union (one mesh of their union, "
        "overlaps merged), separate (a mesh per body), largest, "
        "or one (refuse).",
    ),
    fill_shell: bool = typer.Option(
        False,
        help=FILL_SHELL_HELP
        + "mesh the solid its outer sheet encloses, openings closed, instead of the wall.",
    ),
):
    """Surface → positively oriented tet mesh (.vtu) with surface nodes and faces marked."""
    import meshio

    from .io import atomic_write, check_output_file
    from .mesh import read_surface, surface_to_tets, tet_quality
    from .mesh.quality import REGULAR_RADIUS_EDGE
    from .mesh.surface import metres_hint
    from .mesh.topology import boundary_faces

    check_output_file(out, "volume mesh", mesh_format=True)
    for name, v in (("--edge-length", edge_length), ("--max-volume", max_volume)):
        if v is not None and not (np.isfinite(v) and v > 0):
            raise InputError(f"{name} {v}: expected a finite value > 0 (SI units)")
    if target_tets < 1:
        raise InputError(f"--target-tets {target_tets}: expected >= 1")
    if quality is not None and not (np.isfinite(quality) and quality >= REGULAR_RADIUS_EDGE):
        raise InputError(
            f"--quality {quality}: expected a finite radius–edge ratio >= {REGULAR_RADIUS_EDGE:.3f} "
            "(the regular tet's, the best there is)"
        )
    V, F = read_surface(inp)
    hint = metres_hint(V, str(inp))
    if hint:
        err.print(f"warning: {hint} (--edge-length and the output are in the file's units)")
    if max_volume is not None:
        edge_length = (6 * np.sqrt(2) * max_volume) ** (1 / 3)  # regular tet of that volume
        # An upper bound: one larger than the surface asks for its coarsest mesh.
        edge_length = min(edge_length, float(np.linalg.norm(np.ptp(V, axis=0))))
    X, T, info = surface_to_tets(
        V,
        F,
        edge_length=edge_length,
        target_tets=target_tets,
        repair=repair,
        bodies=bodies,
        fill_shell=fill_shell,
        log=console.print,
    )
    for note in info["warnings"]:
        err.print(f"warning: {note}")
    q = tet_quality(X, T)
    if quality is not None and q["radius_edge"].max() > quality:
        raise PliantError(f"worst radius–edge ratio {q['radius_edge'].max():.2f} exceeds --quality {quality}")
    faces, _ = boundary_faces(T)
    surf = np.zeros(len(X), np.int8)
    surf[np.unique(faces)] = 1
    mesh = meshio.Mesh(
        X,
        [("tetra", T), ("triangle", faces)],
        point_data={"surface_node": surf},
        cell_data={"surface_face": [np.zeros(len(T), np.int8), np.ones(len(faces), np.int8)]},
    )
    atomic_write(out, lambda tmp: meshio.write(tmp, mesh), "volume mesh")
    console.print(f"{out}: {len(X):,} nodes, {len(T):,} tets, {len(faces):,} surface faces")


@mesh_app.command("quality")
@_guard
def quality_cmd(
    inp: Path,
    png: Optional[Path] = typer.Option(None, help="Histogram picture."),
    E: float = typer.Option(3000.0, "--E", help="Young's modulus for Δt [Pa]."),
    nu: float = typer.Option(0.45, "--nu", help="Poisson's ratio for Δt."),
    density: float = typer.Option(1000.0, help="Density for Δt [kg/m³]."),
    as_json: bool = typer.Option(False, "--json"),
):
    """Per-tet radius–edge ratio, dihedral angles, volume and critical time step: summary + PNG."""
    from .io import check_output_file
    from .io.mesh import read_volume_mesh_file
    from .materials import LinearElastic
    from .mesh import quality_summary, tet_quality
    from .mesh.quality import dilatational_wave_speed, quality_histogram
    from .mesh.topology import conformity_problem

    if png:
        check_output_file(png, "picture")
    for name, v in (("--E", E), ("--density", density)):
        if not (np.isfinite(v) and v > 0):
            raise InputError(f"{name} {v}: expected a finite value > 0 (SI units)")
    X, T, _, _, split = read_volume_mesh_file(inp)
    q = tet_quality(X, T)
    dt = q["min_altitude"] / dilatational_wave_speed(LinearElastic(E=E, nu=nu), density)
    s = quality_summary(q, dt)
    s["not_conforming"] = conformity_problem(X, T)  # None, or why the mesh cannot be simulated
    s["split_cells"] = split  # {"hexahedron": n, ...}: the file's cells split into the tets
    if png:
        quality_histogram(png, q, dt)
    if as_json:
        typer.echo(json.dumps(s, indent=2))
        return
    if split:
        cells = ", ".join(f"{n:,} {kind}" for kind, n in split.items())
        console.print(f"{inp}: cells split into tets (pliant.mesh.split): {cells}", markup=False)
    console.print(
        f"{inp}: {s['tets']:,} tets, {s['inverted']} inverted, {s['degenerate']} "
        f"degenerate (zero volume), {s['slivers_min_dihedral_below_5deg']} slivers (min "
        "dihedral < 5°)"
    )
    if s["not_conforming"]:
        console.print(f"  not one mesh: {s['not_conforming']}", markup=False)
    for k in ("radius_edge", "min_dihedral", "max_dihedral", "volume"):
        v = s[k]
        console.print(f"  {k:13s} min {v['min']:.4g}  median {v['median']:.4g}  max {v['max']:.4g}")
    d = s["dt_critical"]
    if d is None:
        console.print("  critical Δt: none: no element has a positive volume")
        return
    console.print(
        f"  critical Δt: {d['min']:.3g} s (element {d['element']}), median {d['median']:.3g}"
        f" s: the worst element costs {d['cost_factor']:.1f}× the steps"
    )
    if s["inverted"] or s["degenerate"]:
        console.print(
            f"  (over the {s['tets'] - s['inverted'] - s['degenerate']:,} valid elements: "
            "inverted and degenerate elements have no stable step and must be fixed)"
        )
