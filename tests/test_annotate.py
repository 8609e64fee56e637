"""The annotated frame's overlays keep out of the picture's way."""

from __future__ import annotations

import numpy as np
import pytest

from motiondetect.detection.detector import FrameResult
from motiondetect.io.annotate import annotate


@pytest.mark.parametrize("size", [(232, 152), (352, 288), (854, 480)])
def test_the_legend_is_one_line_along_the_bottom(size):
    """Three stacked entries covered a fifth to a third of the frame's height
    at its left edge, over whatever moved there; one line covers under an
    eighth."""
    w, h = size
    grey = np.full((h, w, 3), 128, np.uint8)
    empty = FrameResult(0, 0.0, [], np.zeros((64, 64), bool), None, None, None)
    drawn = np.any(annotate(grey, empty, (w, h)) != 128, axis=2)
    below_label = drawn[h // 4 :]  # the frame's label is on the top line
    rows = np.nonzero(below_label.any(axis=1))[0] + h // 4
    assert rows.size and rows.max() >= h - 8  # along the bottom edge
    assert rows.max() - rows.min() < h / 8
    # The three entries side by side, within the frame.
    assert np.nonzero(drawn[rows.min() :].any(axis=0))[0].max() < w - 1
