import pytest


@pytest.fixture(params=["float32", "float64"])
def dtype(request):
    return request.param


# --- backends: every test taking `backend` runs on each, and the summary counts them ----------------
BACKENDS = ("cpu", "cuda-emulated", "cuda")
_backend_of: dict[str, str] = {}


@pytest.fixture(params=BACKENDS)
def backend(request):
    """A backend name; "cuda" is skipped, with the reason, where there is no device."""
    if request.param == "cuda":
        from pliant import _core

        names, why = _core.cuda_devices()
        if not names:
            pytest.skip(f"backend cuda: no CUDA device here ({why})")
    return request.param


def pytest_collection_modifyitems(items):
    for item in items:
        cs = getattr(item, "callspec", None)
        if cs is not None and "backend" in cs.params:
            _backend_of[item.nodeid] = cs.params["backend"]


def pytest_terminal_summary(terminalreporter):
    counts = {b: {} for b in BACKENDS}
    for outcome in ("passed", "failed", "skipped", "error"):
        for rep in terminalreporter.stats.get(outcome, []):
            b = _backend_of.get(getattr(rep, "nodeid", ""))
            if b and (outcome != "passed" or rep.when == "call"):
                counts[b][outcome] = counts[b].get(outcome, 0) + 1
    if any(counts.values()):
        terminalreporter.section("tests per backend")
        for b, c in counts.items():
            terminalreporter.write_line(
                f"{b:>14}: " + (", ".join(f"{n} {o}" for o, n in c.items()) or "none run")
            )
