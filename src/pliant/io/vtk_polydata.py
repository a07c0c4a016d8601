"""Triangle surfaces from legacy VTK files of DATASET POLYDATA (the ``.vtk`` that VTK's
vtkPolyDataWriter, NiftySim's ``<VTKSurface>`` models, ITK-SNAP and 3D Slicer write), which meshio
does not read. ASCII and BINARY (big-endian), file versions 2.0 to 5.1 (5.1 stores each cell
section as OFFSETS and CONNECTIVITY arrays): POINTS, then VERTICES and LINES (skipped), POLYGONS
(fan-triangulated) and TRIANGLE_STRIPS (split into triangles, every other one reversed, so that all
keep the strip's orientation); FIELD and METADATA blocks skipped; POINT_DATA and CELL_DATA end the
read. Format: "VTK File Formats", The VTK User's Guide, 11th ed. (Kitware 2010), §19.3, and VTK 9's
vtkDataWriter for version 5.1."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import MeshError

__all__ = ["is_vtk_polydata", "read_vtk_polydata"]

# Legacy VTK data type names → numpy dtypes (BINARY data are big-endian).
_TYPES = {
    "bit": "u1",
    "unsigned_char": "u1",
    "char": "i1",
    "unsigned_short": "u2",
    "short": "i2",
    "unsigned_int": "u4",
    "int": "i4",
    "unsigned_long": "u8",
    "long": "i8",
    "vtktypeuint64": "u8",
    "vtktypeint64": "i8",
    "vtkidtype": "i8",
    "float": "f4",
    "double": "f8",
}
_CELLS = ("VERTICES", "LINES", "POLYGONS", "TRIANGLE_STRIPS")
_END = ("POINT_DATA", "CELL_DATA")


def is_vtk_polydata(path) -> bool:
    """Whether ``path`` is a legacy VTK file whose dataset is POLYDATA (a surface), by its header."""
    try:
        with open(path, "rb") as f:
            head = f.read(1024)
    except OSError:
        return False
    lines = [ln.strip() for ln in head.split(b"\n")]
    return (
        len(lines) > 4
        and lines[0].lower().startswith(b"# vtk datafile")
        and any(ln.upper().split()[:2] == [b"DATASET", b"POLYDATA"] for ln in lines[3:6] if ln)
    )


class _Reader:
    """A cursor over the file's bytes: keyword lines (text), then ASCII or binary arrays."""

    def __init__(self, data: bytes, path: Path):
        self.data, self.path, self.i, self.line = data, path, 0, 1

    def fail(self, what: str) -> MeshError:
        return MeshError(f"{self.path}:{self.line}: {what}")

    def raw_line(self) -> str | None:
        """The next line as text (None at the end of the file)."""
        if self.i >= len(self.data):
            return None
        j = self.data.find(b"\n", self.i)
        j = len(self.data) if j < 0 else j
        text = self.data[self.i : j].decode("latin-1").strip()
        self.i, self.line = j + 1, self.line + 1
        return text

    def keyword_line(self) -> list[str] | None:
        """The next non-blank line's words (None at the end of the file)."""
        while (text := self.raw_line()) is not None:
            if text:
                return text.split()
        return None

    def array(self, binary: bool, count: int, type_name: str, what: str) -> np.ndarray:
        """``count`` values of the VTK type ``type_name``."""
        dtype = _TYPES.get(type_name.lower())
        if dtype is None:
            raise self.fail(f"{what}: data type {type_name!r}; expected one of {', '.join(_TYPES)}")
        left = len(self.data) - self.i
        size = np.dtype(dtype).itemsize
        # a binary value takes its size; an ASCII one a character and a separator (the last none)
        if count < 0 or (count * size > left if binary else 2 * count > left + 1):
            raise self.fail(f"{what}: {count} values announced, the file has {left} bytes left (truncated?)")
        if binary:
            out = np.frombuffer(self.data, dtype=">" + dtype, count=count, offset=self.i)
            self.i += count * size
            if self.data[self.i : self.i + 1] == b"\n":  # the writer ends binary data with a newline
                self.i += 1
            return out.astype(dtype)
        words: list[str] = []
        while len(words) < count:
            text = self.raw_line()
            if text is None:
                raise self.fail(f"{what}: {count} values announced, the file ends after {len(words)}")
            words += text.split()
        if len(words) != count:
            raise self.fail(f"{what}: {len(words)} values on the lines of {count} announced")
        try:
            return np.array(words, dtype=float if dtype[0] == "f" else np.int64)
        except ValueError:
            raise self.fail(f"{what}: a value that is not a number") from None

    def skip_metadata(self) -> None:
        """A METADATA block: text up to the first blank line."""
        while (text := self.raw_line()) is not None and text:
            pass


def _count(reader: _Reader, word: str, what: str) -> int:
    try:
        n = int(word)
    except ValueError:
        raise reader.fail(f"{what}: count {word!r}; expected a whole number") from None
    if n < 0:
        raise reader.fail(f"{what}: count {n}; expected >= 0")
    return n


def _cells(reader: _Reader, binary: bool, words: list[str], modern: bool) -> list[np.ndarray]:
    """One cell section's cells, each an array of point indices."""
    name = words[0]
    if len(words) < 3:
        raise reader.fail(f"{name}: expected '{name} n size'")
    n, size = _count(reader, words[1], name), _count(reader, words[2], name)
    if modern:  # 5.1: OFFSETS (n values: cells + 1) and CONNECTIVITY (size values)
        arrays = {}
        for _ in range(2):
            head = reader.keyword_line()
            if not head or head[0].upper() not in ("OFFSETS", "CONNECTIVITY") or len(head) < 2:
                raise reader.fail(f"{name}: expected OFFSETS and CONNECTIVITY arrays")
            arrays[head[0].upper()] = reader.array(
                binary, n if head[0].upper() == "OFFSETS" else size, head[1], name
            )
        off, conn = arrays.get("OFFSETS"), arrays.get("CONNECTIVITY")
        if off is None or conn is None:
            raise reader.fail(f"{name}: expected OFFSETS and CONNECTIVITY arrays")
        off = off.astype(np.int64)
        if n and (off[0] != 0 or off[-1] != size or np.any(np.diff(off) < 0)):
            raise reader.fail(f"{name}: OFFSETS must rise from 0 to the CONNECTIVITY's {size} values")
        conn = conn.astype(np.int64)
        return [conn[off[k] : off[k + 1]] for k in range(max(n - 1, 0))]
    flat = reader.array(binary, size, "int", name).astype(np.int64)
    if n and size == 4 * n and np.all(flat[::4] == 3):  # all triangles: the common case, at once
        return list(flat.reshape(n, 4)[:, 1:])
    cells, k = [], 0
    for _ in range(n):
        m = int(flat[k]) if k < size else -1
        if m < 0 or k + 1 + m > size:
            raise reader.fail(f"{name}: {n} cells announced in {size} values, which hold fewer")
        cells.append(flat[k + 1 : k + 1 + m])
        k += 1 + m
    if k != size:
        raise reader.fail(f"{name}: {size} values announced, the {n} cells take {k}")
    return cells


def _triangles(name: str, cells: list[np.ndarray]) -> list[tuple[int, int, int]]:
    """POLYGONS fanned from their first point; TRIANGLE_STRIPS with every other triangle reversed."""
    out = []
    for c in cells:
        for j in range(len(c) - 2):
            if name == "POLYGONS":
                out.append((c[0], c[j + 1], c[j + 2]))
            else:
                out.append((c[j], c[j + 1], c[j + 2]) if j % 2 == 0 else (c[j + 1], c[j], c[j + 2]))
    return out


def _skip_field(reader: _Reader, binary: bool, words: list[str]) -> None:
    """A FIELD block: ``FIELD name n`` then n arrays ``name components tuples type`` and values."""
    n = _count(reader, words[2] if len(words) > 2 else "", "FIELD")
    for _ in range(n):
        head = reader.keyword_line()
        while head and head[0].upper() == "METADATA":
            reader.skip_metadata()
            head = reader.keyword_line()
        if not head or len(head) < 4:
            raise reader.fail("FIELD: expected an array 'name components tuples type'")
        comps, tuples = _count(reader, head[1], "FIELD"), _count(reader, head[2], "FIELD")
        reader.array(binary, comps * tuples, head[3], f"FIELD array {head[0]}")


def read_vtk_polydata(path) -> tuple[np.ndarray, np.ndarray]:
    """Vertices [file units] (V, 3) float64 and triangles (F, 3) int64 of a legacy VTK POLYDATA file.
    MeshError naming the file and line for anything malformed, truncated or not POLYDATA."""
    path = Path(path)
    try:
        data = path.read_bytes()
    except OSError as e:
        raise MeshError(f"{path}: cannot read ({e.strerror or e})") from None
    r = _Reader(data, path)
    head = r.raw_line() or ""
    if not head.lower().startswith("# vtk datafile"):
        raise r.fail("not a legacy VTK file (expected '# vtk DataFile Version ...')")
    try:
        modern = float(head.split()[-1]) >= 5.0  # 5.x: cells as OFFSETS + CONNECTIVITY
    except ValueError:
        raise r.fail(f"file version {head.split()[-1]!r}; expected a number such as 3.0 or 5.1") from None
    r.raw_line()  # title
    mode = (r.keyword_line() or [""])[0].upper()
    if mode not in ("ASCII", "BINARY"):
        raise r.fail(f"data mode {mode!r}; expected ASCII or BINARY")
    binary = mode == "BINARY"
    dataset = r.keyword_line() or []
    if [w.upper() for w in dataset[:2]] != ["DATASET", "POLYDATA"]:
        raise r.fail(f"dataset {' '.join(dataset[1:2]) or 'none'}; expected DATASET POLYDATA (a surface)")
    points, tris = None, []
    while (words := r.keyword_line()) is not None:
        key = words[0].upper()
        if key in _END:
            break
        if key == "METADATA":
            r.skip_metadata()
        elif key == "FIELD":
            _skip_field(r, binary, words)
        elif key == "POINTS":
            if len(words) < 3:
                raise r.fail("POINTS: expected 'POINTS n type'")
            n = _count(r, words[1], "POINTS")
            points = r.array(binary, 3 * n, words[2], "POINTS").astype(float).reshape(n, 3)
        elif key in _CELLS:
            cells = _cells(r, binary, words, modern)
            if key in ("POLYGONS", "TRIANGLE_STRIPS"):
                tris += _triangles(key, cells)
        else:
            raise r.fail(f"unknown section {words[0]!r} in a POLYDATA file")
    if points is None:
        raise MeshError(f"{path}: no POINTS section")
    if not tris:
        raise MeshError(f"{path}: no POLYGONS or TRIANGLE_STRIPS (a surface needs triangles)")
    return points, np.asarray(tris, dtype=np.int64).reshape(-1, 3)
