"""Validation of scene tables: unknown keys are errors; every error names the file, the key path,
the line where it can be found, and what was expected."""

from __future__ import annotations

import contextlib
import math
import re
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..errors import FileError, InputError

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib


class SceneError(FileError):
    """A scene file that does not meet the schema. ``file``, ``key`` and ``line`` name the culprit."""


_WIDE_BOMS = {  # the byte-order marks of encodings TOML does not allow (TOML is UTF-8)
    b"\xff\xfe\x00\x00": "UTF-32",
    b"\x00\x00\xfe\xff": "UTF-32",
    b"\xff\xfe": "UTF-16",
    b"\xfe\xff": "UTF-16",
}


def read_toml(path: Path, what: str = "scene") -> tuple[str, dict]:
    """A TOML file's text and its tables; SceneError for a missing, unreadable, wrongly encoded or
    invalid file. A UTF-8 byte-order mark (as Windows editors write) is skipped; a UTF-16 or
    UTF-32 file is named as such (TOML files are UTF-8)."""
    from ..io.files import MISSING, file_problem

    problem = file_problem(path)
    if problem:
        raise SceneError(f"no such {what} file" if problem == MISSING else problem, str(path))
    try:
        raw = path.read_bytes()
    except OSError as e:
        raise SceneError(f"cannot read the {what} file: {e.strerror or e}", str(path)) from None
    wide = next((name for bom, name in _WIDE_BOMS.items() if raw.startswith(bom)), None)
    if wide:
        raise SceneError(f"the file is {wide}-encoded; expected UTF-8 (save it as UTF-8)", str(path))
    if b"\x00" in raw:  # UTF-16 without its mark, or not text at all
        raise SceneError("the file holds NUL bytes (UTF-16, or not text); expected UTF-8 text", str(path))
    text = raw.removeprefix(b"\xef\xbb\xbf").decode("utf-8", errors="replace")
    try:
        return text, tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise SceneError(f"not valid TOML: {e}", str(path)) from None
    except RecursionError:
        raise SceneError(f"not a usable {what}: tables or arrays nested too deeply", str(path)) from None


@dataclass
class Ctx:
    """Where we are: the file name and its text (for line numbers)."""

    file: str
    text: str

    def line_of(self, key: str) -> int | None:
        """Line of a key path such as 'material[1].E' or 'solver.dt' (best effort)."""
        parts = re.findall(r"([A-Za-z_][\w-]*)(?:\[(\d+)\])?", key)
        if not parts:
            return None
        lines = self.text.splitlines()
        header, idx = parts[0]
        leaf = parts[-1][0] if len(parts) > 1 else None
        count, start = -1, None
        want = int(idx) if idx else 0
        for i, ln in enumerate(lines):
            s = ln.strip()
            if re.match(rf"^\[\[?\s*{re.escape(header)}\s*\]\]?", s):
                count += 1
                if count == want:
                    start = i
                    if leaf is None:
                        return i + 1
                    continue
            if start is not None and i > start:
                if (
                    s.startswith("[")
                    and not s.startswith("[[" + header)
                    and re.match(r"^\[", s)
                    and not re.match(rf"^\[{re.escape(header)}\.", s)
                ):
                    break
                if leaf and re.match(rf"^{re.escape(leaf)}\s*=", s):
                    return i + 1
                if leaf and re.search(rf"[{{,]\s*{re.escape(leaf)}\s*=", s):
                    return i + 1
        if start is not None:
            return start + 1
        for i, ln in enumerate(lines):  # top-level key
            if re.match(rf"^\s*{re.escape(header)}\s*=", ln):
                return i + 1
        return None

    def where(self, key: str) -> str:
        """``file:line`` of a key path, or the file alone where its line is not found."""
        line = self.line_of(key)
        return self.file if line is None else f"{self.file}:{line}"

    def error(self, key: str, message: str) -> SceneError:
        return SceneError(message, self.file, key, self.line_of(key))

    @contextlib.contextmanager
    def under(self, key: str):
        """Turn an InputError raised inside (by a builder or material) into a SceneError naming
        this file, key and line."""
        try:
            yield
        except FileError:
            raise
        except InputError as e:
            raise self.error(key, str(e)) from None


_TYPES = {
    "number": (int, float),
    "int": (int,),
    "str": (str,),
    "bool": (bool,),
    "table": (dict,),
    "list": (list,),
}


def key_path(path: str, key: str) -> str:
    """'solver' + 'dt' -> 'solver.dt'; keys that are not bare TOML keys are quoted ('solver.""')."""
    k = key if re.fullmatch(r"[A-Za-z0-9_-]+", key) else '"' + key.replace('"', '\\"')[:40] + '"'
    return f"{path}.{k}" if path else k


def check_keys(
    ctx: Ctx, table: Any, path: str, allowed: dict[str, str], required: tuple[str, ...] = ()
) -> dict:
    """Check that ``table`` is a table whose keys are among ``allowed`` (key → type name; '|' for
    alternatives; after a space, the form the message shows: "list [[x0, y0, z0], [x1, y1, z1]]")
    and that ``required`` keys are present. Returns the table."""
    if not isinstance(table, dict):
        raise ctx.error(path, f"expected a table, got {type(table).__name__}")
    for k, v in table.items():
        kp = key_path(path, k)
        if k not in allowed:
            raise ctx.error(kp, f"unknown key {_short(k, 40)}; expected one of: {', '.join(sorted(allowed))}")
        spec, _, form = allowed[k].partition(" ")
        kinds = spec.split("|")
        ok = False
        for kind in kinds:
            types = _TYPES.get(kind, ())
            if isinstance(v, types) and not (kind in ("number", "int") and isinstance(v, bool)):
                ok = True
        if not ok:
            raise ctx.error(
                kp, f"{k} = {_short(v)}: expected {' or '.join(kinds)}{' ' + form if form else ''}"
            )
        if isinstance(v, float) and not math.isfinite(v):
            raise ctx.error(kp, f"{k} = {v!r}: expected a finite number")
    for k in required:
        if k not in table:
            raise ctx.error(path, f"missing key {k!r}")
    return table


def _short(v, limit: int = 80) -> str:
    """repr of a value, cut to ``limit`` characters (hostile files hold megabyte strings)."""
    r = repr(v)
    return r if len(r) <= limit else r[:limit] + f"... ({len(r)} characters)"


def vector(ctx: Ctx, value, path: str, n: int = 3) -> list[float]:
    if not (
        isinstance(value, list)
        and len(value) == n
        and all(isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x) for x in value)
    ):
        raise ctx.error(path, f"{_short(value)}: expected a list of {n} finite numbers")
    return [float(x) for x in value]
