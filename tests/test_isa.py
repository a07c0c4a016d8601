"""One build, every CPU: the engine is compiled per instruction set and the best one the CPU
runs is imported (pliant/_core.py); PLIANT_ISA forces one. Each path gives the same bits for any
thread count, and the paths agree to round-off."""

import json
import os
import platform
import subprocess
import sys

import numpy as np
import pytest

from pliant import _core

SCRIPT = r"""
import json, sys
import numpy as np
import pliant as pl
X, T = pl.mesh.box_tets((0.1, 0.02, 0.02), (10, 2, 2), jitter=0.2, seed=3)
out = {"isa": pl._core.isa}
for threads in (1, 2):
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(pl.NeoHookeanCoupled(E=2e4, nu=0.45), density=1000.0)
    b.fix(np.nonzero(X[:, 0] < 1e-9)[0])
    b.set_gravity((0.0, 0.0, -9.81))
    sim = pl.Simulation(b.finalize("float64", threads=threads), dt=1e-4)
    sim.run(steps=300)
    out[threads] = sim.displacements.tolist()
print(json.dumps(out))
"""


def _run(isa):
    env = dict(os.environ, PLIANT_ISA=isa)
    r = subprocess.run([sys.executable, "-c", SCRIPT], env=env, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout)


def test_every_instruction_set_is_built():
    want = {"generic", "avx2", "avx512"} if platform.machine() in ("x86_64", "AMD64") else {"generic"}
    assert want <= set(_core.isas), _core.isas


# The x86-64 psABI micro-architecture levels (System V AMD64 ABI, "Micro-architecture levels"),
# in /proc/cpuinfo's names (LZCNT shows as abm): written here from the ABI, not from pliant/_core.py.
V3 = {"avx", "avx2", "bmi1", "bmi2", "f16c", "fma", "abm", "movbe", "xsave"}
V4 = V3 | {"avx512f", "avx512bw", "avx512cd", "avx512dq", "avx512vl"}


def test_the_chosen_path_is_the_fastest_this_cpu_runs():
    flags = set()
    try:
        for line in open("/proc/cpuinfo", encoding="ascii", errors="replace"):
            if line.startswith("flags"):
                flags = set(line.split(":", 1)[1].split())
                break
    except OSError:
        pass
    runs = {"generic"} | ({"avx2"} if V3 <= flags else set()) | ({"avx512"} if V4 <= flags else set())
    if "native" in _core.isas:  # built for this very machine: preferred
        assert _core.isa == "native"
        return
    best = next(i for i in ("avx512", "avx2", "generic") if i in runs and i in _core.isas)
    assert _core.isa == best


@pytest.mark.parametrize("isa", ["generic", "avx2", "avx512", "native"])
def test_each_path_is_deterministic_and_agrees(isa):
    if isa not in _core.isas:
        pytest.skip(f"the {isa} module is not in this build ({', '.join(_core.isas)})")
    flags = _core._cpu_flags()
    if isa in _core._NEEDS and not _core._NEEDS[isa] <= flags:
        pytest.skip(f"this CPU cannot run the {isa} module")
    got = _run(isa)
    assert got["isa"] == isa
    # Same path: the same bits for 1 and 2 threads.
    assert got["1"] == got["2"]
    # Paths differ only in vectorization and FMA contraction: last bits, carried by 300 damped
    # steps; 1e-10 of the largest displacement bounds that.
    ref = np.asarray(_run("generic")["1"])
    u = np.asarray(got["1"])
    assert np.abs(u).max() > 1e-4
    assert np.abs(u - ref).max() <= 1e-10 * np.abs(ref).max()


def test_an_unknown_path_is_named_and_the_best_one_used():
    env = dict(os.environ, PLIANT_ISA="sse9")
    r = subprocess.run(
        [sys.executable, "-c", "import pliant; print(pliant._core.isa)"],
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert r.returncode == 0, r.stderr
    assert "PLIANT_ISA='sse9' is not in this build" in r.stderr and "generic" in r.stderr
    assert r.stdout.strip() == _core.isa
