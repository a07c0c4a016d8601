"""CUDA backend: compiled wherever nvcc is (CI builds it every time), no spills, a clear error
without a GPU, and CPU–GPU agreement where a GPU exists."""

import re
import shutil
from pathlib import Path

import numpy as np
import pytest

import pliant as pl
from pliant import _core

USAGE = Path(pl.__file__).parent / "cuda_resource_usage.txt"


def test_cuda_backend_is_compiled_when_nvcc_exists():
    assert _core.cuda_compiled() == (shutil.which("nvcc") is not None)


def test_no_kernel_spills_to_local_memory():
    if not _core.cuda_compiled():
        pytest.skip("CUDA backend not compiled (no nvcc at build time)")
    text = USAGE.read_text()
    # ptxas -v on the shipped compile (every architecture): each entry function, then for every
    # function its stack frame and spills. Any spill store or load fails, on any architecture.
    entries = re.findall(r"Compiling entry function '([^']+)' for '(sm_\d+)'", text)
    frames = re.findall(
        r"Function properties for (\S+)\s+(\d+) bytes stack frame, "
        r"(\d+) bytes spill stores, (\d+) bytes spill loads",
        text,
    )
    archs = {arch for _, arch in entries}
    assert len(entries) >= 10 and len(frames) >= len(entries) and {"sm_75", "sm_90"} <= archs
    bad = [(name, stores, loads) for name, _, stores, loads in frames if (stores, loads) != ("0", "0")]
    assert not bad, f"kernels spilling to local memory: {bad}"


def _sphere_model(backend="cpu", extras=False):
    """NiftySim's sphere under gravity; `extras`: T4ANP, a follower pressure on its upper half, a
    rigid sphere pressing it and an Arruda–Boyce material, so that every kernel runs."""
    X, T, _ = pl.io.read_volume_mesh(Path(__file__).parent / "data" / "niftysim_sphere.vtk")
    T = pl.mesh.orient_positive(X, T)
    b = pl.ModelBuilder()
    b.add_mesh(X, T)
    b.set_material(pl.ArrudaBoyce(1e3, 2.0, 2e4) if extras else pl.NeoHookean(mu=1e3, K=2e4), density=1000.0)
    b.fix(np.nonzero(X[:, 2] < -0.8)[0])
    b.set_gravity((0.0, 0.0, -9.81), curve=pl.SmoothRamp(0.05))
    b.damping = 5.0
    if extras:
        from pliant.contact import Sphere
        from pliant.mesh.topology import boundary_faces

        b.nodal_pressure = True
        B, _ = boundary_faces(T)
        b.add_pressure(B[np.all(X[B][:, :, 2] > 0.5, axis=1)], 200.0, pl.Ramp(0.05))
        tool = Sphere(0.3)
        tool.at(0.0, (0.0, 1.32, 0.0)).at(0.1, (0.0, 1.25, 0.0))  # 5 cm into it, slowly
        b.add_tool(tool)
    return b.finalize("float32", backend=backend)


def test_cuda_without_a_device_is_a_clear_error():
    names, why = _core.cuda_devices()
    if names:
        pytest.skip(f"a CUDA device is present ({names[0]}): the no-device path cannot be tested")
    with pytest.raises(pl.BackendError, match="cuda"):
        _sphere_model("cuda")
    print("backend='cuda' refused:", why)


@pytest.mark.parametrize("extras", [False, True], ids=["plain", "anp-pressure-contact"])
@pytest.mark.parametrize("device", ["cuda-emulated", "cuda"])
def test_cpu_and_gpu_agree_over_1000_steps(extras, device):
    names, why = _core.cuda_devices()
    if device == "cuda" and not names:
        pytest.skip(f"no CUDA device here ({why}); this test runs where a GPU is present")
    cpu, gpu = _sphere_model("cpu", extras), _sphere_model(device, extras)
    assert gpu.backend == device
    a, b = pl.Simulation(cpu, dt=1e-4), pl.Simulation(gpu, dt=1e-4)
    a.run(steps=1000)
    b.run(steps=1000)
    ua, ub = a.displacements, b.displacements
    scale = np.abs(ua).max()
    assert scale > 1e-3
    # float32: the GPU's (and the emulated device's scalar) FMA contraction and libm differ from
    # the CPU's SIMD code in the last bits; over 1,000 steps the difference stays below 1e-5 of
    # the largest displacement.
    assert np.abs(ua - ub).max() <= 1e-5 * scale
