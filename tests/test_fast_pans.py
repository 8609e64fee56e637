"""Fast steady pans: DIS starts its search from the last field
(``DenseFlowConfig.start_speed_px``), and the band test reads how far it
searched (docs/detectors.md, "Fast steady pans")."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from motiondetect.constraint_ray.camera_fit import fit_camera
from motiondetect.constraint_ray.fit_config import FitConfig
from motiondetect.detection.detector import MotionDetector
from motiondetect.measurement.dense_flow import DenseFlow, DenseFlowConfig

from .velocity_scenes import PHOTO, H, W, paste

WIDE = np.hstack([PHOTO, PHOTO[:, ::-1]])  # room for a long pan


def _pan(speeds: list[float]) -> list[np.ndarray]:
    """Frames of a camera panning right at each of ``speeds`` px/frame in turn."""
    xs = np.cumsum([0.0, *speeds])
    return [
        cv2.warpAffine(
            WIDE, np.float32([[1, 0, -x - 40], [0, 1, -136]]), (W, H), flags=cv2.INTER_CUBIC
        )
        for x in xs
    ]


@pytest.mark.parametrize("start_speed_px", [15.0, np.inf])
def test_a_fast_steady_pan_is_measured_from_the_last_fields_velocity(start_speed_px):
    """DIS's search reaches about 30 px/frame from where it starts. A pan
    that speeds up steadily to 50 px/frame is measured, and judged, when
    each search starts from the last field (the default); started from rest
    (``inf``) the 40 and 50 px/frame fields are wrong in places and the fit
    says the motion is beyond the band."""
    speeds = [20, 30, 40, 50, 50]
    flow = DenseFlow(DenseFlowConfig(work_size=W, start_speed_px=start_speed_px))
    fields = [flow.process(frame) for frame in _pan(speeds)][1:]
    worst = []
    for field, speed in zip(fields[2:], speeds[2:]):
        # Content enters at the right.
        v = field.velocity_px[20:-20, 20 : -(20 + speed)].reshape(-1, 2)
        worst.append(np.percentile(np.hypot(v[:, 0] + speed, v[:, 1]), 90))
        assert fit_camera(field, FitConfig()).reliable == (start_speed_px == 15.0)
    if start_speed_px == 15.0:
        assert all(field.searched_px is not None for field in fields[2:])
        assert max(worst) < 0.5
    else:
        assert max(worst) > 5.0


def test_a_mover_in_a_fast_steady_pan_is_found_on_every_frame():
    """A 48 px mover drifting against a pan that speeds up to 50 px/frame:
    found whole from the third frame on, as the one region, its trail (the
    background it uncovers, about its own size) the only other pixels
    flagged. Searched from rest (``inf``), the fast frames are unreliable or
    miss it. Measured: covered 0.98-1.00, 1600-3300 other pixels."""
    speeds = [20, 30, 40, 50, 50, 50, 50, 50]
    found = {}
    for start_speed_px in (15.0, np.inf):
        detector = MotionDetector(
            "both", DenseFlowConfig(work_size=W, start_speed_px=start_speed_px)
        )
        found[start_speed_px] = []
        for i, frame in enumerate(_pan(speeds)[:-1]):
            image, mover = paste(frame, 60 + 6 * i, 90 + 3 * i)
            result = detector.process(image, i, i / 30)
            flagged = result.input_mask(W, H) > 0
            if i >= 2 and start_speed_px == 15.0:
                assert result.reliable and len(result.regions) == 1
                assert flagged[mover].mean() > 0.9
                assert np.count_nonzero(flagged & ~mover) < 2 * np.count_nonzero(mover)
            found[start_speed_px].append(result.reliable and flagged[mover].mean() > 0.5)
    assert sum(found[np.inf][3:]) <= 1


def test_a_jerky_pan_is_measured_from_rest():
    """A camera whose motion reverses every frame gives the last field no
    say: each search starts from rest, and each field is right."""
    flow = DenseFlow(DenseFlowConfig(work_size=W))
    fields = [flow.process(frame) for frame in _pan([20, -20, 20, -20, 20])][1:]
    for field, speed in zip(fields, [20, -20, 20, -20, 20]):
        assert field.searched_px is None
        v = field.velocity_px[20:-20, 40:-40].reshape(-1, 2)
        assert np.median(np.hypot(v[:, 0] + speed, v[:, 1])) < 0.1


def test_a_pan_that_breaks_off_is_measured_from_rest():
    """A steady 40 px/frame pan that turns back at 10 px/frame lies 50 px from
    the last field, beyond DIS's reach from it: that frame is measured again
    from rest, and is right and judged."""
    flow = DenseFlow(DenseFlowConfig(work_size=W))
    fields = [flow.process(frame) for frame in _pan([20, 30, 40, 40, -10])][1:]
    assert fields[3].searched_px is not None  # the steady part started from the last field
    last = fields[-1]
    assert last.searched_px is None
    v = last.velocity_px[20:-20, 40:-40].reshape(-1, 2)
    assert np.percentile(np.hypot(v[:, 0] - 10, v[:, 1]), 90) < 0.5
    assert fit_camera(last, FitConfig()).reliable


def test_a_search_from_rest_is_not_led_by_an_earlier_start():
    """OpenCV's DIS keeps an initial flow it was given for its later calls.
    A field measured from rest after searches from the last field (here the
    pan breaking off) equals the same two frames measured afresh."""
    frames = _pan([20, 30, 40, 40, -10])
    flow = DenseFlow(DenseFlowConfig(work_size=W))
    last = [flow.process(frame) for frame in frames][-1]
    fresh = DenseFlow(DenseFlowConfig(work_size=W))
    fresh.process(frames[-2])
    alone = fresh.process(frames[-1])
    assert last.searched_px is None
    np.testing.assert_array_equal(last.velocity_px, alone.velocity_px)
    np.testing.assert_array_equal(last.forward_px, alone.forward_px)
