"""Each detection's velocity: how it moves in the picture, and against what
lies behind it (the camera's motion taken out), in input px per second."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from motiondetect import detect
from motiondetect.detection.base import DetectorOutput
from motiondetect.detection.detector import MotionDetector
from motiondetect.detection.fusion import FrameMotion, object_region, object_velocities
from motiondetect.detection.objects import MovingObject
from motiondetect.measurement.normal_flow import GridGeometry

from .velocity_scenes import H, W, pan_with_mover


def _frame_motion(rim_px: int) -> tuple[np.ndarray, FrameMotion]:
    """A 40x40 object moving (3, 1) work px/frame over a background moving
    (-2, 0), its outer 8 px (most of its pixels) smeared, as DIS smears a
    mover's edge over half a patch."""
    h, w = 120, 160
    mask = np.zeros((h, w), bool)
    mask[40:80, 60:100] = True
    core = np.zeros((h, w), bool)
    core[48:72, 68:92] = True
    background = np.float32([-2.0, 0.0])
    velocity = np.broadcast_to(background, (h, w, 2)).copy()
    velocity[mask] = (0.5, 0.5)  # the smeared rim
    velocity[core] = (3.0, 1.0)
    return mask, FrameMotion(velocity, velocity - background, 1 / 30, rim_px)


def _region(mask: np.ndarray, motion: FrameMotion, held: bool = False, before=None):
    ys, xs = np.nonzero(mask)
    box = (int(xs.min()), int(ys.min()), int(xs.max()) + 1, int(ys.max()) + 1)
    obj = MovingObject(mask, box, (0.0, 0.0), track=4, age=9, held=held)
    output = DetectorOutput(None, None, mask=mask, pixel_strength=mask.astype(np.float32))
    geometry = GridGeometry((320, 240), mask.shape[::-1])  # input twice the work size
    return object_region(obj, {"velocity-ray": output}, geometry, before, motion)


def test_a_detection_moves_as_its_core_does_in_input_px_per_second():
    """Left out, a rim as wide as the smear leaves only the mover's own
    velocity: (3, 1) work px a frame is (180, 60) input px/s at 30 frames/s
    and twice the size; against the background's (-2, 0), (300, 60). With
    the rim kept (``rim_px`` 0) the smear, most of the mask, is what counts."""
    mask, motion = _frame_motion(rim_px=8)
    region = _region(mask, motion)
    assert region.velocity_px_s == pytest.approx((180.0, 60.0))
    assert region.own_velocity_px_s == pytest.approx((300.0, 60.0))
    record = region.to_json()
    assert record["velocity_px_s"] == [180.0, 60.0]
    assert record["own_velocity_px_s"] == [300.0, 60.0]
    smeared = _region(mask, FrameMotion(motion.velocity, motion.residual, 1 / 30, 0))
    assert smeared.velocity_px_s == pytest.approx((30.0, 30.0))
    # A held detection carries its track's last velocities; none without one.
    held = _region(mask, motion, held=True, before=region)
    assert held.velocity_px_s == region.velocity_px_s
    assert held.own_velocity_px_s == region.own_velocity_px_s
    assert _region(mask, motion, held=True).velocity_px_s is None


def test_a_mover_smaller_than_the_rim_is_measured_over_its_whole_mask():
    mask, motion = _frame_motion(rim_px=30)
    region = _region(mask, motion)
    inside = motion.velocity[mask]
    assert region.velocity_px_s == pytest.approx(tuple(np.median(inside, axis=0) * 60))
    assert object_velocities(np.zeros_like(mask), (60, 40, 100, 80), motion) is None


@pytest.mark.parametrize(
    ("pan", "mover"), [(2.0, (3.0, 1.0)), (4.0, (-1.5, 0.5)), (0.0, (2.0, -1.0))]
)
def test_a_movers_velocity_is_measured_under_a_pan(pan, mover):
    """A textured square moving ``mover`` px/frame across a photograph panned
    ``pan`` px/frame (its image moves (-pan, 0), the frame's view velocity
    to within 0.05 px/frame): on every frame it is reported, its velocity
    is within 0.3 px/frame of the truth (9 px/s at 30 frames/s) and its own
    velocity, against the background, within 0.3 px/frame of ``mover +
    (pan, 0)``. Measured: within 0.20, 0.12 and 0.12
    of the three cases (DIS smooths a little of the background into the
    mover's core)."""
    vx, vy = mover
    clip = pan_with_mover(lambda t: (60 + vx * t, 90 + vy * t), frames=12, pan=pan)
    md = MotionDetector("both")
    reported = 0
    for t, (image, _) in enumerate(clip):
        result = md.process(image, t, t / 30)
        if t < 2:  # nothing measured yet, then no time between frames measured
            assert result.view_velocity_px_s is None
            continue
        view = np.array(result.view_velocity_px_s) / 30  # the background's motion
        assert np.abs(view - (-pan, 0)).max() < 0.05
        for region in result.regions:
            assert not region.held
            image_v = np.array(region.velocity_px_s) / 30
            own_v = np.array(region.own_velocity_px_s) / 30
            assert np.abs(image_v - (vx, vy)).max() < 0.3
            assert np.abs(own_v - (vx + pan, vy)).max() < 0.3
            assert np.abs(image_v - own_v - view).max() < 0.05  # a pan moves every pixel alike
            reported += 1
    assert reported >= 5


def test_velocities_are_per_second_of_the_input_at_any_size_and_frame_skip():
    """The same scene at twice the size and 60 frames/s, judged every 2nd
    frame: the mover crosses (6, 2) input px a frame, (360, 120) px/s, and
    (10, 2) a frame against the background, (600, 120) px/s. Measured:
    within 1.4 px/s."""
    clip = pan_with_mover(lambda t: (60 + 3.0 * t, 90 + 1.0 * t), frames=24, pan=2.0)
    frames = [cv2.resize(image, (2 * W, 2 * H), interpolation=cv2.INTER_CUBIC) for image, _ in clip]
    reported = 0
    for result in detect(frames, fps=60.0, frame_skip=1):
        for region in result.regions:
            assert np.abs(np.subtract(region.velocity_px_s, (360, 120))).max() < 10
            assert np.abs(np.subtract(region.own_velocity_px_s, (600, 120))).max() < 10
            reported += 1
    assert reported >= 12
