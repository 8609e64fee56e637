"""Each object's rim judged by its look: known answers on drawn scenes."""

import cv2
import numpy as np

from motiondetect.detection.objects import TrackConfig, group_objects
from motiondetect.detection.shaping import rim_by_look

H, W = 120, 160
RIM = TrackConfig().support_px


def _disk(radius: int, centre=(80, 60)) -> np.ndarray:
    mask = np.zeros((H, W), np.uint8)
    cv2.circle(mask, centre, radius, 1, thickness=-1)
    return mask


def _scene(mover: np.ndarray, seed: int = 0) -> np.ndarray:
    """A bright mover (grey 190-215) on dark texture (30-100)."""
    rng = np.random.default_rng(seed)
    grey = rng.integers(30, 100, (H, W)).astype(np.uint8)
    grey[mover > 0] = rng.integers(190, 215, int(mover.sum()))
    return grey


def _grown(mask: np.ndarray, px: int) -> np.ndarray:
    return cv2.dilate(mask, np.ones((2 * px + 1,) * 2, np.uint8))


def test_a_band_of_background_round_the_mover_is_taken_off():
    """The flags reach 2 px past a bright disc on dark texture: the rim's
    background pixels look like the ring round the mask, the disc's like
    its core, so the disc comes back exactly."""
    mover = _disk(20)
    out = rim_by_look(_grown(mover, RIM), _scene(mover), RIM)
    assert np.array_equal(out, mover)


def test_grouped_objects_lose_the_band_only_when_the_look_is_judged():
    mover = _disk(20)
    flagged, grey = _grown(mover, RIM) > 0, _scene(mover)
    velocity = np.zeros((H, W, 2), np.float32)
    judged, kept = (
        group_objects(flagged, velocity, TrackConfig(rim_look=on), grey=grey)[0].mask
        for on in (True, False)
    )
    assert np.array_equal(judged, mover > 0)
    assert np.array_equal(kept, flagged)  # off: the band stays
    assert judged.sum() < kept.sum()


def test_a_rim_that_looks_like_the_core_is_kept():
    """Mover and background look alike: the look cannot tell them apart, and
    the likelier look of a rim pixel is the core's as often as the ring's.
    Here both are the same flat grey, so every rim pixel ties and stays."""
    mask = _grown(_disk(20), RIM)
    grey = np.full((H, W), 120, np.uint8)
    assert np.array_equal(rim_by_look(mask, grey, RIM), mask)


def test_a_cut_through_the_mover_keeps_it_whole():
    """Two bright blocks joined by a dark bar no wider than the rim: dropping
    the bar would split one object in two, so nothing is dropped."""
    blocks = np.zeros((H, W), np.uint8)
    blocks[40:80, 20:60] = blocks[40:80, 100:140] = 1
    grey = _scene(blocks)
    mask = blocks.copy()
    mask[58:61, 60:100] = 1  # 3 px: all rim, and looking like the dark ring
    assert np.array_equal(rim_by_look(mask, grey, RIM), mask)


def test_an_object_without_a_core_or_with_the_test_off_is_returned_as_it_is():
    thin = np.zeros((H, W), np.uint8)
    thin[50:54, 20:140] = 1  # 4 px thick: eroded by 2 px, nothing is left
    grey = _scene(_disk(5))
    assert np.array_equal(rim_by_look(thin, grey, RIM), thin)
    wide = _grown(_disk(20), RIM)
    assert np.array_equal(rim_by_look(wide, _scene(_disk(20)), 0), wide)
