"""Print the path of the wheel pip built for this environment's pliant (the same extension-module
hashes in the wheel's RECORD and in the installed one), or nothing. pip keeps a wheel it built
from a local folder only in a temporary "ephemeral" cache, kept when pip runs with --no-clean
(.ci/run sets PIP_NO_CLEAN and a private TMPDIR for the README's test command); pip's persistent
cache is searched too. Used by .ci/wheel so that CI repairs and tests the very wheel the test
command built and installed, instead of compiling the engine a second time."""

import importlib.metadata as md
import os
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path


def module_hashes(record: str) -> dict[str, str]:
    """Extension modules and their hashes from a RECORD file's text."""
    rows = (line.split(",") for line in record.splitlines())
    return {r[0]: r[1] for r in rows if len(r) >= 2 and r[0].endswith(".so")}


def candidates() -> list[str]:
    """pliant wheels in pip's ephemeral caches under the temporary folder and in its cache."""
    found = [str(p) for p in Path(tempfile.gettempdir()).glob("pip-ephem-wheel-cache-*/wheels/**/pliant-*.whl")]
    listed = subprocess.run(
        [sys.executable, "-m", "pip", "cache", "list", "--format=abspath", "pliant-*"],
        capture_output=True,
        text=True,
    ).stdout.split()
    return sorted(found + listed, key=os.path.getmtime, reverse=True)


def main() -> None:
    try:
        installed = module_hashes(md.distribution("pliant").read_text("RECORD") or "")
    except md.PackageNotFoundError:
        return
    for path in candidates():
        with zipfile.ZipFile(path) as z:
            record = next(n for n in z.namelist() if n.endswith(".dist-info/RECORD"))
            if installed and module_hashes(z.read(record).decode()) == installed:
                print(path)
                return


if __name__ == "__main__":
    main()
