"""Each object outlined by the image change, not by the smeared flags: known answers."""

import cv2
import numpy as np
import pytest

from motiondetect.detection.objects import TrackConfig, group_objects
from motiondetect.detection.shaping import CHANGE_BOX, outlined

H, W = 120, 160
CLOSE = np.ones((19, 19), np.uint8)


def _disk(radius: int, centre=(80, 60)) -> np.ndarray:
    mask = np.zeros((H, W), np.uint8)
    cv2.circle(mask, centre, radius, 1, thickness=-1)
    return mask


def _reach(mask: np.ndarray, px: int) -> np.ndarray:
    return cv2.dilate(mask, np.ones((2 * px + 1,) * 2, np.uint8)) > 0


def _object_mask(flagged: np.ndarray, changed: np.ndarray, **fields) -> np.ndarray:
    velocity = np.zeros((H, W, 2), np.float32)
    (obj,) = group_objects(flagged > 0, velocity, TrackConfig(**fields), changed > 0)
    return obj.mask


@pytest.mark.parametrize("outline_px", [0, 1])
def test_the_outline_follows_the_change_not_the_flow_smear(outline_px):
    """A mover of radius 20 changed the image; dense flow flagged 6 px all round
    it. The gate's reach (2 px) joins the mover; its outline lies within
    ``outline_px`` of the change, and none of the mover is lost."""
    mover, flagged = _disk(20), _disk(26)
    mask = _object_mask(flagged, mover, outline_px=outline_px)
    assert mask[mover > 0].all()
    assert not (mask & ~_reach(mover, outline_px)).any()
    wide = _object_mask(flagged, mover, outline_px=2)  # off: the gate's band stays
    assert (wide & ~_reach(mover, 1)).sum() > 100
    assert wide.sum() > mask.sum()


def test_an_outline_keeps_the_mover_and_drops_the_crumbs_the_cut_leaves():
    own = np.zeros((H, W), np.uint8)
    own[30:90, 40:120] = 1
    near = own.copy()
    near[30:33, 40:120] = 0  # a 3-px band off the top...
    near[31, 60] = near[31, 61] = 1  # ...but for a crumb smaller than the change box
    assert 2 < CHANGE_BOX**2  # the crumb is smaller than the change map can outline
    out = outlined(own, near.copy(), CLOSE)
    assert out.sum() == own[33:90].sum()


def test_an_outline_that_cuts_the_mover_in_two_or_most_of_it_away_keeps_it_whole():
    """A followed, plain mover changes the image only at its two ends: the cut
    would go through it, not round it, so the object keeps all its pixels."""
    own = np.zeros((H, W), np.uint8)
    own[40:80, 20:140] = 1
    ends = np.zeros_like(own)
    ends[40:80, 20:60] = ends[40:80, 100:140] = 1  # two thirds kept, 40 px apart
    assert np.array_equal(outlined(own, ends.copy(), CLOSE), own)
    one_end = np.zeros_like(own)
    one_end[40:80, 20:60] = 1  # one part, but only a third of the mover
    assert np.array_equal(outlined(own, one_end.copy(), CLOSE), own)
    close_ends = ends.copy()
    close_ends[40:80, 60:85] = 1  # a 15-px gap the closing bridges: one part
    assert outlined(own, close_ends.copy(), CLOSE).sum() == close_ends.sum()


def test_outline_px_may_not_exceed_the_gates_reach():
    with pytest.raises(ValueError, match="outline_px must be at most support_px"):
        TrackConfig(support_px=1, outline_px=2)
