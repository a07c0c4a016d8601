"""The installed package on a fresh machine (issue 11): every third-party module any code path imports
is a declared dependency, and the installed ``pliant`` program answers ``--help`` for every command
and runs the demo. CI installs into a new virtual environment (.ci/run), so nothing installed by
hand can stand in for a missing dependency."""

import ast
import importlib.metadata as md
import re
import subprocess
import sys
from pathlib import Path

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

import pytest
import typer

from pliant.cli import app

ROOT = Path(__file__).parents[1]
PLIANT = Path(sys.executable).with_name("pliant")

# Modules pliant's dependencies import lazily on code paths pliant uses, which an import scan of
# pliant cannot see (each was once missing on a fresh machine or would be):
INDIRECT = {
    "networkx": "trimesh: hole filling, body splitting and winding repair (issue 11's traceback)",
}
# Modules imported only where installed (behind importlib.util.find_spec): module → the distribution
# declared in an extra that provides it, and why.
OPTIONAL = {
    "mujoco": ("mujoco", "pliant validate's peer (pliant/validate/peers.py); the test extras install it"),
    "newton": ("newton", "pliant validate's peer (pliant/validate/peers.py); the test extras install it"),
    "warp": ("newton", "Newton's own dependency (warp-lang), used by its peer to damp and synchronize"),
}


def _imported_modules() -> set[str]:
    """Top-level modules imported anywhere in src/pliant (also inside functions)."""
    mods = set()
    for f in (ROOT / "src" / "pliant").rglob("*.py"):
        for node in ast.walk(ast.parse(f.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Import):
                mods |= {a.name.split(".")[0] for a in node.names}
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                mods.add(node.module.split(".")[0])
    return mods - set(sys.stdlib_module_names) - {"pliant", "__future__"}


def _declared() -> set[str]:
    """Distributions pliant requires (not extras), normalized names."""
    reqs = md.requires("pliant") or []
    names = set()
    for r in reqs:
        if "extra ==" in r:
            continue
        names.add(re.split(r"[ ;<>=!~\[]", r, maxsplit=1)[0].lower().replace("_", "-"))
    return names


def test_every_imported_module_is_a_declared_dependency():
    dists = md.packages_distributions()
    declared = _declared()
    missing = {}
    # tomli is declared for Python < 3.11 only, where tomllib does not exist.
    for mod in sorted(
        (_imported_modules() | set(INDIRECT))
        - set(OPTIONAL)
        - ({"tomli"} if sys.version_info >= (3, 11) else set())
    ):
        owners = {d.lower().replace("_", "-") for d in dists.get(mod, [])}
        assert owners, f"module {mod!r} is imported but no installed distribution provides it"
        if not owners & declared:
            missing[mod] = sorted(owners)
    assert not missing, f"imported but not declared in pyproject.toml: {missing}"
    # Optional modules (installed or not here): each is the distribution of that name in an extra.
    extras = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["optional-dependencies"]
    in_extras = {re.split(r"[ ;<>=!~\[]", r, maxsplit=1)[0].lower() for e in extras.values() for r in e}
    assert set(OPTIONAL) <= _imported_modules(), OPTIONAL
    assert {dist for dist, _ in OPTIONAL.values()} <= in_extras, (OPTIONAL, in_extras)


def _commands(group: typer.Typer) -> list[list[str]]:
    cmd = typer.main.get_command(group)
    out = [[]]

    def walk(c, prefix):
        for name, sub in getattr(c, "commands", {}).items():
            out.append(prefix + [name])
            walk(sub, prefix + [name])

    walk(cmd, [])
    return out


@pytest.mark.parametrize("words", _commands(app), ids=lambda w: " ".join(w) or "pliant")
def test_every_command_answers_help(words):
    assert PLIANT.exists(), f"the pliant program is not installed in this environment ({PLIANT})"
    r = subprocess.run([str(PLIANT), *words, "--help"], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0 and r.stderr == "", r.stderr
    assert "Usage" in r.stdout and "--help" in r.stdout


def test_the_commands_are_all_there():
    names = {" ".join(w) for w in _commands(app)}
    assert names >= {
        "run",
        "demo",
        "view",
        "bench",
        "info",
        "mesh",
        "mesh simplify",
        "mesh subdivide",
        "mesh check",
        "mesh repair",
        "mesh tetrahedralize",
        "mesh quality",
    }


def test_the_installed_program_runs_the_demo(tmp_path):
    """The README's first command, shortened (the full demo is test_cli's)."""
    r = subprocess.run(
        [str(PLIANT), "demo", "-o", str(tmp_path / "d"), "--duration", "0.02", "--no-progress"],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert r.returncode == 0 and "Traceback" not in r.stderr, r.stderr
    assert (tmp_path / "d" / "result.pvd").exists() and (tmp_path / "d" / "result.png").exists()


def test_kinds_are_the_engines_enums():
    """Materials, load curves and tools carry the engine's own enums (bound from C++), so that
    Python restates no kind number (issue 12)."""
    import pliant as pl
    from pliant import _core

    mats = [
        pl.NeoHookean(E=1e3, nu=0.3),
        pl.MooneyRivlin(100, 50, 1e4),
        pl.NeoHookeanCoupled(E=1e3, nu=0.3),
        pl.StVenantKirchhoff(E=1e3, nu=0.3),
        pl.LinearElastic(E=1e3, nu=0.3),
        pl.Polynomial(100, 50, 1, 1, 1, K=1e4),
        pl.ArrudaBoyce(100, 3, 1e4),
        pl.TransverselyIsotropic(100, 1e4, 50, (1, 0, 0)),
    ]
    assert sorted(type(m.kind).__name__ for m in mats) == ["MaterialKind"] * 8
    assert {m.kind.name for m in mats} == set(_core.MaterialKind.__members__)
    curves = [
        pl.Constant(),
        pl.Step(0.1),
        pl.Ramp(1),
        pl.SmoothRamp(1),
        pl.Hilly(1),
        pl.Table([0, 1], [0, 1]),
    ]
    assert {c.kind.name for c in curves} == set(_core.CurveKind.__members__)
    c = pl.contact
    tools = [
        c.Plane((0, 0, 0), (0, 0, 1)),
        c.Sphere(0.1),
        c.Capsule(0.1, 0.2),
        c.Box((1, 1, 1)),
        c.Cylinder(0.1, 0.2),
    ]
    assert {type(t.kind).__name__ for t in tools} == {"ToolKind"}
    assert {t.kind.name for t in tools} | {"Grid"} == set(_core.ToolKind.__members__)


def test_main_help_lists_the_exit_codes():
    r = subprocess.run([str(PLIANT), "--help"], capture_output=True, text=True, timeout=60)
    text = " ".join(r.stdout.split())
    assert r.returncode == 0 and "Exit codes: 0 done; 1 the simulation failed" in text
    assert "2 bad input" in text and "3 internal error" in text and "130 interrupted" in text
