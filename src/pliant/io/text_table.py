"""Rows of numbers parsed in bulk: the common large text file (OFF, ASCII PLY) read with numpy,
each row checked to hold its words alone, so that a row short of a value and another with one too
many are not taken for two good rows. The readers fall back to their line-by-line parsers (which
name the line at fault) wherever this gives None."""

from __future__ import annotations

import numpy as np

__all__ = ["table"]

_SEP = b"\0"  # not white space: a word of its own between rows (a row that holds one is refused)


def table(rows: list[bytes], dtypes: list) -> list[np.ndarray] | None:
    """The rows (lines, without their newline) as columns (len(rows),), one for each of ``dtypes``,
    or None when a row has other than len(dtypes) words or a word is not a number of its column's
    type (numpy's parse: for integers, beyond int64 is None too)."""
    n, width = len(rows), len(dtypes)
    if not n:
        return [np.zeros(0, dtype=dt) for dt in dtypes]
    words = (b" " + _SEP + b" ").join(rows).split()
    step = width + 1
    if len(words) != step * n - 1 or words[width::step].count(_SEP) != n - 1 or words.count(_SEP) != n - 1:
        return None
    try:
        return [np.array(words[k::step], dtype=dt) for k, dt in enumerate(dtypes)]
    except (ValueError, OverflowError):
        return None
