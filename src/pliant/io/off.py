"""Triangle surfaces from OFF files (Geomview's Object File Format; Princeton Shape Benchmark,
ModelNet). meshio's reader refused polygons, faces followed by their colour and the COFF / NOFF
variants, all common. Format (Geomview manual, "OFF Files"): a header keyword ``[ST][C][N][4][n]OFF``
(optionally followed by the counts on the same line), the counts ``NVertices NFaces NEdges``, then a
vertex a line (x y z, then whatever the variant adds: normals, colour, texture coordinates), then a
face a line (``k v1 ... vk``, then an optional colour). ``#`` starts a comment; blank lines are
skipped; a first count glued to the keyword (``OFF490 518 0``, as in ModelNet's files) is read.
Polygons are fanned from their first vertex. The binary variant is refused by name."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from ..errors import MeshError
from .text_table import table

__all__ = ["read_off"]

_HEADER = re.compile(r"^(ST)?C?N?(4)?(n)?OFF$")


def _lines(path: Path):
    """(line number, words) of the file's lines, comments and blank lines left out."""
    with open(path, encoding="utf-8", errors="replace") as f:
        for lineno, line in enumerate(f, 1):
            words = line.split("#", 1)[0].split()
            if words:
                yield lineno, words


def _ints(path: Path, lineno: int, words: list[str], what: str) -> list[int]:
    try:
        return [int(w) for w in words]
    except ValueError:
        raise MeshError(f"{path}:{lineno}: expected {what}, got {' '.join(words)[:80]!r}") from None


def _header(path: Path, lines) -> tuple[int, int, int]:
    """The vertex and face counts, after the keyword (which may share their line), and the line
    number of the counts."""
    try:
        lineno, words = next(lines)
    except StopIteration:
        raise MeshError(f"{path}: empty file; expected an OFF header") from None
    glued = re.match(r"^(\w*OFF)(\d+)$", words[0])  # "OFF490 518 0": ModelNet's files glue the first count
    if glued:
        words = [glued.group(1), glued.group(2), *words[1:]]
    m = _HEADER.match(words[0])
    if not m:
        raise MeshError(
            f"{path}:{lineno}: {words[0][:40]!r} is not an OFF header (OFF, COFF, NOFF, STOFF...)"
        )
    if m.group(2):
        raise MeshError(f"{path}:{lineno}: {words[0]}: 4-D vertices; expected a 3-D surface")
    rest = words[1:]
    if rest and rest[0].upper() == "BINARY":
        raise MeshError(f"{path}:{lineno}: binary OFF is not read; expected the ASCII form")
    if m.group(3):  # nOFF: the vertices' dimension comes first
        if not rest:
            lineno, rest = next(lines, (lineno, []))
        dim = _ints(path, lineno, rest[:1], "nOFF's dimension") or [0]
        if dim[0] != 3:
            raise MeshError(f"{path}:{lineno}: nOFF of dimension {dim[0]}; expected 3")
        rest = rest[1:]
    if not rest:
        try:
            lineno, rest = next(lines)
        except StopIteration:
            raise MeshError(f"{path}: the file ends before its counts (NVertices NFaces NEdges)") from None
    counts = _ints(path, lineno, rest[:3], "NVertices NFaces NEdges")
    if len(counts) < 2 or min(counts) < 0:
        raise MeshError(f"{path}:{lineno}: expected NVertices NFaces NEdges (counts >= 0), got {rest}")
    return counts[0], counts[1], lineno


def _fast(path: Path, nv: int, nf: int, after: int) -> tuple[np.ndarray, np.ndarray] | None:
    """The common file read in bulk (numpy parses the numbers; text_table): no comment after the
    header, three numbers a vertex line, only triangles without colours, nothing more. None for
    anything else, which the line-by-line reader then reads or refuses naming its line. 1.3 M
    faces: 10 s → 2 s."""
    data = path.read_bytes().split(b"\n")[after:]
    rows = [r for r in data if r.strip()]
    if len(rows) != nv + nf or any(b"#" in r for r in rows):
        return None
    xyz = table(rows[:nv], [np.float64] * 3)
    face = table(rows[nv:], [np.int64] * 4)
    if xyz is None or face is None or np.any(face[0] != 3):
        return None
    F = np.stack(face[1:], axis=1)
    if nf and (F.min() < 0 or F.max() >= nv):
        return None
    return np.stack(xyz, axis=1), F


def read_off(path) -> tuple[np.ndarray, np.ndarray]:
    """Vertices [file units] (V, 3) float64 and triangles (F, 3) int64 of an ASCII OFF file.
    MeshError naming the file and line for a bad header, vertex or face, and for a file that
    holds fewer vertices or faces than its counts say (truncated) or more lines after them."""
    path = Path(path)
    lines = _lines(path)
    nv, nf, after = _header(path, lines)
    fast = _fast(path, nv, nf, after)
    if fast is not None:
        return fast
    V: list[list[float]] = []  # appended: a header's count alone allocates nothing
    F: list[list[int]] = []
    for i in range(nv + nf):
        try:
            lineno, words = next(lines)
        except StopIteration:
            what = f"{i} of its {nv:,} vertices" if i < nv else f"{i - nv} of its {nf:,} faces"
            raise MeshError(f"{path}: the file ends after {what} (truncated?)") from None
        if i < nv:
            try:
                V.append([float(w) for w in words[:3]])
            except ValueError:
                V.append([])
            if len(V[-1]) != 3:
                raise MeshError(f"{path}:{lineno}: expected a vertex 'x y z', got {' '.join(words)[:80]!r}")
            continue
        k = _ints(path, lineno, words[:1], "a face 'k v1 ... vk'")[0]
        idx = _ints(path, lineno, words[1 : k + 1], "a face 'k v1 ... vk'")
        if k < 3 or len(idx) != k:
            raise MeshError(f"{path}:{lineno}: a face of {k} vertices with {len(idx)} given; expected k >= 3")
        if min(idx) < 0 or max(idx) >= nv:
            raise MeshError(
                f"{path}:{lineno}: vertex index out of range 0..{nv - 1} in {' '.join(words)[:80]!r}"
            )
        F.extend([idx[0], idx[j], idx[j + 1]] for j in range(1, k - 1))
    extra = next(lines, None)
    if extra is not None:
        raise MeshError(
            f"{path}:{extra[0]}: more data after the {nv:,} vertices and {nf:,} faces the header counts"
        )
    return np.asarray(V, dtype=float).reshape(-1, 3), np.asarray(F, dtype=np.int64).reshape(-1, 3)
