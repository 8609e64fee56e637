"""Mask helpers of ``detection/regions.py`` against NumPy's own answers."""

from __future__ import annotations

import numpy as np
import pytest

from motiondetect.detection.regions import true_pixels


@pytest.mark.parametrize("density", [0.0, 0.002, 0.3, 1.0])
def test_true_pixels_are_nonzeros_rows_and_columns_in_its_order(density):
    rng = np.random.default_rng(7)
    mask = rng.random((262, 320)) < density
    for view in (mask, mask[::4, ::4], mask[10:200, 33:301], mask[:, ::-1]):
        rows, cols = true_pixels(view)
        want_rows, want_cols = np.nonzero(view)
        assert rows.dtype == want_rows.dtype and cols.dtype == want_cols.dtype
        np.testing.assert_array_equal(rows, want_rows)
        np.testing.assert_array_equal(cols, want_cols)
        assert view[rows, cols].all() and len(rows) == np.count_nonzero(view)
