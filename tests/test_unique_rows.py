"""pliant.mesh.topology.unique_rows, the mesh pipeline's row deduplication, against numpy's own
np.unique(axis=0): the same rows in the same order, the same inverse and counts, for edges, faces
and element rows, with values that fit its one-key-a-row sort and values that do not."""

import numpy as np
import pytest

from pliant.mesh.topology import unique_rows


@pytest.mark.parametrize(
    "shape, high",
    [((50_000, 2), 3_000), ((40_000, 3), 500), ((30_000, 4), 60), ((1000, 3), 2**40), ((7, 2), 1)],
    ids=["edges", "faces", "tets", "beyond-one-key", "tiny"],
)
def test_unique_rows_is_numpys(shape, high):
    rows = np.random.default_rng(7).integers(0, high, size=shape)
    want = np.unique(rows, axis=0, return_inverse=True, return_counts=True)
    got = unique_rows(rows, return_inverse=True, return_counts=True)
    assert np.array_equal(got[0], want[0])
    assert np.array_equal(got[1], want[1].reshape(-1)) and got[1].shape == (shape[0],)
    assert np.array_equal(got[2], want[2])
    assert np.array_equal(unique_rows(rows), want[0])
    assert np.array_equal(rows, got[0][got[1]])  # the inverse rebuilds the rows


def test_unique_rows_of_nothing():
    out, inv, count = unique_rows(np.zeros((0, 3), np.int64), return_inverse=True, return_counts=True)
    assert out.shape == (0, 3) and inv.shape == (0,) and count.shape == (0,)
