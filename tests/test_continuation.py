"""The animate detector's prediction: the previous velocity carried on by
the camera's fitted change of motion (:mod:`motiondetect.animate.continuation`)."""

from __future__ import annotations

import cv2
import numpy as np

from motiondetect.animate.continuation import continued_velocity, sample_at
from motiondetect.detection.detector import MotionDetector
from motiondetect.measurement.dense_flow import pixel_grid

from .scenes import scene


def _moved(points: np.ndarray, motion: np.ndarray) -> np.ndarray:
    h, w = points.shape[:2]
    return cv2.perspectiveTransform(points.reshape(-1, 1, 2), motion).reshape(h, w, 2)


def test_the_camera_s_change_of_rotation_is_carried_and_a_reversal_is_not():
    """A pan of 3 px/frame whose rotation jolts by 1.5 degrees: each point's
    velocity is predicted to within 0.05 px, where the last velocity alone
    misses by up to 3 px; a patch that reversed is predicted as it was."""
    w, h = 160, 120
    grid = pixel_grid(w, h)
    pan = np.float32([[1, 0, 3], [0, 1, 0], [0, 0, 1]])  # previous -> current position
    turn = cv2.getRotationMatrix2D((w / 2, h / 2), 1.5, 1.0)
    jolted = np.vstack([turn, [0, 0, 1]]).astype(np.float32) @ pan
    was_before = _moved(grid, np.linalg.inv(pan))  # two frames ago, at previous pixels
    previous = grid - was_before
    patch = np.s_[50:70, 70:90]
    previous[patch] = (-6.0, 0.0)  # the patch moved left, and now moves with the pan
    source = _moved(grid, np.linalg.inv(jolted))  # current pixels, where they were
    velocity = grid - source
    continued = continued_velocity(previous, grid, source, 1.0, threshold_px=1.0)
    inside = np.s_[10:-10, 10:-10]
    predicted = sample_at(continued, source[inside].reshape(-1, 2)).reshape(100, 140, 2)
    error = np.hypot(*np.moveaxis(velocity[inside] - predicted, -1, 0))
    alone = sample_at(previous, source[inside].reshape(-1, 2)).reshape(100, 140, 2)
    missed = np.hypot(*np.moveaxis(velocity[inside] - alone, -1, 0))
    ys = np.round(source[inside][..., 1]).astype(int).clip(0, h - 1)
    xs = np.round(source[inside][..., 0]).astype(int).clip(0, w - 1)
    near = np.zeros((h, w), bool)
    near[48:72, 68:92] = True  # the patch and the 2 px that bilinear samples mix with it
    core = np.zeros((h, w), bool)
    core[52:68, 72:88] = True
    on_patch, off_patch = core[ys, xs], ~near[ys, xs]
    assert np.nanmax(error[off_patch]) < 0.05
    assert np.nanmax(missed[off_patch]) > 2.0
    assert np.nanmin(error[on_patch]) > 8.0  # 9 px: the reversal stays a violation


def test_a_rigid_orbit_is_not_animate_once_its_planes_disagree():
    """A camera circling a point of the synthetic world (``fixation``, 1.4
    times the samples' speed): no single surface dominates, and the 1-px
    RANSAC plane jumps by 2-3 px at the frame's corners from one frame to
    the next. Predicting from the previous frame's plane residual, the
    animate detector alone reported a region on 15 of frames 12-29; with
    the camera's change fitted to the velocities, on none."""
    frames = scene("fixation", (), frames=30, speed=1.4, seed=114, supersample=2)
    md = MotionDetector("animate")
    flagged = 0
    for fr in frames:
        result = md.process(fr.image, fr.index, fr.index / 30)
        if fr.index >= 12:
            flagged += bool(result.regions)
    assert flagged <= 4
