"""The documentation site builds with warnings as errors (Sphinx: the guides through MyST, the API
reference from the docstrings), and its examples page lists every example."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).parents[1]


def test_site_builds_without_warnings(tmp_path):
    r = subprocess.run(
        [
            sys.executable,
            "-m",
            "sphinx",
            "-W",
            "--keep-going",
            "-q",
            "-b",
            "html",
            str(ROOT / "docs"),
            str(tmp_path),
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert r.returncode == 0, r.stderr[-3000:]
    api = (tmp_path / "api.html").read_text(encoding="utf-8")
    for name in ("ModelBuilder", "Simulation", "NeoHookean", "run_sweep", "Batch", "run_validation"):
        assert name in api, name


def test_examples_page_lists_every_example():
    page = (ROOT / "docs" / "examples.md").read_text(encoding="utf-8")
    for path in (ROOT / "examples").glob("*.toml"):
        assert f"../examples/{path.name}" in page, path.name
