import os
import subprocess
import sys
from pathlib import Path

import pytest

# Under pytest-xdist (the README's `-n auto`) each worker runs the engine on one thread: the workers
# share the cores, and OpenMP threads that outnumber the cores spin against each other. Tests that
# compare thread counts ask for theirs explicitly.
if os.environ.get("PYTEST_XDIST_WORKER"):
    os.environ.setdefault("OMP_NUM_THREADS", "1")


@pytest.fixture
def pliant_cli():
    """The installed command line: ``pliant_cli(*args)`` runs ``pliant args...`` to its end and
    returns the CompletedProcess (text output; a guard of 10 minutes against a hang)."""
    exe = str(Path(sys.executable).with_name("pliant"))

    def run(*args) -> subprocess.CompletedProcess:
        return subprocess.run([exe, *map(str, args)], capture_output=True, text=True, timeout=600)

    return run


@pytest.fixture(params=["float32", "float64"])
def dtype(request):
    return request.param


# --- backends: every test taking `backend` runs on each, and the summary counts them ----------------
BACKENDS = ("cpu", "cuda-emulated", "cuda")


@pytest.fixture(params=BACKENDS)
def backend(request):
    """A backend name; "cuda" is skipped, with the reason, where there is no device. The name goes
    into the test's report (user_properties: they reach the summary from xdist workers too)."""
    request.node.user_properties.append(("backend", request.param))
    if request.param == "cuda":
        from pliant import _core

        names, why = _core.cuda_devices()
        if not names:
            pytest.skip(f"backend cuda: no CUDA device here ({why})")
    return request.param


def pytest_terminal_summary(terminalreporter):
    counts: dict[str, dict[str, int]] = {b: {} for b in BACKENDS}
    for outcome in ("passed", "failed", "skipped", "error"):
        for rep in terminalreporter.stats.get(outcome, []):
            b = dict(getattr(rep, "user_properties", ())).get("backend")
            if b and (outcome != "passed" or rep.when == "call"):
                counts[b][outcome] = counts[b].get(outcome, 0) + 1
    if any(counts.values()):
        terminalreporter.section("tests per backend")
        for b, c in counts.items():
            terminalreporter.write_line(
                f"{b:>14}: " + (", ".join(f"{n} {o}" for o, n in c.items()) or "none run")
            )
