"""Triangle surfaces from PLY files (Turk's Polygon File Format: scanners, MeshLab, the Stanford
repository), read by trimesh. meshio's reader refused trimesh's own binary files with face colours
("buffer size must be a multiple of element size") and the type names uint8 / uint32 that the PLY
specification also allows. trimesh's reader, in turn, read a truncated ASCII file, or one whose
header counts more vertices than it holds, as far as it went and said nothing: the header's counts
are checked against what was read here. Format: G. Turk, "The PLY Polygon File Format" (1994):
``ply``, ``format ascii|binary_little_endian|binary_big_endian 1.0``, ``element NAME COUNT`` each
followed by its ``property`` lines, ``end_header``; in ASCII, one record a line."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import MeshError

__all__ = ["read_ply"]

_MAX_HEADER = 1 << 20  # bytes: a header longer than this is not a PLY header


def _header(path: Path) -> tuple[str, dict[str, int], int]:
    """The format, each element's count, and the header's length in bytes. MeshError for a file that
    does not begin with ``ply`` or whose header has no ``end_header``, a bad element line or format."""
    with open(path, "rb") as f:
        head = f.read(_MAX_HEADER)
    if not head.startswith(b"ply"):
        raise MeshError(f"{path}: not a PLY file (it does not begin with 'ply')")
    end = head.find(b"end_header")
    if end < 0:
        raise MeshError(f"{path}: the PLY header has no end_header (truncated, or not PLY)")
    stop = head.find(b"\n", end)
    text = head[:end].decode("ascii", errors="replace").splitlines()
    fmt, counts = "", {}
    for lineno, line in enumerate(text, 1):
        words = line.split()
        if words[:1] == ["format"]:
            fmt = words[1] if len(words) > 1 else ""
        elif words[:1] == ["element"]:
            if len(words) != 3 or not words[2].isdigit():
                raise MeshError(f"{path}:{lineno}: expected 'element NAME COUNT', got {line.strip()[:80]!r}")
            counts[words[1]] = int(words[2])
    if fmt not in ("ascii", "binary_little_endian", "binary_big_endian"):
        raise MeshError(
            f"{path}: PLY format {fmt!r}; expected ascii, binary_little_endian or binary_big_endian"
        )
    return fmt, counts, (stop + 1 if stop >= 0 else len(head))


def _ascii_records(path: Path, start: int) -> int:
    """Non-blank lines after the header: the records of an ASCII PLY, one a line."""
    n = 0
    with open(path, "rb") as f:
        f.seek(start)
        for line in f:
            n += bool(line.strip())
    return n


def read_ply(path) -> tuple[np.ndarray, np.ndarray]:
    """Vertices [file units] (V, 3) float64 and triangles (F, 3) int64 of a PLY file (ASCII or
    binary; polygons triangulated by trimesh). MeshError naming the file for a malformed header, a
    file that holds fewer or more records than its header counts, or no faces."""
    import trimesh

    path = Path(path)
    fmt, counts, start = _header(path)
    if counts.get("vertex", 0) == 0 or counts.get("face", 0) == 0:
        raise MeshError(
            f"{path}: {counts.get('vertex', 0):,} vertices and {counts.get('face', 0):,} faces in its "
            "header; expected a surface (a 'vertex' and a 'face' element)"
        )
    if fmt == "ascii" and (found := _ascii_records(path, start)) != sum(counts.values()):
        said = ", ".join(f"{n:,} {k}" for k, n in counts.items())
        raise MeshError(
            f"{path}: the header counts {said} records; the file holds {found:,} "
            f"({'truncated?' if found < sum(counts.values()) else 'more than it says'})"
        )
    try:
        m = trimesh.load(path, file_type="ply", force="mesh", process=False)
    except Exception as e:  # trimesh raises what its parser raises
        raise MeshError(f"{path}: cannot read as a PLY surface ({type(e).__name__}: {e})") from None
    if not isinstance(m, trimesh.Trimesh) or len(m.vertices) != counts["vertex"]:
        n = len(m.vertices) if isinstance(m, trimesh.Trimesh) else 0
        raise MeshError(f"{path}: read {n:,} of the {counts['vertex']:,} vertices its header counts")
    V = np.asarray(m.vertices, dtype=np.float64).reshape(-1, 3)
    return V, np.asarray(m.faces, dtype=np.int64).reshape(-1, 3)
