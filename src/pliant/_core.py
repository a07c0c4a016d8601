"""The engine (pliant._core): the compiled module for this CPU's instruction set.

A build holds one module per instruction set (``_core_generic``: x86-64; ``_core_avx2``:
x86-64-v3; ``_core_avx512``: x86-64-v4 with 512-bit vectors; ``_core_native`` when built with
PLIANT_NATIVE=ON). The fastest one this CPU runs is imported here and its names re-exported, so
``from pliant import _core`` sees one engine. ``PLIANT_ISA=generic|avx2|avx512|native`` forces one
(tests, benchmarks). ``isa`` names the chosen path, ``isas`` those in this build."""

import importlib
import os
from importlib.util import find_spec
from typing import Any

_ORDER = ("native", "avx512", "avx2", "generic")


def _in_build() -> tuple:
    return tuple(i for i in _ORDER if find_spec(f"{__package__}._core_{i}") is not None)


# CPU flags (Linux /proc/cpuinfo names) of the x86-64 micro-architecture levels the modules target.
_NEEDS = {
    "avx2": {"avx", "avx2", "bmi1", "bmi2", "f16c", "fma", "movbe", "abm", "xsave"},
    "avx512": {
        "avx",
        "avx2",
        "bmi1",
        "bmi2",
        "f16c",
        "fma",
        "movbe",
        "abm",
        "xsave",
        "avx512f",
        "avx512bw",
        "avx512cd",
        "avx512dq",
        "avx512vl",
    },
}


def _cpu_flags() -> set:
    """The CPU's feature flags (empty where /proc/cpuinfo is not readable: the generic module).
    Only one engine module may be loaded in a process (they bind the same types), so the choice
    is made before importing any."""
    try:
        with open("/proc/cpuinfo", encoding="ascii", errors="replace") as f:
            for line in f:
                if line.startswith("flags"):
                    return set(line.split(":", 1)[1].split())
    except OSError:
        pass
    return set()


def _choose(isas: tuple) -> str:
    forced = os.environ.get("PLIANT_ISA", "").strip()
    if forced in isas:
        return forced
    if not isas:
        raise ImportError("pliant's compiled engine is missing (no pliant._core_* module): reinstall pliant")
    flags = _cpu_flags()
    best = next((i for i in isas if i in ("native", "generic") or _NEEDS[i] <= flags), isas[-1])
    if forced:  # a bad setting must not stop every command: say so, run on the best path
        import sys

        print(
            f"warning: PLIANT_ISA={forced!r} is not in this build of pliant "
            f"({', '.join(isas)}); using {best}",
            file=sys.stderr,
        )
    return best


isas = _in_build()
isa = _choose(isas)
_engine = importlib.import_module(f"{__package__}._core_{isa}")
globals().update({k: v for k, v in vars(_engine).items() if not k.startswith("__")})


def __getattr__(name: str) -> Any:
    """Names the engine module does not have (the engine's own are set above): AttributeError.
    Declared so that type checkers see the engine's names, which nanobind defines at import, as
    typed Any rather than missing."""
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
