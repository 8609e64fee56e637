"""The rolling shutter's wobble: offsets per sensor line, recovered with known answers."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from motiondetect.constraint_ray.fit_config import FitConfig
from motiondetect.constraint_ray.rolling_shutter import line_offsets
from motiondetect.detection.detector import MotionDetector
from motiondetect.tools.evaluate import Counts, score_frame

from .velocity_scenes import H as SCENE_H
from .velocity_scenes import W as SCENE_W
from .velocity_scenes import background, paste

H, W, STEP = 180, 320, 8


LINES = (np.arange(STEP, H - STEP, STEP), np.arange(STEP, W - STEP, STEP))


def _samples():
    ys, xs = np.meshgrid(*LINES, indexing="ij")
    return np.stack([xs.ravel(), ys.ravel()], axis=1).astype(np.float32)


def _offsets(points, residual, previous=None):
    grid = residual.reshape(len(LINES[0]), len(LINES[1]), 2).astype(np.float32)
    last = np.zeros_like(grid) if previous is None else previous
    return line_offsets(grid, LINES, 0.3, (H, W), 1.0, None, last)


def _wobble(coordinate: np.ndarray, length: int) -> np.ndarray:
    """A 10 Hz vibration's swing read over 25 ms (2.5 rad of its phase across
    the frame): about 1.5 px, curved (not a shear, which the plane takes)."""
    u = coordinate / length
    return np.stack([1.5 * np.sin(2.5 * u + 0.3), -1.0 * np.cos(2.5 * u)], axis=1)


@pytest.mark.parametrize("axis", [0, 1])
def test_the_wobble_along_the_lines_read_is_recovered_past_a_mover(axis):
    points = _samples()
    rng = np.random.default_rng(1)
    coordinate, length = points[:, 1 - axis], (H, W)[axis]
    residual = _wobble(coordinate, length) + rng.normal(0, 0.1, (len(points), 2))
    mover = (np.abs(points[:, 0] - 100) < 30) & (np.abs(points[:, 1] - 60) < 30)
    residual[mover] += (4.0, -3.0)  # a mover's own motion, over a few bands
    found = _offsets(points, residual)
    assert found is not None and found.axis == axis
    lines = np.arange(STEP, length - STEP)  # where the samples lie
    assert np.abs(found.offsets[lines] - _wobble(lines, length)).max() < 0.15
    left = residual - found.at(points)
    assert np.median(np.hypot(*left[~mover].T)) < 0.2  # the scene is left with the noise
    assert np.median(np.hypot(*left[mover].T)) > 4.0  # the mover keeps its residual
    assert found.field((H, W)).shape == (H, W, 2)


def test_noise_and_a_mover_give_no_offsets():
    points = _samples()
    rng = np.random.default_rng(2)
    residual = rng.normal(0, 0.2, (len(points), 2))
    residual[(np.abs(points[:, 0] - 200) < 40) & (points[:, 1] < 90)] += (3.0, 0.0)
    assert _offsets(points, residual) is None


def _wobbled_clip(amplitude: float, frames: int = 30):
    """A panning camera (2 px/frame) with a rolling shutter (rows read over
    0.8 of the frame period) on a 9 Hz vibration of ``amplitude`` px; the
    patch moves 1 px/frame against the scene. Frames and masks."""
    ys, xs = np.mgrid[0:SCENE_H, 0:SCENE_W].astype(np.float32)
    out = []
    for t in range(frames):
        image, mask = paste(background(2.0 * t), 60 - t, 100)
        times = (t + 0.8 * np.arange(SCENE_H) / SCENE_H) / 30.0
        dx = amplitude * np.sin(2 * np.pi * 9.0 * times)
        dy = 0.6 * amplitude * np.sin(2 * np.pi * 11.7 * times + 1.0)
        map_x, map_y = xs + dx[:, None].astype(np.float32), ys + dy[:, None].astype(np.float32)
        image = cv2.remap(image, map_x, map_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)
        mask = cv2.remap(mask.astype(np.uint8), map_x, map_y, cv2.INTER_NEAREST) > 0
        out.append((image, mask))
    return out


def _scored(clip, config: FitConfig) -> dict:
    md, counts = MotionDetector("both", config), Counts()
    for t, (image, mask) in enumerate(clip):
        result = md.process(image, t, t / 30)
        if t >= 3:
            flagged = (result.input_mask(SCENE_W, SCENE_H) > 0).astype(np.uint8) * 255
            counts.add(score_frame(flagged, mask.astype(np.uint8) * 255))
    return counts.metrics()


def test_a_slow_mover_is_found_through_a_vibrating_rolling_shutter():
    clip = _wobbled_clip(3.0)
    found = _scored(clip, FitConfig(line_gain=0.15))
    assert found["object_recall"] >= 0.85 and found["cell_f1"] >= 0.75
    assert found["false_alarm_regions_per_frame"] <= 0.15
    # without the model the wobble's residual hides the mover (the test's point)
    blind = _scored(clip, FitConfig(line_gain=0.0))
    assert blind["object_recall"] <= 0.75 and blind["cell_f1"] <= 0.6


def test_without_a_wobble_the_line_model_stays_out():
    still = _wobbled_clip(0.0, frames=12)
    md = MotionDetector("both", FitConfig(line_gain=0.15))
    off = MotionDetector("both", FitConfig(line_gain=0.0))
    for t, (image, _) in enumerate(still):
        a, b = md.process(image, t, t / 30), off.process(image, t, t / 30)
        assert np.array_equal(a.input_mask(SCENE_W, SCENE_H), b.input_mask(SCENE_W, SCENE_H))


def test_a_line_structure_that_persists_is_parallax_not_a_wobble():
    """The same row-wise residual on the last frame (the ground's parallax
    under a sideways motion persists) is left alone; one that changed is taken."""
    points = _samples()
    residual = _wobble(points[:, 1], H).astype(np.float32)
    grid = residual.reshape(len(LINES[0]), len(LINES[1]), 2)
    assert _offsets(points, residual, previous=grid * 0.9) is None
    assert _offsets(points, residual, previous=-grid) is not None
