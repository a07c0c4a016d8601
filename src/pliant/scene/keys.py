"""Dotted key paths into a scene's tables, for sweeps and overrides: ``solver.damping``,
``material[0].E``, ``material.liver.E`` (an array of tables entry by its ``name``),
``tool.probe.keyframes[1].position[2]``, ``mesh.scale``. The notation is the one scene errors
already use for their culprits (``material[1].E``), with names allowed in place of indices."""

from __future__ import annotations

import copy
import re
from typing import Any

from .schema import SceneError

__all__ = ["set_key", "get_key", "apply_overrides"]


class _KeyProblem(Exception):
    """What is wrong with a key path; the public functions add the file and the key."""


_SEGMENT = re.compile(r"([A-Za-z_][\w-]*)((?:\[\d+\])*)")


def _parse_key(key: str) -> list[str | int]:
    """``'tool.probe.keyframes[1].position[2]'`` → ``['tool', 'probe', 'keyframes', 1, 'position',
    2]``. Raises _KeyProblem for a malformed path."""
    if not isinstance(key, str) or not key:
        raise _KeyProblem("expected a dotted key path such as 'material[0].E'")
    parts: list[str | int] = []
    for seg in key.split("."):
        m = _SEGMENT.fullmatch(seg)
        if not m:
            raise _KeyProblem(
                f"segment {seg!r} is not a name with optional [index]es; "
                "expected a path such as 'tool.probe.keyframes[1].position[2]'"
            )
        parts.append(m.group(1))
        parts.extend(int(i) for i in re.findall(r"\[(\d+)\]", m.group(2)))
    return parts


def _child(node: Any, part: str | int, key: str, done: str) -> Any:
    """The entry ``part`` of ``node``: a table's key, a list's index, or the entry of an array of
    tables whose ``name`` is ``part``."""
    where = done or "the scene"
    if isinstance(part, int):
        if not isinstance(node, list):
            raise _KeyProblem(f"{where} is not an array; [{part}] does not apply")
        if part >= len(node):
            raise _KeyProblem(f"{where} has {len(node)} entries; [{part}] is out of range")
        return node[part]
    if isinstance(node, dict):
        if part not in node:
            raise _KeyProblem(f"{where} has no key {part!r} (it has {', '.join(map(repr, node)) or 'none'})")
        return node[part]
    if isinstance(node, list):
        named = [i for i, e in enumerate(node) if isinstance(e, dict) and e.get("name") == part]
        if len(named) != 1:
            names = [e.get("name") for e in node if isinstance(e, dict) and "name" in e]
            raise _KeyProblem(
                f"{'no' if not named else 'more than one'} entry of {where} "
                f"is named {part!r} (names: {', '.join(map(repr, names)) or 'none'})"
            )
        return node[named[0]]
    raise _KeyProblem(f"{where} is a value, not a table; {part!r} does not apply")


def _resolve(data: dict, key: str) -> tuple[Any, str | int]:
    """The container holding the key's last entry, and that entry's index or name (resolved)."""
    parts = _parse_key(key)
    node: Any = data
    done = ""
    for part in parts[:-1]:
        node = _child(node, part, key, done)
        done += f"[{part}]" if isinstance(part, int) else (f".{part}" if done else part)
    last = parts[-1]
    if isinstance(last, str) and isinstance(node, list):  # an entry by its name
        _child(node, last, key, done)
        last = next(i for i, e in enumerate(node) if isinstance(e, dict) and e.get("name") == last)
    elif isinstance(last, int) or not isinstance(node, dict):
        _child(node, last, key, done)
    return node, last


def get_key(data: dict, key: str, source: str = "") -> Any:
    """The value at ``key``; SceneError (naming ``source``, the key and the missing part)."""
    try:
        node, last = _resolve(data, key)
        if isinstance(node, dict) and last not in node:
            raise _KeyProblem(f"no key {last!r} there")
    except _KeyProblem as e:
        raise SceneError(str(e), source, key) from None
    return node[last]


def set_key(data: dict, key: str, value: Any, source: str = "") -> None:
    """Set ``key`` to ``value`` in place. A table's key may be new (the scene's validation then
    judges it); an index must exist; an entry named in an array of tables must exist."""
    try:
        node, last = _resolve(data, key)
    except _KeyProblem as e:
        raise SceneError(str(e), source, key) from None
    node[last] = value


def apply_overrides(data: dict, overrides: dict[str, Any] | None, source: str = "") -> dict:
    """A deep copy of ``data`` with each ``key → value`` of ``overrides`` set, in order."""
    out = copy.deepcopy(data)
    for key, value in (overrides or {}).items():
        set_key(out, key, value, source)
    return out
