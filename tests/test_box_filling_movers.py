"""A tracked mover whose box fills the view (``Tracker.predicted_pixels``,
``camera_fit._plane``; docs/detectors.md, "A mover whose box fills the
view").

The samples inside the confirmed tracks' boxes stop voting for the plane
only while the boxes leave ``min_inlier_share`` of the samples. A rounded
or L-shaped mover's box holds the background between its limbs, and can
fill the view while the mover does not: its own pixels are left out then.
"""

from __future__ import annotations

import cv2
import numpy as np
import pytest
from skimage import data

from motiondetect.constraint_ray.camera_fit import fit_camera
from motiondetect.constraint_ray.fit_config import FitConfig
from motiondetect.detection.detector import MotionDetector
from motiondetect.detection.tracking import Tracker

from .velocity_scenes import H, W, background, coverage, field_between

REST = FitConfig().min_inlier_share
COFFEE = cv2.cvtColor(data.coffee(), cv2.COLOR_RGB2BGR)


def _box_share(t: int) -> float:
    """The share of the view the cornered mover's box covers on frame ``t``."""
    return 0.3 + 0.6 * min(t / 30, 1.0)


def _cornered_mover(frames: int = 36, arm: float = 0.45):
    """A camera panning 3 px/frame follows an L-shaped textured mover (two
    arms ``arm`` of its box wide), wobbling 6 px about the centre, whose
    box grows from 30 % to 90 % of the view: its pixels, 21-63 % of it,
    leave the background a corner. Frames and masks."""
    for t in range(frames):
        share = _box_share(t)
        mw, mh = int(W * np.sqrt(share)), int(H * np.sqrt(share))
        x, y = (W - mw) // 2 + int(round(6 * np.sin(t / 5))), (H - mh) // 2
        inside = np.zeros((mh, mw), bool)
        inside[:, : int(arm * mw)] = True
        inside[int((1 - arm) * mh) :, :] = True
        frame = background(3.0 * t)
        texture = cv2.resize(COFFEE, (mw, mh), interpolation=cv2.INTER_AREA)
        frame[y : y + mh, x : x + mw][inside] = texture[inside]
        mask = np.zeros((H, W), bool)
        mask[y : y + mh, x : x + mw] = inside
        yield frame, mask


def test_the_tracks_own_pixels_are_asked_for_only_where_their_boxes_leave_too_few_samples():
    """``fit_camera``'s choice is made on the 8-px grid's samples: a box of
    74.7 % of the pixels holds 77 % of the samples (the frame-edge band has
    none), so the tracks' own pixels (an L of 70 % of the view) are asked
    for; then the pan's plane is found, the L's motion left out.
    Without them the L, still in the view, takes the plane. A box that
    leaves enough samples is used as it is, and the pixels are not made."""
    frames = [frame for frame, _ in _cornered_mover(2)]
    inside = np.zeros((H, W), np.uint8)
    inside[:, : int(0.45 * W)] = 1
    inside[int(0.55 * H) :, :] = 1
    mover = inside > 0
    still = np.where(mover[..., None], frames[0], background(3.0))
    field = field_between(np.where(mover[..., None], frames[0], background(0.0)), still)
    box = np.zeros((H, W), bool)
    box[:, 8:247] = True  # 74.7 % of the pixels, 30 of the grid's 39 columns
    asked = []

    def pixels() -> np.ndarray:
        asked.append(True)
        return mover

    def pan_error(fit) -> float:  # off the L, the view moves (-3, 0) px/frame
        point = np.array([[[300.0, 20.0]]])
        velocity = (point - cv2.perspectiveTransform(point, fit.homography))[0, 0]
        return float(np.hypot(*(velocity - [-3.0, 0.0])))

    assert box.mean() < 1 - REST and pan_error(fit_camera(field, FitConfig(), movers=box)) > 2.0
    assert pan_error(fit_camera(field, FitConfig(), movers=box, finer_movers=pixels)) < 0.3
    assert asked == [True]
    half = np.zeros((H, W), bool)
    half[:, : W // 2] = True
    fit_camera(field, FitConfig(), movers=half, finer_movers=pixels)
    assert asked == [True]


@pytest.mark.parametrize("own_pixels", [True, False])
def test_a_mover_whose_box_fills_the_view_leaves_out_its_own_pixels(monkeypatch, own_pixels):
    """Once an L-shaped mover's box covers more than 1 - ``min_inlier_share``
    of the view, the box leaves too few samples to fit the plane to; its
    pixels (56-63 %, grown by half a flow patch) do not. Measured over the
    frames whose box covers 82-90 % of the view: covered 0.55-0.98 (mean
    0.83) with 3000-5800 background pixels; with the boxes only, as before,
    0.00-0.02 with 14100-24300, the mover's motion taken for the camera's."""
    if not own_pixels:
        monkeypatch.setattr(Tracker, "predicted_pixels", lambda *args: None)
    found, background_px = coverage(
        MotionDetector("both"), _cornered_mover(), lambda t, _: _box_share(t) >= 0.82
    )
    assert len(found) >= 8
    if own_pixels:
        assert min(found) > 0.4 and np.mean(found) > 0.75
        assert max(background_px) < 8000
    else:
        assert max(found) < 0.1 and min(background_px) > 10000
