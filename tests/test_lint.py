"""Lint, format and types: ruff (pyflakes, pycodestyle, bugbear; configuration in pyproject.toml) finds
nothing over the package and the tests, its formatter would change nothing, and mypy finds no
type error in the package."""

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).parents[1]
PATHS = ["src", "tests", "docs/conf.py"]


def _ruff(*args):
    return subprocess.run(
        [sys.executable, "-m", "ruff", *args, "--no-cache", *PATHS],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=300,
    )


def test_ruff_finds_nothing():
    r = _ruff("check")
    assert r.returncode == 0, r.stdout + r.stderr


def test_ruff_format_changes_nothing():
    r = _ruff("format", "--check")
    assert r.returncode == 0, "run `ruff format src tests docs/conf.py`:\n" + r.stdout + r.stderr


def test_mypy_finds_nothing(tmp_path):
    """The type checker over src/pliant (configuration in pyproject.toml: [tool.mypy])."""
    r = subprocess.run(
        [sys.executable, "-m", "mypy", "--cache-dir", str(tmp_path), "--no-error-summary"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=600,
    )
    errors = [ln for ln in r.stdout.splitlines() if ": error:" in ln]
    assert r.returncode == 0 and not errors, "\n".join(errors) or r.stdout + r.stderr


def test_clang_format_changes_nothing():
    """The C++ and CUDA sources follow .clang-format (clang-format from the test environment)."""
    files = subprocess.run(
        ["git", "ls-files", "cpp/*.hpp", "cpp/*.cpp", "cpp/*.cu", "cpp/*.cuh"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=60,
    ).stdout.split()
    if not files:  # not a git checkout (an unpacked sdist): every source file under cpp/
        files = [
            str(p.relative_to(ROOT))
            for p in (ROOT / "cpp").rglob("*")
            if p.suffix in (".hpp", ".cpp", ".cu", ".cuh")
        ]
    assert files
    exe = Path(sys.executable).with_name("clang-format")
    r = subprocess.run(
        [str(exe), "--dry-run", "--Werror", *files], cwd=ROOT, capture_output=True, text=True, timeout=300
    )
    assert r.returncode == 0, "run `clang-format -i` on cpp/:\n" + r.stderr[-3000:]
