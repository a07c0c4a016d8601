"""Print the path of the wheel in pip's cache that pip built from the checkout named by argv[1] and
installed into this environment (the same extension-module hashes in the wheel's RECORD and in the
installed one), or nothing. Used by .ci/wheel so that CI repairs and tests the wheel the README's
test command built instead of compiling the engine a second time."""

import importlib.metadata as md
import json
import os
import subprocess
import sys
import zipfile
from pathlib import Path


def module_hashes(record: str) -> dict[str, str]:
    """Extension modules and their hashes from a RECORD file's text."""
    rows = (line.split(",") for line in record.splitlines())
    return {r[0]: r[1] for r in rows if len(r) >= 2 and r[0].endswith(".so")}


def main() -> None:
    origin = Path(sys.argv[1]).resolve().as_uri()
    try:
        installed = module_hashes(md.distribution("pliant").read_text("RECORD") or "")
    except md.PackageNotFoundError:
        return
    listed = subprocess.run(
        [sys.executable, "-m", "pip", "cache", "list", "--format=abspath", "pliant-*"],
        capture_output=True,
        text=True,
    ).stdout.split()
    for path in sorted(listed, key=os.path.getmtime, reverse=True):
        info = Path(path).with_name("origin.json")
        if not info.exists() or json.loads(info.read_text()).get("url") != origin:
            continue
        with zipfile.ZipFile(path) as z:
            record = next(n for n in z.namelist() if n.endswith(".dist-info/RECORD"))
            if installed and module_hashes(z.read(record).decode()) == installed:
                print(path)
                return


if __name__ == "__main__":
    main()
