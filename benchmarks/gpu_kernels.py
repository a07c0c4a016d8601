"""Kernel time per step on a GPU, kernel by kernel: NiftySim's ball_ball.xml (2,000 steps from t =
0.5 s) and examples/organs_contact.toml (500 steps from t = 0.25 s) on the CUDA backend, after 200
steps that capture the graphs. Times come from CUPTI through PyTorch's profiler (which records every
CUDA kernel of the process, graph replays included); PyTorch is not a pliant dependency, and this
benchmark says so and stops where it is missing. Not a test. docs/engine.md, "Performance (CUDA
backend)", has its figures.

    python benchmarks/gpu_kernels.py            # kernels above 0.5 µs a step
    python benchmarks/gpu_kernels.py --all

A kernel is named by its launch shape, the engine function that launched it and the number the
compiler gave its lambda there (e.g. `team:soft_pass#1`: the sweeps' sums; `each_counted:soft_pass#2`:
the detection).
"""

from __future__ import annotations

import argparse
import re
import sys
import time
import warnings
from collections import defaultdict
from pathlib import Path

import pliant as pl
from pliant import _core
from pliant.io.niftysim import load_niftysim
from pliant.scene import load_scene

ROOT = Path(__file__).resolve().parents[1]


def kernel_name(name: str) -> str:
    """`launch shape:engine function#lambda` from a kernel's demangled name."""
    shape = re.search(r"cuda_detail::(\w+?)_kernel", name)
    fn = re.findall(r"::(\w+)\((?:[^()]|\([^()]*\))*\)::\{?lambda", name)
    lam = re.findall(r"lambda\((?:[^()]|\([^()]*\))*\)#?(\d*)", name)
    return f"{shape.group(1) if shape else name[:40]}:{fn[-1] if fn else '?'}#{lam[-1] if lam else ''}"


def profile_run(label: str, sim: pl.Simulation, t0: float, steps: int, floor_us: float) -> None:
    from torch.profiler import ProfilerActivity, profile

    sim.run(until=t0)
    sim.run(steps=200)  # the graphs are captured here, not in the profile
    with profile(activities=[ProfilerActivity.CUDA]) as prof:
        wall = time.perf_counter()
        info = sim.run(steps=steps)
        wall = time.perf_counter() - wall
    total: dict[str, float] = defaultdict(float)
    count: dict[str, int] = defaultdict(int)
    for e in prof.events():
        if e.device_type.name == "CUDA":
            total[kernel_name(e.name)] += getattr(e, "device_time_total", 0.0)
            count[kernel_name(e.name)] += 1
    n = info.steps
    print(
        f"{label}: {sim.model.n_elements:,} tets, {n:,} steps: wall {1e6 * wall / n:.1f} µs a step, "
        f"kernels {sum(total.values()) / n:.1f} µs a step"
    )
    for k, us in sorted(total.items(), key=lambda kv: -kv[1]):
        if us / n >= floor_us:
            print(f"  {us / n:8.2f} µs a step  {count[k] / n:5.2f} launches a step  {k}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--all", action="store_true", help="every kernel, not only those above 0.5 µs a step")
    args = ap.parse_args()
    try:
        import torch
    except ImportError:
        sys.exit("benchmarks/gpu_kernels.py: PyTorch is not installed (its profiler reads the kernel times)")
    if not torch.cuda.is_available() or not _core.cuda_devices()[0]:
        sys.exit("benchmarks/gpu_kernels.py: no CUDA device here")
    warnings.simplefilter("ignore")  # the ball mesh's slow-element warning
    floor = 0.0 if args.all else 0.5
    balls = load_niftysim(ROOT / "tests" / "data" / "niftysim_ball_ball.xml")
    model = balls.builder.finalize("float32", backend="cuda")
    profile_run("ball_ball.xml", pl.Simulation(model, dt=balls.dt), 0.5, 2000, floor)
    organs = load_scene(ROOT / "examples" / "organs_contact.toml")
    model = organs.builder.finalize(organs.dtype, backend="cuda")
    profile_run("organs_contact.toml", pl.Simulation(model), 0.25, 500, floor)


if __name__ == "__main__":
    main()
