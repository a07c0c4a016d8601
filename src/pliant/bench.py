"""Benchmark: the study's table (8,000 steps of Δt = 0.025 ms on 7,456 / 12,584 / 27,918 tets,
Neo-Hookean) plus larger meshes. Prints figures; it is not a test.

Study (Chapter on GPU TLED, 2013 hardware): GPU 2.88 / 5.21 / 8.74 s, CPU 298 / 667 / 1,186 s.
"""

from __future__ import annotations

import json
import os
import time
from dataclasses import asdict, dataclass

import numpy as np

from .materials import NeoHookean
from .mesh import box_tets
from .mesh.topology import drop_unused
from .tled import ModelBuilder, Solver

STUDY = {7456: (2.88, 298.0), 12584: (5.21, 667.0), 27918: (8.74, 1186.0)}
DT = 2.5e-5  # s (0.025 ms, the study's step)


@dataclass
class BenchRow:
    tets: int
    nodes: int
    steps: int
    dt: float
    threads: int | None  # CPU threads; None on the GPU
    dtype: str
    backend: str
    seconds: float  # wall time of the timed steps [s]
    seconds_per_8000: float  # scaled to the study's 8,000 steps [s]
    element_seconds: float | None  # kernel 1 share of `seconds`; None where not timed (kernel_timed)
    node_seconds: float | None  # kernel 2 (+ constraints) share; None where not timed
    element_steps_per_second: float
    memory_bytes: int  # model + two states + scratch
    bytes_per_tet: float
    speedup_vs_study_gpu: float | None
    speedup_vs_study_cpu: float | None


def exact_count_mesh(n_tets: int, size: float | None = None, seed: int = 0):
    """A jittered box mesh with exactly ``n_tets`` tets: the first n_tets of a Kuhn-split grid
    (a compact, layered chunk), unused nodes removed. The box edge [m] defaults to 0.1 m at
    27,918 tets and scales with the cube root of the count (same element size, so the study's
    Δt stays stable). Returns nodes [m] (N, 3), tets (n_tets, 4)."""
    n = max(2, int(np.ceil((n_tets / 6.0) ** (1.0 / 3.0))))
    size = 0.1 * (n_tets / 27918.0) ** (1.0 / 3.0) if size is None else size
    X, T = box_tets((size, size, size), (n, n, n), jitter=0.2, seed=seed)
    # Order cells layer by layer (z slowest) so that a prefix is compact.
    cz = X[T].mean(axis=1)
    order = np.lexsort((cz[:, 0], cz[:, 1], np.floor(cz[:, 2] / (size / n))))
    T = T[order[:n_tets]]
    X, T, _ = drop_unused(X, T)
    return X, T


def timed_run(solver: Solver, steps: int, warmup: int = 50):
    """Run ``warmup`` steps, then time ``steps`` more on a new state: (wall time [s], RunInfo)."""
    state = solver.model.state()
    solver.run(state, steps=warmup)
    return run_timed(solver, state, steps)


def run_timed(solver: Solver, state, steps: int):
    """Run ``steps`` steps of ``state`` on: (wall time [s], RunInfo)."""
    t0 = time.perf_counter()
    info = solver.run(state, steps=steps)
    return time.perf_counter() - t0, info


def kernel_timed(backend: str) -> bool:
    """Whether RunInfo's per-kernel seconds are measured: on the CPU backend only. On the GPU the
    kernels run asynchronously inside graphs and are not timed one by one, and the emulated
    device's recorded launches are not timed either (both read 0)."""
    return backend == "cpu"


def host_threads(model, backend: str) -> int | None:
    """The CPU threads a benchmark row reports: None on the GPU (the host only launches)."""
    return None if backend == "cuda" else model.threads


def _share(seconds: float, wall: float, backend: str) -> float | None:
    return seconds / wall if kernel_timed(backend) else None


def _bench_solver(model, backend: str, dt: float | None = DT) -> Solver:
    """The study's step (dt None: the model's own step [s]); on the GPU, stability checks every
    1,000 steps (each is a host round trip), else every 16."""
    return Solver(model, dt=dt, check_every=1000 if backend == "cuda" else 16)


def bench_one(
    n_tets: int,
    steps: int,
    threads: int | None = None,
    dtype: str = "float32",
    warmup: int = 50,
    backend: str = "cpu",
) -> BenchRow:
    X, T = exact_count_mesh(n_tets)
    b = ModelBuilder()
    b.add_mesh(X, T, source=f"bench mesh ({n_tets} tets)")
    b.set_material(NeoHookean(mu=3.0e3, K=5.0e4), density=1000.0)  # soft tissue
    b.fix(np.nonzero(X[:, 2] < 1e-9)[0])
    b.set_gravity()
    b.damping = 10.0
    model = b.finalize(dtype, threads=threads, backend=backend)
    wall, info = timed_run(_bench_solver(model, backend), steps, warmup)
    itemsize = np.dtype(dtype).itemsize
    pad = -(-model.n_nodes // 16) * 16
    mem = (
        model.memory_bytes + itemsize * (2 * 2 * 3 * pad + 3 * pad) + itemsize * 13 * (-(-n_tets // 16) * 16)
    )
    per8000 = wall * 8000.0 / steps
    study = STUDY.get(n_tets)
    return BenchRow(
        n_tets,
        model.n_nodes,
        steps,
        DT,
        host_threads(model, backend),
        dtype,
        backend,
        wall,
        per8000,
        info.element_seconds if kernel_timed(backend) else None,
        info.node_seconds if kernel_timed(backend) else None,
        n_tets * steps / wall,
        mem,
        mem / n_tets,
        study[0] / per8000 if study else None,
        study[1] / per8000 if study else None,
    )


def run_benchmark(
    sizes=(7456, 12584, 27918, 100_000, 1_000_000),
    steps: int = 8000,
    large_steps: int = 200,
    threads: int | None = None,
    dtype: str = "float32",
    json_path: str | None = None,
    echo=print,
    backend: str = "cpu",
) -> list[BenchRow]:
    rows = []
    for n in sizes:
        row = bench_one(n, steps if n in STUDY else large_steps, threads, dtype, backend=backend)
        rows.append(row)
        echo(row)
    if json_path:
        from .io.files import atomic_write_text

        atomic_write_text(
            json_path,
            json.dumps(
                {"backend": backend, "load_average": os.getloadavg(), "rows": [asdict(r) for r in rows]},
                indent=2,
            ),
            "benchmark JSON",
        )
    return rows


def bench_contact(steps: int = 2000, echo=print, backend: str = "cpu") -> list[dict]:
    """Share of the contact kernel in the step: the demo (Spot, ground plane and sphere) and the
    liver example pressed by a capsule, on ``backend`` (where kernels are not timed, the GPU and
    the emulated device, the shares are None: only the wall time is measured). Returns one dict
    per case."""
    from pathlib import Path

    from .contact import Capsule
    from .demo import DEMO_SCENE
    from .scene import load_scene

    cases = []
    demo = load_scene(DEMO_SCENE)
    cases.append(("demo: Spot + ground + sphere", demo))
    liver_path = Path.cwd() / "examples" / "liver_indentation.toml"  # run from the repository
    if not liver_path.exists():
        echo({"case": "liver + capsule", "skipped": f"{liver_path} not found (run from the repository root)"})
    else:
        liver = load_scene(liver_path)
        tool = Capsule(0.005, 0.06, rotation=(0.7071068, 0.7071068, 0.0, 0.0), mu_s=0.2, mu_k=0.1)
        tool.at(0.0, (-0.0554, 0.3745, 0.112)).at(0.3, (-0.0554, 0.3745, 0.09))
        liver.builder.add_tool(tool)
        cases.append(("liver + capsule", liver))
    rows = []
    for name, sc in cases:
        model = sc.builder.finalize(sc.dtype, backend=backend)
        wall, info = timed_run(_bench_solver(model, backend, dt=None), steps)
        row = {
            "case": name,
            "tets": model.n_elements,
            "contact_nodes": int(len(model.contact_nodes)),
            "tools": len(model.tools),
            "steps": steps,
            "seconds": wall,
            "contact_share": _share(info.contact_seconds, wall, backend),
            "element_share": _share(info.element_seconds, wall, backend),
            "node_share": _share(info.node_seconds, wall, backend),
        }
        rows.append(row)
        echo(row)
    return rows


def material_cases():
    """Every material (and viscoelastic, T4ANP and edge-smoothed cases) with soft-tissue constants,
    for the per-material table: (name, material, T4ANP, strain smoothing)."""
    from . import materials as m

    nh = m.NeoHookean(mu=3.0e3, K=5.0e4)
    cases = [
        ("NeoHookean", nh, False),
        ("NeoHookeanCoupled", m.NeoHookeanCoupled(E=8.8e3, nu=0.47), False),
        ("StVenantKirchhoff", m.StVenantKirchhoff(E=8.8e3, nu=0.47), False),
        ("LinearElastic", m.LinearElastic(E=8.8e3, nu=0.47), False),
        ("MooneyRivlin", m.MooneyRivlin(1.0e3, 0.5e3, 5.0e4), False),
        ("Polynomial", m.Polynomial(1.0e3, 0.5e3, 200.0, 100.0, 50.0, K=5.0e4), False),
        ("ArrudaBoyce", m.ArrudaBoyce(3.0e3, 2.0, 5.0e4), False),
        ("TransverselyIsotropic", m.TransverselyIsotropic(3.0e3, 5.0e4, 1.0e3, (1.0, 0.0, 0.0)), False),
        ("Viscoelastic(NeoHookean), 1 term", m.Viscoelastic(nh, iso=[(0.5, 0.1)]), False),
        (
            "Viscoelastic(NeoHookean), 1+1 terms",
            m.Viscoelastic(nh, iso=[(0.5, 0.1)], vol=[(0.2, 0.1)]),
            False,
        ),
        (
            "Viscoelastic(NeoHookean), 2+2 terms",
            m.Viscoelastic(nh, iso=[(0.2, 0.01), (0.2, 1.0)], vol=[(0.2, 0.01), (0.2, 1.0)]),
            False,
        ),
        (
            "Viscoelastic(NeoHookean), 4+4 terms",
            m.Viscoelastic(
                nh,
                iso=[(0.1, 0.01), (0.1, 0.1), (0.1, 1.0), (0.1, 10.0)],
                vol=[(0.1, 0.01), (0.1, 0.1), (0.1, 1.0), (0.1, 10.0)],
            ),
            False,
        ),
        ("NeoHookean, T4ANP", nh, True),
    ]
    smoothed = [
        ("NeoHookean, edge-smoothed", nh, False, "edge"),
        ("NeoHookean, edge-smoothed + T4ANP", nh, True, "edge"),
    ]
    return [(*c, "element") for c in cases] + smoothed


def bench_materials(
    steps: int = 2000,
    threads: int | None = None,
    dtype: str = "float32",
    cells=(24, 24, 8),
    echo=print,
    backend: str = "cpu",
    pairs: int = 5,
) -> list[dict]:
    """Per-step time of every material on one box (24 × 24 × 8 cells: 27,648 tets; gravity, fixed
    base, Δt = 0.025 ms), relative to the decoupled Neo-Hookean. Each case is timed in ``pairs``
    chunks of steps / pairs steps, each right after a chunk of the Neo-Hookean, so that both see the
    same phase of a shared machine; "relative" is the median of the chunks' ratios, with their
    range ("relative_min", "relative_max"; the Neo-Hookean's row against itself shows the noise),
    "ms_per_step" the median chunk's. Returns one dict per case."""
    X, T = box_tets((0.12, 0.12, 0.04), cells, jitter=0.2, seed=0)
    chunk = max(1, steps // pairs)
    cases = material_cases()
    runs = [_material_run(X, T, c, dtype, threads, backend) for c in cases]
    ref_solver, ref_state = runs[0]
    rows = []
    for (name, *_), (solver, state) in zip(cases, runs):
        times, ratios, element = [], [], 0.0
        for _ in range(pairs):
            ref_wall, _ = run_timed(ref_solver, ref_state, chunk)
            wall, info = run_timed(solver, state, chunk)
            times.append(wall / chunk)
            ratios.append(wall / ref_wall)
            element += _share(info.element_seconds, wall, backend) or 0.0
        row = {
            "material": name,
            "tets": len(T),
            "steps": chunk * pairs,
            "threads": host_threads(solver.model, backend),
            "ms_per_step": 1e3 * float(np.median(times)),
            "relative": float(np.median(ratios)),
            "relative_min": min(ratios),
            "relative_max": max(ratios),
            "element_share": element / pairs if kernel_timed(backend) else None,
        }
        rows.append(row)
        echo(row)
    return rows


def _material_run(X, T, case, dtype, threads, backend, warmup: int = 50):
    """A solver and a warmed-up state for one material case of bench_materials."""
    _, material, anp, smoothing = case
    b = ModelBuilder()
    b.add_mesh(X, T, source="material bench box")
    b.set_material(material, density=1000.0)
    b.fix(np.nonzero(X[:, 2] < 1e-9)[0])
    b.set_gravity()
    b.damping = 10.0
    b.nodal_pressure = anp
    b.strain_smoothing = smoothing
    solver = _bench_solver(b.finalize(dtype, threads=threads, backend=backend), backend)
    state = solver.model.state()
    solver.run(state, steps=warmup)
    return solver, state


def bench_batch(
    copies: int = 64,
    n_tets: int = 2000,
    steps: int = 2000,
    threads: int | None = None,
    dtype: str = "float32",
    backend: str = "cpu",
) -> dict:
    """Many small bodies: ``copies`` Neo-Hookean bodies of ``n_tets`` tets (each its own modulus,
    E = 3–6 kPa), ``steps`` steps of the study's Δt, stepped one model after another versus as one
    :class:`~pliant.tled.batch.Batch`. Model building is not timed. Returns the figures: seconds
    each way, the gain, and element-steps per second of the batch."""
    from .tled.batch import Batch

    X, T = exact_count_mesh(n_tets, size=0.1 * (n_tets / 27918.0) ** (1.0 / 3.0))
    Es = np.linspace(3e3, 6e3, copies)

    def body(E: float) -> ModelBuilder:
        b = ModelBuilder()
        b.add_mesh(X, T)
        b.set_material(NeoHookean(E=E, nu=0.45), density=1000.0)
        b.fix(np.nonzero(X[:, 2] < 1e-9)[0])
        b.set_gravity((0.0, 0.0, -9.81))
        return b

    solvers = [_bench_solver(body(E).finalize(dtype, threads=threads, backend=backend), backend) for E in Es]
    states = [s.model.state() for s in solvers]
    for s, st in zip(solvers, states):
        s.run(st, steps=20)  # warm-up
    t0 = time.perf_counter()
    for s, st in zip(solvers, states):
        s.run(st, steps=steps)
    alone = time.perf_counter() - t0
    batch = Batch([body(E) for E in Es], dtype, threads=threads, backend=backend)
    together, _ = timed_run(_bench_solver(batch.model, backend), steps, warmup=20)
    return {
        "copies": copies,
        "tets": int(len(T)),
        "steps": steps,
        "backend": backend,
        "threads": host_threads(solvers[0].model, backend),
        "dtype": dtype,
        "one_by_one_s": alone,
        "batch_s": together,
        "gain": alone / together,
        "batch_element_steps_per_second": copies * len(T) * steps / together,
    }
