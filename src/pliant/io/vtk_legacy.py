"""The legacy VTK file format's reader core ("VTK File Formats", The VTK User's Guide, 11th ed.,
Kitware 2010, §19.3; VTK 9's vtkDataWriter for version 5.1): the header, keyword lines, ASCII and
BINARY (big-endian) arrays, cell sections (counts-prefixed lists, or 5.1's OFFSETS and
CONNECTIVITY), and the blocks a reader of geometry skips (FIELD, METADATA, point and cell
attributes). Used by pliant.io.vtk_polydata (surfaces) and pliant.io.vtk_grid (tetrahedra)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import MeshError

__all__ = ["TYPES", "Reader", "cells", "count", "dataset_of", "open_legacy", "points", "skip_field"]

# Legacy VTK data type names → numpy dtypes (BINARY data are big-endian).
TYPES = {
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


class Reader:
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
        dtype = TYPES.get(type_name.lower())
        if dtype is None:
            raise self.fail(f"{what}: data type {type_name!r}; expected one of {', '.join(TYPES)}")
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
            with np.errstate(invalid="ignore"):  # a signalling NaN's bits: NaN, refused by the callers
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
        except (ValueError, OverflowError):  # OverflowError: a whole number beyond int64
            raise self.fail(f"{what}: a value that is not a number") from None

    def skip_metadata(self) -> None:
        """A METADATA block: text up to the first blank line."""
        while (text := self.raw_line()) is not None and text:
            pass


def count(reader: Reader, word: str, what: str) -> int:
    try:
        n = int(word)
    except ValueError:
        raise reader.fail(f"{what}: count {word!r}; expected a whole number") from None
    if n < 0:
        raise reader.fail(f"{what}: count {n}; expected >= 0")
    return n


def cells(reader: Reader, binary: bool, words: list[str], modern: bool) -> list[np.ndarray]:
    """One cell section's cells, each an array of point indices."""
    name = words[0]
    if len(words) < 3:
        raise reader.fail(f"{name}: expected '{name} n size'")
    n, size = count(reader, words[1], name), count(reader, words[2], name)
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


def skip_field(reader: Reader, binary: bool, words: list[str]) -> None:
    """A FIELD block: ``FIELD name n`` then n arrays ``name components tuples type`` and values."""
    n = count(reader, words[2] if len(words) > 2 else "", "FIELD")
    for _ in range(n):
        head = reader.keyword_line()
        while head and head[0].upper() == "METADATA":
            reader.skip_metadata()
            head = reader.keyword_line()
        if not head or len(head) < 4:
            raise reader.fail("FIELD: expected an array 'name components tuples type'")
        comps, tuples = count(reader, head[1], "FIELD"), count(reader, head[2], "FIELD")
        reader.array(binary, comps * tuples, head[3], f"FIELD array {head[0]}")


def points(reader: Reader, binary: bool, words: list[str]) -> np.ndarray:
    """A POINTS section ``POINTS n type``: its n points [file units] as (n, 3) float64."""
    if len(words) < 3:
        raise reader.fail("POINTS: expected 'POINTS n type'")
    n = count(reader, words[1], "POINTS")
    with np.errstate(invalid="ignore"):  # as in Reader.array
        return reader.array(binary, 3 * n, words[2], "POINTS").astype(float).reshape(n, 3)


def dataset_of(path) -> str | None:
    """The DATASET of a legacy VTK file by its header (POLYDATA, UNSTRUCTURED_GRID...), upper case;
    None for another file or one that cannot be read."""
    from .files import file_problem

    if file_problem(path):  # a named pipe would wait here for a writer
        return None
    try:
        with open(path, "rb") as f:
            head = f.read(1024)
    except OSError:
        return None
    lines = [ln.strip() for ln in head.split(b"\n")]
    if len(lines) < 5 or not lines[0].lower().startswith(b"# vtk datafile"):
        return None
    for ln in lines[3:6]:
        words = ln.upper().split()
        if words[:1] == [b"DATASET"] and len(words) > 1:
            return words[1].decode("latin-1")
    return None


def open_legacy(path, dataset: str, what: str) -> tuple[Reader, bool, bool]:
    """A Reader past the header of a legacy VTK file of DATASET ``dataset`` (what: the dataset's
    meaning, for the error): (reader, binary, modern: version 5.x, cells as OFFSETS and
    CONNECTIVITY). MeshError naming the file and line when the header is not that."""
    path = Path(path)
    try:
        data = path.read_bytes()
    except OSError as e:
        raise MeshError(f"{path}: cannot read ({e.strerror or e})") from None
    r = Reader(data, path)
    head = r.raw_line() or ""
    if not head.lower().startswith("# vtk datafile"):
        raise r.fail("not a legacy VTK file (expected '# vtk DataFile Version ...')")
    try:
        modern = float(head.split()[-1]) >= 5.0
    except ValueError:
        raise r.fail(f"file version {head.split()[-1]!r}; expected a number such as 3.0 or 5.1") from None
    r.raw_line()  # title
    mode = (r.keyword_line() or [""])[0].upper()
    if mode not in ("ASCII", "BINARY"):
        raise r.fail(f"data mode {mode!r}; expected ASCII or BINARY")
    words = r.keyword_line() or []
    if [w.upper() for w in words[:2]] != ["DATASET", dataset]:
        raise r.fail(f"dataset {' '.join(words[1:2]) or 'none'}; expected DATASET {dataset} ({what})")
    return r, mode == "BINARY", modern
