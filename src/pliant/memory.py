"""Memory a mesh will need, checked against what the machine has before the work starts. A mesh
too large for the machine is refused by name (InputError: exit 2 on the command line), where it
would otherwise fill the memory until the kernel's out-of-memory killer ends the process without a
word (Linux overcommits: each allocation succeeds, the pages fail later).

The figures are peaks per tetrahedron measured on top of what a process already holds (Python
3.11, numpy 2, 2026-11-26; ``resource.getrusage`` maxima, 1.3M to 8M tets, jittered boxes), each
rounded up by about a quarter for what differs between machines and meshes."""

from __future__ import annotations

from .errors import InputError

BOX_BYTES_PER_TET = 400  # box_tets: nodes, tets, the jitter's untangling (measured 319–326 B/tet)
MODEL_BYTES_PER_TET = 300  # ModelBuilder.finalize on top of its mesh, float32 or float64 (205–253)
OUTPUT_BYTES_PER_TET = 700  # a scene run's frames and picture on top of its model (about 560)


def _proc_bytes(file: str, key: str) -> int | None:
    """The figure of a ``key: N kB`` line of a Linux /proc file [bytes]; None where there is none."""
    try:
        with open(file, encoding="ascii", errors="replace") as f:  # a process name may be any bytes
            for line in f:
                if line.startswith(key + ":"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        return None
    return None


def available_memory() -> int | None:
    """Memory [bytes] the machine can give without swapping: Linux's MemAvailable (page cache that
    can be dropped included); None where /proc/meminfo does not say (other systems: not checked)."""
    return _proc_bytes("/proc/meminfo", "MemAvailable")


def data_segment() -> int | None:
    """This process's data segment [bytes]: Linux's VmData, what RLIMIT_DATA bounds (anonymous
    writable memory); None where /proc does not say."""
    return _proc_bytes("/proc/self/status", "VmData")


def require_memory(n_tets: float, bytes_per_tet: float, what: str) -> None:
    """Raise InputError naming ``what`` ("cells = [400, 400, 400] (3.84e+08 tets)") if ``n_tets``
    tetrahedra at ``bytes_per_tet`` [bytes] need more memory than the machine has available."""
    need = float(n_tets) * bytes_per_tet
    have = available_memory()
    if have is not None and need > have:
        raise InputError(
            f"{what} needs about {need / 1e9:.3g} GB of memory; this machine has {have / 1e9:.3g} GB "
            "available; expected a mesh that fits (fewer cells or tets)"
        )
