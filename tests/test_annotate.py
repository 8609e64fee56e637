"""The annotated frame's overlays keep out of the picture's way."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from motiondetect.detection.detector import FrameResult
from motiondetect.detection.regions import Region
from motiondetect.io.annotate import (
    MIN_WIDTH,
    OWN_ARROW_S,
    TRAIL_FRAMES,
    Trails,
    annotate,
    annotated_size,
)
from motiondetect.io.colours import OWN_MOTION, RAY


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


def test_a_caption_left_out_is_outlined_and_nothing_else_is_drawn_for_it():
    w, h = 320, 240
    grey = np.full((h, w, 3), 40, np.uint8)
    overlay = np.zeros((120, 160), bool)  # work pixels, half the input size
    overlay[100:104, 20:80] = True
    plain = FrameResult(0, 0.0, [], np.zeros((64, 64), bool), None, None, None)
    marked = FrameResult(0, 0.0, [], np.zeros((64, 64), bool), None, None, None, overlay=overlay)
    changed = np.any(annotate(grey, marked, (w, h)) != annotate(grey, plain, (w, h)), axis=2)
    ys, xs = np.nonzero(changed)
    assert ys.size and ys.min() >= 196 and ys.max() <= 212  # around rows 200-207
    assert xs.min() >= 36 and xs.max() <= 164  # around columns 40-159
    assert not changed[203, 60]  # an outline, the caption itself left as it is


@pytest.mark.parametrize(("left", "right", "place"), [(0, 70, "right"), (0, 320, "top")])
def test_the_legend_keeps_off_a_caption_left_out(left, right, place):
    """A caption along the bottom left (found fixed to the screen) keeps
    the legend's place free: the legend goes to the bottom right, or, under
    a caption as wide as the frame, below the label at the top."""
    w, h = 320, 240
    grey = np.full((h, w, 3), 128, np.uint8)
    overlay = np.zeros((120, 160), bool)  # work pixels, half the input size
    overlay[112:118, left // 2 : right // 2] = True
    plain = FrameResult(0, 0.0, [], np.zeros((64, 64), bool), None, None, None)
    marked = FrameResult(0, 0.0, [], np.zeros((64, 64), bool), None, None, None, overlay=overlay)
    before, after = annotate(grey, plain, (w, h)), annotate(grey, marked, (w, h))
    orange = np.all(before == RAY, axis=2)  # the legend's first swatch
    assert orange[h - 20 :, : w // 3].any()
    moved = np.all(after == RAY, axis=2)
    assert not moved[h - 20 :, : w // 3].any()
    if place == "right":
        assert moved[h - 20 :, w // 3 :].any()
    else:
        assert moved[20:50].any() and not moved[h - 20 :].any()


@pytest.mark.parametrize(
    "size, long_side, expected",
    [
        ((1920, 1080), 512, (512, 288)),  # reduced to the long side
        ((352, 288), 512, (352, 288)),  # as it is
        ((176, 144), 512, (320, 262)),  # QCIF enlarged to the overlay's width
        ((240, 156), 512, (320, 208)),  # UCSD
        ((144, 176), 512, (320, 392)),  # upright
        ((176, 144), 200, (200, 164)),  # never beyond --video-size
        ((1080, 1920), 512, (288, 512)),  # an upright phone clip keeps the long side
    ],
)
def test_annotated_size(size, long_side, expected):
    assert annotated_size(*size, long_side) == expected


def test_a_small_input_is_annotated_at_a_readable_width():
    """At QCIF's 176 px the label ran off the frame; enlarged to MIN_WIDTH it
    fits, and the picture is interpolated, not blocky."""
    ramp = np.tile(np.linspace(0, 255, 176).astype(np.uint8), (144, 1))
    image = np.dstack([ramp] * 3)
    empty = FrameResult(40, 1.33, [], np.zeros((64, 64), bool), None, None, None)
    size = annotated_size(176, 144, 512)
    out = annotate(image, empty, size)
    assert out.shape[:2] == (size[1], size[0]) and size[0] == MIN_WIDTH
    middle = (size[1] // 2, slice(0, size[0] // 2))  # no legend, no label there
    linear = cv2.resize(image, size, interpolation=cv2.INTER_LINEAR)
    assert np.array_equal(out[middle], linear[middle])


def test_a_tracks_recent_path_is_drawn_behind_its_box():
    """A box moving 15 px a frame to the right: after six frames its path
    runs from its first centre to its box, in the box's colour; a track
    unseen for the trail's length is forgotten."""
    grey = np.full((240, 320, 3), 128, np.uint8)
    trails = Trails()

    def result(index: int, x: int, track: int = 4) -> FrameResult:
        region = Region([x, 60, 20, 20], np.zeros((0, 2), int), 400, 0.9, ("velocity-ray",), track)
        return FrameResult(index, index / 30, [region], np.zeros((64, 64), bool), None, None, None)

    for i in range(6):
        out = annotate(grey, result(i, 20 + 15 * i), (320, 240), trails)
    assert tuple(out[70, 50]) == RAY  # on the path from (30, 70), left of the box at 95-115
    assert tuple(out[90, 50]) == (128, 128, 128)  # off it
    plain = annotate(grey, result(5, 95), (320, 240))
    assert tuple(plain[70, 50]) == (128, 128, 128)  # no trails asked for
    later = annotate(grey, result(5 + TRAIL_FRAMES, 95), (320, 240), trails)
    assert tuple(later[70, 50]) == (128, 128, 128)  # the old path is gone


def test_a_held_track_is_drawn_thin_and_labelled_held():
    """A held region (its track missed on the frame) is drawn with a 1-px
    box, thinner than a found one's, and says "held" where a found one
    shows its score."""
    grey = np.full((240, 320, 3), 128, np.uint8)

    def drawn(held: bool) -> np.ndarray:
        region = Region(
            [100, 80, 60, 60], np.zeros((0, 2), int), 3600, 0.9, ("velocity-ray",), 3, held
        )
        result = FrameResult(9, 0.3, [region], np.zeros((64, 64), bool), None, None, None)
        return np.all(annotate(grey, result, (320, 240)) == RAY, axis=2)

    found, held = drawn(False), drawn(True)
    side = (slice(100, 130), slice(95, 105))  # across the box's left side, below its label
    assert held[side].any(axis=0).sum() == 1 < found[side].any(axis=0).sum()
    label = (slice(80, 96), slice(100, 160))
    assert not np.array_equal(found[label], held[label])  # "#3 held", not "#3 0.90"


def test_a_detections_own_motion_is_drawn_as_an_arrow_from_its_centre():
    """A box at (100-160, 80-140) moving against the background at 80 px/s to
    the right and 40 px/s down: a cyan arrow from its centre (130, 110) to
    40 px right and 20 down (half a second's motion), drawn on a frame half
    the input's size at half those lengths; none without a velocity."""
    grey = np.full((120, 160, 3), 128, np.uint8)

    def drawn(own) -> np.ndarray:
        region = Region(
            [100, 80, 60, 60], np.zeros((0, 2), int), 3600, 0.9, ("velocity-ray",), 3,
            own_velocity_px_s=own,
        )  # fmt: skip
        result = FrameResult(9, 0.3, [region], np.zeros((64, 64), bool), None, None, None)
        out = annotate(grey, result, (160, 120), input_size=(320, 240))
        return np.all(out == OWN_MOTION, axis=2)

    assert OWN_ARROW_S == 0.5
    arrow = drawn((80.0, 40.0)) & ~drawn(None)
    ys, xs = np.nonzero(arrow)
    assert len(xs) and abs(xs.min() - 65) <= 1 and abs(ys.min() - 55) <= 1  # (130, 110) / 2
    assert arrow[65, 85] and xs.max() <= 86  # to 20 px right and 10 down, no farther
    assert not (drawn((1.0, 0.0)) & ~drawn(None)).any()  # too short to draw
