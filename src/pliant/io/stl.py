"""Triangle surfaces from STL files, ASCII and binary. meshio's ASCII reader took every line's last
three words without looking at its keyword, and a blank line (which many writers leave before
``endsolid``) or a facet of four vertices broke it ("cannot reshape array of size 144 into shape
(0)"); a truncated binary file came back as "UnicodeDecodeError". Binary layout: an 80-byte free
header, the facet count (uint32), then 50 bytes a facet (normal and three vertices as 12 float32,
an attribute uint16), little-endian; its size is 84 + 50 × count. ASCII grammar (3D Systems,
"StereoLithography Interface Specification", 1988, §6.5): ``solid NAME``, then facets of ``facet
normal ni nj nk`` / ``outer loop`` / ``vertex x y z`` ... / ``endloop`` / ``endfacet``, then
``endsolid NAME``; several solids may follow one another. Keywords in any case, blank lines and any
spacing accepted; a polygon of more than three vertices is fanned from its first. Vertices at
exactly the same position are one vertex (STL stores each facet's corners on their own)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from ..errors import MeshError
from ..mesh.topology import join_coincident

__all__ = ["is_ascii_stl", "join_coincident", "read_ascii_stl", "read_binary_stl", "read_stl"]


def is_ascii_stl(path) -> bool:
    """Whether ``path`` is an ASCII STL: it begins with ``solid``, its size is not that of a binary
    STL (84 bytes + 50 a facet, the count at byte 80), whose free header may also begin with
    ``solid``, and its first kilobyte is text (no NUL byte, which binary facets hold)."""
    path = Path(path)
    with open(path, "rb") as f:
        head = f.read(1024)
    if not head.lstrip().lower().startswith(b"solid"):
        return False
    if len(head) >= 84 and path.stat().st_size == 84 + 50 * int.from_bytes(head[80:84], "little"):
        return False
    return b"\0" not in head


_FACET = np.dtype([("normal", "<f4", 3), ("v", "<f4", (3, 3)), ("attribute", "<u2")])  # 50 bytes


def read_binary_stl(path) -> tuple[np.ndarray, np.ndarray]:
    """Vertices [file units] (V, 3) float64 and triangles (F, 3) int64 of a binary STL file,
    coincident corners joined. MeshError naming the file when its size is not 84 bytes + 50 for
    each facet its header counts (truncated, or more data)."""
    path = Path(path)
    size = path.stat().st_size
    with open(path, "rb") as f:
        head = f.read(84)
        if len(head) < 84:
            raise MeshError(f"{path}: {size} bytes: too short for a binary STL (84-byte header) or ASCII STL")
        n = int.from_bytes(head[80:84], "little")
        if size != 84 + 50 * n:
            raise MeshError(
                f"{path}: a binary STL whose header counts {n:,} facets is {84 + 50 * n:,} bytes; this one "
                f"is {size:,} ({'truncated?' if size < 84 + 50 * n else 'more data than facets'})"
            )
        facets = np.fromfile(f, dtype=_FACET, count=n)
    V = facets["v"].astype(np.float64).reshape(-1, 3)
    return join_coincident(V, np.arange(len(V), dtype=np.int64).reshape(-1, 3))


def read_stl(path) -> tuple[np.ndarray, np.ndarray]:
    """An STL file, ASCII or binary (is_ascii_stl): vertices (V, 3) float64, triangles (F, 3)."""
    return read_ascii_stl(path) if is_ascii_stl(path) else read_binary_stl(path)


def _vertex(path: Path, lineno: int, words: list[str]) -> list[float]:
    try:
        xyz = [float(w) for w in words[1:]]
    except ValueError:
        xyz = []
    if len(xyz) != 3:
        raise MeshError(f"{path}:{lineno}: expected 'vertex x y z', got {' '.join(words)[:80]!r}")
    return xyz


# A triangle facet's 21 words: keyword positions (numbers at 2-4, 8-10, 12-14, 16-18)
_FACET_WORDS = {
    0: b"facet",
    1: b"normal",
    5: b"outer",
    6: b"loop",
    7: b"vertex",
    11: b"vertex",
    15: b"vertex",
}
_FACET_WORDS |= {19: b"endloop", 20: b"endfacet"}
_FACET_LINES = (b"facet", b"outer", b"vertex", b"vertex", b"vertex", b"endloop", b"endfacet")  # first words


def _facet_lines(body: bytes) -> int:
    """The number of facets n when the lines are those the line-by-line reader sees of n triangle
    facets: 7 n lines that are not blank, whose first words are those of _FACET_LINES in turn (one
    regular expression, a literal newline first, which the engine searches for fast); else 0. With
    the 21 words of each facet at their places, each line then runs from its keyword to the next:
    a vertex line holds its three numbers alone."""
    first = re.findall(rb"\n[ \t\r\v\f]*(\S*)", body)
    if b"" in first:
        first = [w for w in first if w]  # blank lines
    n = len(first) // 7
    if len(first) != 7 * n or any(first[k::7].count(key) != n for k, key in enumerate(_FACET_LINES)):
        return 0
    return n


def _ascii_corners_in_bulk(path: Path) -> np.ndarray | None:
    """The corners (3 F, 3) of the common file, read in bulk: a first line ``solid [name]``, then
    triangle facets of seven lines each, their keywords in lower case, then one line ``endsolid
    [name]``; each facet's 21 words checked at their places and its lines where the line-by-line
    reader looks, so that the file reads as that reader reads it. None for anything else, which the
    line-by-line reader then reads or refuses naming its line. 1.3 M facets (390 MB), on a loaded
    machine: 18–23 s line by line, 11–13 s in bulk, of which the check of the lines takes 3–4 s."""
    data = path.read_bytes()
    head = data.find(b"\n")  # the end of the solid's line
    stop = data.find(b"\n", data.rfind(b"endfacet"))  # the end of the last facet's line
    if head < 0 or stop <= head or data[:head].split()[:1] != [b"solid"]:
        return None
    tail = [ln.split() for ln in data[stop + 1 :].split(b"\n") if ln.strip()]
    if len(tail) != 1 or tail[0][0] != b"endsolid":
        return None
    body = data[head:stop]
    del data
    n = _facet_lines(body)
    words = body.split() if n else []
    if not n or len(words) != 21 * n or any(words[k::21].count(key) != n for k, key in _FACET_WORDS.items()):
        return None
    try:
        xyz = [np.array(words[k::21], dtype=np.float64) for k in (8, 9, 10, 12, 13, 14, 16, 17, 18)]
    except ValueError:
        return None
    return np.stack(xyz, axis=1).reshape(-1, 3)


def read_ascii_stl(path) -> tuple[np.ndarray, np.ndarray]:
    """Vertices [file units] (V, 3) float64 and triangles (F, 3) int64 of an ASCII STL file,
    coincident corners joined. MeshError naming the file and line for an unknown keyword, a bad
    vertex, a facet of fewer than three vertices, or a file that ends inside a facet."""
    path = Path(path)
    bulk = _ascii_corners_in_bulk(path)
    if bulk is not None and len(bulk):
        return join_coincident(bulk, np.arange(len(bulk), dtype=np.int64).reshape(-1, 3))
    corners: list[list[float]] = []  # every facet's corners, in order
    sizes: list[int] = []  # vertices per facet
    facet_line, loop = 0, []  # the open facet's first line (0: none) and its vertices
    with open(path, encoding="utf-8", errors="replace") as f:
        for lineno, line in enumerate(f, 1):
            words = line.split()
            if not words:
                continue
            key = words[0].lower()
            if key == "vertex":
                if not facet_line:
                    raise MeshError(f"{path}:{lineno}: vertex outside a facet")
                loop.append(_vertex(path, lineno, words))
            elif key == "facet":
                if facet_line:
                    raise MeshError(f"{path}:{lineno}: facet inside the facet of line {facet_line}")
                facet_line, loop = lineno, []
            elif key == "endfacet":
                if len(loop) < 3:
                    raise MeshError(
                        f"{path}:{facet_line}: facet with {len(loop)} vertices; expected 3 (or a polygon)"
                    )
                corners.extend(loop)
                sizes.append(len(loop))
                facet_line = 0
            elif key not in ("solid", "endsolid", "outer", "endloop"):
                raise MeshError(
                    f"{path}:{lineno}: unexpected {words[0][:40]!r} in an ASCII STL; expected solid, "
                    "facet normal, outer loop, vertex, endloop, endfacet or endsolid"
                )
    if facet_line:
        raise MeshError(f"{path}: the file ends inside the facet of line {facet_line} (truncated?)")
    V = np.asarray(corners, dtype=float).reshape(-1, 3)
    n = np.asarray(sizes, dtype=np.int64) - 2  # triangles per facet, fanned from its first corner
    facet = np.repeat(np.arange(len(n)), n)
    first = (np.cumsum(sizes) - sizes)[facet]  # the facet's first corner
    k = np.arange(len(facet)) - (np.cumsum(n) - n)[facet] + 1  # 1 .. size − 2 within the facet
    F = np.stack([first, first + k, first + k + 1], axis=1).astype(np.int64)
    if not len(F):
        return V, F.reshape(-1, 3)
    return join_coincident(V, F)
