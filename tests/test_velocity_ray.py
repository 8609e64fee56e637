"""The constraint ray in velocity space (issue 13, item 3): whole movers found
under a moving camera, rigid parallax and noise left alone, slow movers found
over frames.
"""

from __future__ import annotations

import cv2
import numpy as np

from motiondetect.constraint_ray.fit_config import FitConfig
from motiondetect.constraint_ray.velocity_filter import VelocityRayConfig
from motiondetect.detection.detector import MotionDetector
from motiondetect.detection.objects import TrackConfig
from motiondetect.measurement.dense_flow import DenseFlowConfig
from motiondetect.tools.evaluate import Counts, score_frame

from .velocity_scenes import (
    PHOTO,
    H,
    W,
    animate_on_sample,
    background,
    mover_hits,
    pan_with_mover,
    paste,
)


def test_constraint_ray_finds_a_whole_mover_under_a_pan():
    clip = pan_with_mover(lambda t: (60 + 3 * t, 100 + 1.0 * t))
    md = MotionDetector("constraint-ray")
    hits = mover_hits(md, clip)
    assert np.mean(hits) >= 0.9


def test_the_remembered_background_trims_a_fast_movers_trail():
    """8 px/frame under a pan: without the memory the mask carries the
    ghost on the trailing side; with it (the default) precision rises, and
    the mover is still found whole."""
    clip = pan_with_mover(lambda t: (40 + 8 * t, 100 + 0.5 * t))
    scores = {}
    for rate in (0.0, TrackConfig().background_rate):
        md = MotionDetector("both", TrackConfig(background_rate=rate))
        counts = Counts()
        for t, (image, mask) in enumerate(clip):
            result = md.process(image, t, t / 30)
            if t >= 3:
                counts.add(score_frame(result.input_mask(W, H), mask.astype(np.uint8) * 255))
        scores[rate] = counts.metrics()
    off, on = scores[0.0], scores[TrackConfig().background_rate]
    assert on["recall"] > 0.95 and off["recall"] > 0.95  # measured 1.00 both
    assert on["precision"] > off["precision"] + 0.05  # measured 0.76 against 0.67


def test_rigid_pan_flags_nothing():
    md = MotionDetector()
    for t in range(20):
        result = md.process(background(2.5 * t, 0.3 * t), t, t / 30)
        assert result.regions == [], t


def _dim_and_auto_exposed(image: np.ndarray, t: int, rng) -> np.ndarray:
    """Frame ``t`` as a dim sensor with automatic exposure gives it: a gain
    drifting by up to 20 % (up to 10 % a frame) and 8 grey levels of noise."""
    gain = 1.0 + 0.2 * np.sin(2 * np.pi * t / 12)
    noisy = image.astype(np.float32) * gain + rng.normal(0.0, 8.0, image.shape)
    return np.clip(noisy, 0, 255).astype(np.uint8)


def test_sensor_noise_and_exposure_drift_neither_hide_a_mover_nor_add_alarms():
    """The tolerances come from each frame's measured noise, and DIS matches
    mean-normalised patches, so neither changes the answer: the mover is
    found on every judged frame (measured 21 of 21) and the rigid pan
    gives no region (measured none in 20 frames)."""
    rng = np.random.default_rng(0)
    clip = pan_with_mover(lambda t: (60 + 3 * t, 100 + 1.0 * t))
    clip = [(_dim_and_auto_exposed(image, t, rng), mask) for t, (image, mask) in enumerate(clip)]
    assert np.mean(mover_hits(MotionDetector(), clip)) >= 0.9
    md = MotionDetector()
    for t in range(20):
        frame = _dim_and_auto_exposed(background(2.5 * t, 0.3 * t), t, rng)
        assert md.process(frame, t, t / 30).regions == [], t


def test_flow_without_image_change_is_not_flagged():
    """A residual in a blank region (flow's own error) has no photometric evidence."""
    from motiondetect.constraint_ray.camera_fit import CameraFit
    from motiondetect.constraint_ray.velocity_filter import VelocityRayConfig, VelocityRayDetector
    from motiondetect.measurement.dense_flow import VelocityField, pixel_grid
    from motiondetect.measurement.normal_flow import GridGeometry

    h, w = 96, 128
    rng = np.random.default_rng(0)
    grey = rng.integers(0, 255, (h, w)).astype(np.uint8)
    residual = rng.normal(0, 0.1, (h, w, 2)).astype(np.float32)
    residual[20:40, 20:40] = (3.0, 0.0)  # flow error: the image did not change there
    residual[50:70, 80:100] = (3.0, 0.0)  # a mover: it did
    difference = np.abs(rng.normal(0, 2.0, (h, w))).astype(np.uint8)
    difference[50:70, 80:100] = 40
    fit = CameraFit(np.eye(3), residual, 0.1, 0.9, None, "", 0.5, difference)
    velocity = residual  # the plane is the identity: the residual is the velocity
    geometry = GridGeometry((w, h), (w, h))
    field = VelocityField(velocity, grey, grey, geometry, pixel_grid(w, h), fit)
    for sigmas, blank_flagged in ((3.0, False), (0.0, True)):
        out = VelocityRayDetector(VelocityRayConfig(evidence_sigmas=sigmas)).process(field)
        assert out.mask[55:65, 85:95].all()
        assert out.mask[25:35, 25:35].any() == blank_flagged


def _terrain(t: int, speed: float = 3.0) -> np.ndarray:
    """A rigid scene of smoothly varying depth seen by a camera translating sideways:
    inverse depth 0.7-1.3, so image speeds run 2.1-3.9 px/frame, a parallax no
    plane explains."""
    yy, xx = np.mgrid[0:H, 0:W].astype(np.float32)
    inverse_depth = 1 + 0.3 * np.sin(2 * np.pi * xx / W) * np.sin(2 * np.pi * yy / H)
    map_x = xx + 96 + speed * t * inverse_depth
    return cv2.remap(PHOTO, map_x, yy + 136, cv2.INTER_CUBIC, borderMode=cv2.BORDER_REFLECT)


def _terrain_run(spread_sigmas: float, mover: bool) -> tuple[float, float]:
    """(share of frames with the mover half flagged, false-alarm regions per frame)."""
    # The aperture gate and the discount next to the frame edge, added later,
    # also remove some of this parallax: off, to measure the spread term alone.
    ray = VelocityRayConfig(spread_sigmas=spread_sigmas, edge_error_ratio=1.0)
    fit = FitConfig(aperture_noise=0.0)
    md = MotionDetector("both", ray, fit)
    hits, false_alarms = [], []
    for t in range(12):
        image, mask = _terrain(t), np.zeros((H, W), bool)
        if mover:
            image, mask = paste(image, 130.0, 40 + 8.0 * t)
        flagged = md.process(image, t, t / 30).input_mask(W, H) > 0
        if t < 3:
            continue
        hits.append(flagged[mask].mean() >= 0.5 if mover else True)
        count, labels = cv2.connectedComponents(flagged.astype(np.uint8))
        false_alarms.append(count - 1 - len(set(np.unique(labels[mask & flagged])) - {0}))
    return float(np.mean(hits)), float(np.mean(false_alarms))


def test_the_frames_measured_spread_tolerates_rigid_parallax():
    """The tolerance grows with the whole frame's residual spread, so the
    parallax of a rigid scene of many depths passes while a mover crossing it
    is still found; without the spread term the parallax is flagged."""
    found, with_mover = _terrain_run(5.0, mover=True)
    _, rigid_only = _terrain_run(5.0, mover=False)
    _, rigid_without_spread = _terrain_run(0.0, mover=False)
    assert found >= 0.9  # measured 1.0
    # measured 0.33 and 0.22 (0.56 and 0.56 while tracked movers always voted for the plane)
    assert with_mover <= 0.5 and rigid_only <= 0.5
    assert rigid_without_spread >= 1.5  # measured 2.22 (2.33)
    assert rigid_without_spread >= 4 * rigid_only


def _slowing_mover_found(prior: bool) -> float:
    """Share of frames 10-23 with the mover half flagged: under a 2 px/frame pan it
    moves 3 px/frame against the background for 8 frames, then 0.75 of the
    tolerance's floor, under it but above half of it (the growth threshold)."""
    # Without the summed residual, which the slowed mover borders on.
    ray = VelocityRayConfig(carry=0.0)
    md = MotionDetector("constraint-ray", TrackConfig(prior=prior), ray)
    x, hits = 60.0, []
    for t in range(24):
        x += 3.0 if t < 8 else 0.75 * ray.floor_px
        image, mask = paste(background(2.0 * t), x - 2.0 * t, 100.0)
        flagged = md.process(image, t, t / 30).input_mask(W, H) > 0
        if t >= 10:
            hits.append(flagged[mask].mean() >= 0.5)
    return float(np.mean(hits))


def test_a_tracked_mover_that_slows_stays_found():
    """Where a confirmed track is predicted, a seed needs only the growth
    threshold, so a mover that slows under the floor is still found there;
    without the prior it is lost."""
    assert _slowing_mover_found(prior=True) >= 0.8  # measured 1.0
    # measured 0.0; at 0.9 of the floor 0.29, since the tight plane, likelier
    # here, leaves the mover its whole residual, which DIS's error lifts over
    # the floor
    assert _slowing_mover_found(prior=False) <= 0.2


def _slow_mover_frames(
    frames, carry: float, floor_px: float = VelocityRayConfig.floor_px
) -> tuple[int, int]:
    """(frames with a region on the mover, regions touching no mover pixel)."""
    from .scenes import found_and_stray

    ray = VelocityRayConfig(carry=carry, floor_px=floor_px)
    return found_and_stray(MotionDetector("constraint-ray", ray), frames)


def test_a_mover_too_slow_for_one_frame_is_found_by_the_summed_residual():
    from .scenes import scene

    # About 0.75 px/frame against a one-frame tolerance of 1 px (as noisy
    # footage sets it; the floor stands for it here), above the summed test's
    # 0.6 px/frame. Measured: 0 frames without the sum, 26 with.
    slow = scene("static", ("smooth",), frames=30, speed=0.25)
    on, off = _slow_mover_frames(slow, carry=0.0, floor_px=1.0)
    assert on <= 3 and off == 0
    on, off = _slow_mover_frames(slow, carry=0.75, floor_px=1.0)
    assert on >= 14 and off == 0
    still = scene("static", (), frames=30)
    assert _slow_mover_frames(still, carry=0.75) == (0, 0)


def test_a_still_cameras_slow_mover_needs_no_moving_images_floor():
    """The summed test's floor (``slow_px``) stands for DIS's error under a
    moving image, which repeats frame to frame and adds up as a mover does; it
    grows with the image's motion, from a third of it on a still image. Under
    a still camera a mover at about 0.3 px/frame, half the full floor, is
    found; a still scene, however noisy, and a camera panning slower than 0.3
    px/frame flag nothing. Measured: 23 of 30 frames found (4 with the full
    floor); the pans flag 15-21 of 40 frames with no floor below 0.3
    px/frame, none with the floor in proportion."""
    from .scenes import found_and_stray, scene

    slow = scene("static", ("smooth",), frames=30, speed=0.1)
    on, off = found_and_stray(MotionDetector("constraint-ray"), slow)
    assert on >= 20 and off == 0
    floored = VelocityRayConfig(slow_full_speed_px=0.0)
    assert found_and_stray(MotionDetector("constraint-ray", floored), slow)[0] <= 8
    for noise in (1.0, 8.0):
        still = scene("static", (), frames=30, noise_grey=noise)
        assert found_and_stray(MotionDetector(), still) == (0, 0)
    rng = np.random.default_rng(0)
    for pan in (0.1, 0.2, 0.29):
        md = MotionDetector()
        for t in range(40):
            image = background(pan * t) + rng.normal(0, 2.0, (H, W, 3))
            assert not md.process(np.clip(image, 0, 255).astype(np.uint8), t, t / 30).regions


def _still_noisy_field(rng, speed: float, plane_speed: float | None):
    """One frame of a still camera whose flow has 0.15 px of noise per
    component, with a 20x20 mover at ``speed`` px/frame that changes the
    image; the fit records the measured median speed (about 0.2 px/frame,
    all noise) and the plane's own (none; ``None``: the measured one)."""
    from motiondetect.constraint_ray.camera_fit import CameraFit
    from motiondetect.measurement.dense_flow import VelocityField, pixel_grid, vector_length
    from motiondetect.measurement.normal_flow import GridGeometry

    h, w = 96, 128
    velocity = rng.normal(0, 0.15, (h, w, 2)).astype(np.float32)
    velocity[40:60, 50:70] += (speed, 0.0)
    difference = np.abs(rng.normal(0, 2.0, (h, w))).astype(np.uint8)
    difference[40:60, 50:70] = 40
    measured = float(np.median(vector_length(velocity[8:-8:8, 8:-8:8])))
    plane = measured if plane_speed is None else plane_speed
    fit = CameraFit(
        np.eye(3), velocity, 0.15, 0.95, None, "", measured, difference, 0.15, plane_speed_px=plane
    )
    grey = rng.integers(0, 255, (h, w)).astype(np.uint8)
    return VelocityField(velocity, grey, grey, GridGeometry((w, h), (w, h)), pixel_grid(w, h), fit)


def test_the_still_floor_follows_the_planes_speed_not_the_noises():
    """DIS's noise alone gives a still camera's velocities a median speed
    (about 0.2 px/frame here, as on UCSD's foggy traffic), which is not the
    image moving: the summed test's floor follows the plane's own speed. A
    mover at 0.4 px/frame under a still, noisy camera is found from its
    fourth frame on (measured 9 of 12 frames); with the floor set by the
    measured median speed it is never found; noise alone flags nothing."""
    from motiondetect.constraint_ray.velocity_filter import VelocityRayDetector

    for plane_speed, most in ((0.0, True), (None, False)):
        rng, detector = np.random.default_rng(0), VelocityRayDetector()
        masks = [
            detector.process(_still_noisy_field(rng, 0.4, plane_speed)).mask for _ in range(12)
        ]
        found = sum(m[40:60, 50:70].mean() > 0.5 for m in masks)
        assert (found >= 8) == most and (found == 0) != most, found
        assert not any(m[:35].any() or m[65:].any() for m in masks)
    rng, detector = np.random.default_rng(1), VelocityRayDetector()
    assert not any(
        detector.process(_still_noisy_field(rng, 0.0, 0.0)).mask.any() for _ in range(12)
    )


def test_seeds_are_tested_on_the_motion_the_image_determines():
    """uniform_rigid's brick wall has long mortar lines: along them the flow is
    filled in, and wrong by pixels. Testing seeds only on the determined
    residual removes most of those false alarms and keeps uniform_mixed's
    movers. Measured without the forward-backward check, which came later and
    takes out most of the rest (0.09 and 0.16 with it)."""
    whole, unchecked = FitConfig(aperture_noise=0.0), DenseFlowConfig(check_preset="off")
    on = animate_on_sample("uniform_rigid", unchecked, detector="both")[0]
    off = animate_on_sample("uniform_rigid", whole, unchecked, detector="both")[0]
    assert on <= 0.7 and off >= 1.2  # measured 0.40 and 1.67
    kept = animate_on_sample("uniform_mixed", unchecked, detector="both")
    before = animate_on_sample("uniform_mixed", whole, unchecked, detector="both")
    assert kept[1] >= before[1] - 0.03 and kept[0] < before[0]  # measured 0.26 against 1.19
