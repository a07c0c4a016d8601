"""Triangle surfaces from PLY files (Turk's Polygon File Format: scanners, MeshLab, the Stanford
repository). meshio's reader refused trimesh's own binary files with face colours ("buffer size
must be a multiple of element size") and the type names uint8 / uint32 that the specification also
allows. Binary files are read by trimesh, its result checked against the header's counts; ASCII
files here, since trimesh read a truncated one as far as it went, dropped a face of two vertices
and truncated an index of 2.5 to 2, all without a word. Format: G. Turk, "The PLY Polygon File
Format" (1994): ``ply``, ``format ascii|binary_little_endian|binary_big_endian 1.0``, ``element
NAME COUNT`` each followed by its ``property TYPE NAME`` or ``property list COUNT_TYPE TYPE NAME``
lines, ``end_header``; in ASCII, one record a line, its values in the order of the properties."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import MeshError
from .text_table import table

__all__ = ["read_ply"]

_MAX_HEADER = 1 << 20  # bytes: a header longer than this is not a PLY header
_INTEGER = {"char", "uchar", "short", "ushort", "int", "uint", "int8", "uint8", "int16", "uint16"}
_INTEGER |= {"int32", "uint32"}
_TYPES = _INTEGER | {"float", "double", "float32", "float64"}


@dataclass
class _Element:
    name: str
    count: int
    props: list[tuple[str, bool, str]] = field(default_factory=list)  # (name, is a list, value type)


def _header(path: Path) -> tuple[str, list[_Element], int, int]:
    """The format, the elements, the header's length in bytes and its number of lines. MeshError
    for a file that does not begin with ``ply``, a header without ``end_header``, a bad format,
    element or property line."""
    with open(path, "rb") as f:
        head = f.read(_MAX_HEADER)
    if not head.startswith(b"ply"):
        raise MeshError(f"{path}: not a PLY file (it does not begin with 'ply')")
    end = head.find(b"end_header")
    if end < 0:
        raise MeshError(f"{path}: the PLY header has no end_header (truncated, or not PLY)")
    stop = head.find(b"\n", end)
    text = head[:end].decode("ascii", errors="replace").splitlines()
    fmt, elements = "", []
    for lineno, line in enumerate(text, 1):
        words = line.split()
        if words[:1] == ["format"]:
            fmt = words[1] if len(words) > 1 else ""
        elif words[:1] == ["element"]:
            if len(words) != 3 or not words[2].isdigit():
                raise MeshError(f"{path}:{lineno}: expected 'element NAME COUNT', got {line.strip()[:80]!r}")
            elements.append(_Element(words[1], int(words[2])))
        elif words[:1] == ["property"]:
            is_list = words[1:2] == ["list"]
            ok = elements and (
                (is_list and len(words) == 5 and words[2] in _INTEGER and words[3] in _TYPES)
                or (not is_list and len(words) == 3 and words[1] in _TYPES)
            )
            if not ok:
                raise MeshError(
                    f"{path}:{lineno}: expected 'property TYPE NAME' or 'property list COUNT_TYPE TYPE "
                    f"NAME' after an element, got {line.strip()[:80]!r}"
                )
            elements[-1].props.append((words[-1], is_list, words[-2]))
    if fmt not in ("ascii", "binary_little_endian", "binary_big_endian"):
        raise MeshError(
            f"{path}: PLY format {fmt!r}; expected ascii, binary_little_endian or binary_big_endian"
        )
    return fmt, elements, (stop + 1 if stop >= 0 else len(head)), len(text) + 1


def _values(path: Path, lineno: int, words: list[str], e: _Element) -> dict[str, list[Any]]:
    """One ASCII record's properties by name (a list property's items as its list)."""
    out, k = {}, 0
    try:
        for name, is_list, kind in e.props:
            n = int(words[k]) if is_list else 1
            k += 1 if is_list else 0
            items = words[k : k + n]
            if len(items) != n or n < 0:
                raise IndexError
            out[name] = [int(w) for w in items] if kind in _INTEGER else [float(w) for w in items]
            k += n
    except (ValueError, IndexError):
        raise MeshError(
            f"{path}:{lineno}: {e.name} record {' '.join(words)[:80]!r} does not match its properties "
            f"({', '.join(n for n, _, _ in e.props)}: integers where the header says so)"
        ) from None
    if k != len(words):
        raise MeshError(
            f"{path}:{lineno}: {e.name} record {' '.join(words)[:80]!r} has values its header does not name"
        )
    return out


def _ascii_in_bulk(rows: list[bytes], elements: list[_Element]):
    """The common ASCII file read in bulk (numpy parses the numbers; text_table): a vertex element
    of scalar properties, then a face element of its index list alone, every face a triangle. None
    for anything else, which the record-by-record reader then reads or refuses naming its line.
    1.3 M faces: 15 s → 3 s."""
    if [e.name for e in elements] != ["vertex", "face"] or len(elements[1].props) != 1:
        return None
    vert, face = elements
    if any(is_list for _, is_list, _ in vert.props) or any(k not in _INTEGER for _, _, k in face.props):
        return None
    types = [np.int64 if kind in _INTEGER else np.float64 for _, _, kind in vert.props]  # as _values reads
    X = table(rows[: vert.count], types)
    T = table(rows[vert.count :], [np.int64] * 4)
    if X is None or T is None or np.any(T[0] != 3):
        return None
    cols = [n for n, _, _ in vert.props]
    xyz = [X[cols.index(c)].astype(np.float64) for c in "xyz"]
    return np.stack(xyz, axis=1), np.stack(T[1:], axis=1)


def _face(path: Path, lineno: int, words: list[str], e: _Element, nv: int) -> list[int]:
    """A face record's vertex indices: 3 or more, each in 0 .. nv − 1."""
    r = _values(path, lineno, words, e)
    idx = r.get("vertex_indices", r.get("vertex_index", []))
    if len(idx) < 3:
        raise MeshError(f"{path}:{lineno}: a face of {len(idx)} vertices; expected 3 or more")
    if min(idx) < 0 or max(idx) >= nv:
        raise MeshError(f"{path}:{lineno}: vertex index out of range 0..{nv - 1} in {' '.join(words)[:80]!r}")
    return idx


def _read_ascii(path: Path, raw: list[bytes], elements: list[_Element], line0: int):
    """Vertices (x, y, z) and faces (polygons fanned from their first vertex) of an ASCII PLY."""
    V: list[list[float]] = []
    F: list[list[int]] = []
    nv = sum(e.count for e in elements if e.name == "vertex")  # faces may come first
    lines = ((n, line.decode("ascii", errors="replace").split()) for n, line in enumerate(raw, line0 + 1))
    lines = ((n, w) for n, w in lines if w)
    for e in elements:
        for i in range(e.count):
            try:
                lineno, words = next(lines)
            except StopIteration:
                raise MeshError(
                    f"{path}: the file ends after {i:,} of its {e.count:,} {e.name} records (truncated?)"
                ) from None
            if e.name == "vertex":
                r = _values(path, lineno, words, e)
                V.append([r["x"][0], r["y"][0], r["z"][0]])
            elif e.name == "face":
                idx = _face(path, lineno, words, e, nv)
                F.extend([idx[0], idx[j], idx[j + 1]] for j in range(1, len(idx) - 1))
    extra = next(lines, None)
    if extra is not None:
        raise MeshError(f"{path}:{extra[0]}: more records than the header counts")
    return np.asarray(V, dtype=np.float64).reshape(-1, 3), np.asarray(F, dtype=np.int64).reshape(-1, 3)


def _read_binary(path: Path, counts: dict[str, int]) -> tuple[np.ndarray, np.ndarray]:
    import trimesh

    try:
        m = trimesh.load(path, file_type="ply", force="mesh", process=False)
    except Exception as e:  # trimesh raises what its parser raises
        raise MeshError(f"{path}: cannot read as a PLY surface ({type(e).__name__}: {e})") from None
    V = np.asarray(getattr(m, "vertices", np.zeros((0, 3))), dtype=np.float64).reshape(-1, 3)
    F = np.asarray(getattr(m, "faces", np.zeros((0, 3))), dtype=np.int64).reshape(-1, 3)
    if len(V) != counts["vertex"] or len(F) < counts["face"]:  # polygons give more triangles
        raise MeshError(
            f"{path}: read {len(V):,} vertices and {len(F):,} triangles where the header counts "
            f"{counts['vertex']:,} vertices and {counts['face']:,} faces (faces of fewer than 3 vertices?)"
        )
    return V, F


def read_ply(path) -> tuple[np.ndarray, np.ndarray]:
    """Vertices [file units] (V, 3) float64 and triangles (F, 3) int64 of a PLY file (ASCII or
    binary; polygons fanned from their first vertex). MeshError naming the file (and the line, in
    ASCII) for a malformed header or record, a file with fewer or more records than its header
    counts, or no vertex x, y, z or face vertex_indices."""
    path = Path(path)
    fmt, elements, start, line0 = _header(path)
    counts = {e.name: e.count for e in elements}
    props = {e.name: {n for n, _, _ in e.props} for e in elements}
    if not counts.get("vertex") or not counts.get("face"):
        raise MeshError(
            f"{path}: {counts.get('vertex', 0):,} vertices and {counts.get('face', 0):,} faces in its "
            "header; expected a surface (a 'vertex' and a 'face' element)"
        )
    if not {"x", "y", "z"} <= props["vertex"] or not {"vertex_indices", "vertex_index"} & props["face"]:
        raise MeshError(f"{path}: expected vertex properties x, y, z and a face list vertex_indices")
    face = next(e for e in elements if e.name == "face")
    kinds = [kind for n, is_list, kind in face.props if is_list and n in ("vertex_indices", "vertex_index")]
    if not kinds or kinds[0] not in _INTEGER:
        raise MeshError(
            f"{path}: face vertex_indices of type {(kinds or ['none'])[0]}; expected a list of integers"
        )
    if fmt == "ascii":
        with open(path, "rb") as f:
            f.seek(start)
            raw = f.read().split(b"\n")  # the lines after the header; read once
        rows = [r for r in raw if r.strip()]  # the records, one a line
        if (found := len(rows)) != sum(counts.values()):
            said = ", ".join(f"{n:,} {k}" for k, n in counts.items())
            raise MeshError(
                f"{path}: the header counts {said} records; the file holds {found:,} "
                f"({'truncated?' if found < sum(counts.values()) else 'more than it says'})"
            )
        return _ascii_in_bulk(rows, elements) or _read_ascii(path, raw, elements, line0)
    return _read_binary(path, counts)
