"""The velocity path's measurement and fit (issue 13, items 1, 2 and 6): 2-D
motion, the fitted observer motion, the off-ray distance, the forward-backward
check, and frames that cannot be judged. The detectors on it are tested in
``test_velocity_ray.py`` and ``test_velocity_animate.py``, objects and tracks
in ``test_tracking.py``.

Scenes are a real photograph moved by exact warps, with textured squares
pasted as movers (``velocity_scenes.py``), so every answer is known.
"""

from __future__ import annotations

import dataclasses

import cv2
import numpy as np
import pytest
from skimage import data

from motiondetect.constraint_ray.camera_fit import fit_camera
from motiondetect.constraint_ray.epipole import off_ray
from motiondetect.constraint_ray.fit_config import FitConfig
from motiondetect.constraint_ray.plane import (
    fit_homography,
    mixture_log_likelihood,
    plane_error,
    samples,
)
from motiondetect.constraint_ray.velocity_filter import gap_to_segment
from motiondetect.detection.detector import MotionDetector
from motiondetect.measurement.dense_flow import DenseFlow, DenseFlowConfig, vector_length
from motiondetect.tools.synth import smeared

from .velocity_scenes import H, W, background, field_between


@pytest.mark.parametrize("speed", [0.5, 3.0, 10.0, 25.0])
def test_dense_flow_recovers_known_translation(speed):
    flow = DenseFlow(DenseFlowConfig(work_size=W))
    flow.process(background(0.0))
    field = flow.process(background(speed))
    v = field.velocity_px[20:-20, 20:-20].reshape(-1, 2)
    error = np.hypot(v[:, 0] + speed, v[:, 1])  # the scene moves left as the camera pans right
    assert np.median(error) < 0.1 + 0.01 * speed
    assert np.percentile(error, 90) < 0.5 + 0.03 * speed


def test_dense_flow_never_upscales():
    flow = DenseFlow(DenseFlowConfig(work_size=1000))
    assert flow.geometry_for(W, H).work_size == (W, H)
    assert flow.geometry_for(640, 480).work_size == (640, 480)


def test_fit_explains_a_rigid_planar_scene():
    field = field_between(background(0.0, zoom=1.0), background(4.0, 1.0, zoom=1.02))
    fit = fit_camera(field, FitConfig())
    assert fit.reliable and fit.inlier_share > 0.8
    r = fit.residual_px[16:-16, 16:-16]
    assert np.percentile(np.hypot(r[..., 0], r[..., 1]), 95) < 0.5
    assert fit.epipole is None  # a plane has no parallax


BAND = FitConfig().max_speed_px  # the likelihood's outliers spread over the measurable band


def _pan_samples(seed: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """An 8-px grid of a (2, 1) px/frame pan with 0.05 px of noise."""
    rng = np.random.default_rng(seed)
    ys, xs = np.mgrid[8:180:8, 8:320:8]
    points = np.stack([xs.ravel(), ys.ravel()], 1).astype(np.float32)
    velocity = np.float32([2.0, 1.0]) + rng.normal(0, 0.05, points.shape).astype(np.float32)
    return points, velocity


@pytest.mark.parametrize("offset", [0.5, 0.7, 0.9])
def test_the_likelier_plane_leaves_a_slow_mover_whole(offset):
    # A compact mover (8 % of the samples) going `offset` px/frame faster
    # than the pan: within RANSAC's 1 px, so the 1 px plane leans toward it.
    points, velocity = _pan_samples()
    mover = (abs(points[:, 0] - 230) < 30) & (abs(points[:, 1] - 100) < 40)
    velocity[mover, 0] += offset
    plain, _ = fit_homography(points, velocity, 1.0, outlier_px=BAND)
    chosen, inliers = fit_homography(points, velocity, 1.0, outlier_px=BAND, tight_px=0.3)
    left = np.median(plane_error(points, velocity, plain)[mover])
    whole = np.median(plane_error(points, velocity, chosen)[mover])
    assert left < offset - 0.04  # the compromise absorbs part of the mover
    assert abs(whole - offset) < 0.02  # the tight plane, likelier, leaves all of it
    assert inliers[~mover].all()  # what counts as explained is still 1 px


def test_the_compromise_plane_is_kept_where_no_surface_dominates():
    # Checkered 40-px blocks 0.6 px/frame apart (two depths under a sideways
    # move, interleaved so that no homography fits both): the tight plane
    # explains one half only, the 1 px plane both within 0.3 px.
    points, velocity = _pan_samples()
    near = (points[:, 0] // 40 + points[:, 1] // 40) % 2 == 1
    velocity[near, 0] += 0.6
    plain, _ = fit_homography(points, velocity, 1.0, outlier_px=BAND)
    chosen, _ = fit_homography(points, velocity, 1.0, outlier_px=BAND, tight_px=0.3)
    assert np.allclose(chosen, plain)
    tight, _ = fit_homography(points, velocity, 0.3, outlier_px=BAND)
    tight_error = plane_error(points, velocity, tight)
    plain_error = plane_error(points, velocity, plain)
    assert mixture_log_likelihood(plain_error, BAND) > mixture_log_likelihood(tight_error, BAND)


def test_a_seed_draws_other_samples_but_finds_the_same_plane():
    # A pan with a fifth of the samples on a mover 3 px/frame off it: every
    # seed must find the pan, and report the inliers in the order given.
    points, velocity = _pan_samples()
    mover = (abs(points[:, 0] - 100) < 60) & (abs(points[:, 1] - 90) < 40)
    velocity[mover, 0] += 3.0
    assert 0.15 < mover.mean() < 0.3
    fits = [fit_homography(points, velocity, 1.0, outlier_px=BAND, seed=s) for s in (0, 1, 7)]
    for homography, inliers in fits:
        assert np.array_equal(inliers, ~mover)
        assert np.median(plane_error(points, velocity, homography)[~mover]) < 0.1
    assert not np.array_equal(fits[0][0], fits[1][0])  # another draw, another estimate
    with pytest.raises(ValueError, match="seed"):
        FitConfig(seed=-1)


def test_planes_scored_together_score_as_one_by_one():
    # fit_homography scores the 1 px and the tight plane in one call; each
    # row must get exactly the score it gets alone (same EM, same sums).
    rng = np.random.default_rng(3)
    errors = [np.abs(rng.standard_t(2, 900)) * s for s in (0.05, 0.3, 1.5)]
    together = mixture_log_likelihood(np.stack(errors), BAND)
    alone = [mixture_log_likelihood(e, BAND) for e in errors]
    assert together.shape == (3,) and list(together) == alone
    assert alone[0] > alone[1] > alone[2]  # tighter errors are likelier


def test_a_judged_field_keeps_the_maps_already_computed():
    field = field_between(background(0.0), background(3.0, 1.0))
    structure, source = field.structure, field.source_px
    judged = field.judged(fit_camera(field, FitConfig()))
    assert judged.camera is not None and judged.structure is structure
    assert judged.source_px is source and judged.velocity_px is field.velocity_px


def test_a_prepared_field_comes_with_its_maps_and_the_fits_first_part():
    from motiondetect.constraint_ray.ahead import Ahead, ahead_of

    detector = MotionDetector("both")
    assert detector.measure_frame(background(0.0)) is None
    measured = detector.measure_frame(background(3.0, 1.0))
    assert not {"structure", "source_px"} & set(vars(measured))  # made when first read
    field = detector.prepare(measured)
    assert {"structure", "source_px"} <= set(vars(field))  # made, not waiting
    assert isinstance(field.ahead, Ahead) and field.ahead.config == detector.fit_config
    fresh = field_between(background(0.0), background(3.0, 1.0))
    np.testing.assert_array_equal(field.source_px, fresh.source_px)
    for made, again in zip(field.structure, fresh.structure, strict=True):
        np.testing.assert_array_equal(made, again)
    # The fit reads what was prepared, and a fit with other settings its own.
    other = FitConfig(tight_px=0.0, sample_step_px=16)
    assert ahead_of(field, detector.fit_config) is field.ahead
    assert len(ahead_of(field, other).points) < len(field.ahead.points)
    assert ahead_of(fresh, other, maps=False).maps is None  # left to the plane the fit keeps
    for config in (detector.fit_config, other):
        fit, again = fit_camera(field, config), fit_camera(fresh, config)
        np.testing.assert_array_equal(fit.homography, again.homography)
        np.testing.assert_array_equal(fit.residual_px, again.residual_px)
        assert (fit.inlier_share, fit.noise_px) == (again.inlier_share, again.noise_px)


@pytest.mark.parametrize("shape", [(48, 64, 2), (300, 2), (2,)])
def test_vector_length_is_the_euclidean_length(shape):
    vectors = np.random.default_rng(1).normal(0, 5, shape).astype(np.float32)
    expected = np.hypot(vectors[..., 0], vectors[..., 1])
    # Contiguous float32 (the fast path), float64, and components swapped (strided).
    for given in (vectors, vectors.astype(np.float64), vectors[..., ::-1]):
        length = vector_length(given)
        assert length.shape == shape[:-1] and length.dtype == np.float32
        np.testing.assert_allclose(length, expected, rtol=1e-6)


def test_a_cut_is_unreliable_and_flags_nothing():
    md = MotionDetector()
    md.process(background(0.0), 0, 0.0)
    other = cv2.resize(cv2.cvtColor(data.chelsea(), cv2.COLOR_RGB2BGR), (W, H))
    result = md.process(other, 1, 0.03)
    assert not result.reliable and result.reason in ("cut", "too few inliers")
    assert result.regions == [] and not result.flagged.any()
    # Known ego-motion can still judge such a frame: the frame-edge band stays.
    fit = result.camera
    assert fit.edge_band_px == pytest.approx(FitConfig().edge_px + fit.median_speed_px)


@pytest.mark.parametrize("dx", [60, 100])
def test_the_strip_a_fast_pan_brings_into_view_is_no_cut(dx):
    """The cut test compares what both frames show. A pan of ``dx`` work px
    a frame, exactly undone by the plane, differs by nothing there; the
    strip entering the view (a fifth to a third of the frame) has no
    previous picture and is left out. A new shot still differs everywhere."""
    from motiondetect.constraint_ray.ahead import plane_maps
    from motiondetect.measurement.dense_flow import VelocityField, pixel_grid
    from motiondetect.measurement.normal_flow import GridGeometry

    def grey(image):
        return cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)

    velocity = np.zeros((H, W, 2), np.float32)
    velocity[..., 0] = -dx
    homography = np.array([[1.0, 0, dx], [0, 1, 0], [0, 0, 1]])  # current to previous pixels
    other = grey(cv2.resize(cv2.cvtColor(data.chelsea(), cv2.COLOR_RGB2BGR), (W, H)))
    config = FitConfig()
    cuts = []
    for now in (grey(background(dx)), other):
        field = VelocityField(
            velocity, now, grey(background(0.0)), GridGeometry((W, H), (W, H)), pixel_grid(W, H)
        )
        inliers = np.ones(len(samples(field, config.sample_step_px)[0]), bool)
        maps = plane_maps(field, homography, inliers, config)
        assert maps.difference[8:-8, -dx:-8].mean() > 50  # the entering strip
        cuts.append(maps.cut)
    assert cuts[0] == 0.0 and cuts[1] > config.cut_grey


@pytest.mark.parametrize("dx", [80, 120])
def test_the_change_noise_is_measured_where_both_frames_see(dx):
    """Sensor noise of 2 grey levels on both frames of an exactly undone pan
    over a mid-grey texture leaves a plane difference of sigma 2 sqrt(2);
    the strip entering the view (a quarter to a third of the frame) differs
    by its whole grey level, and over the whole frame would raise the noise
    every evidence test is scaled by."""
    from motiondetect.constraint_ray.ahead import plane_maps
    from motiondetect.measurement.dense_flow import VelocityField, pixel_grid
    from motiondetect.measurement.image_change import difference_noise
    from motiondetect.measurement.normal_flow import GridGeometry

    rng = np.random.default_rng(dx)
    texture = cv2.GaussianBlur(rng.normal(0.0, 1.0, (H, W + dx)), (0, 0), 3)
    texture = 150 + 50 * texture / np.abs(texture).max()  # 100-200 grey levels

    def noisy(view):
        return np.clip(view + rng.normal(0.0, 2.0, view.shape), 0, 255).round().astype(np.uint8)

    velocity = np.zeros((H, W, 2), np.float32)
    velocity[..., 0] = -dx
    homography = np.array([[1.0, 0, dx], [0, 1, 0], [0, 0, 1]])  # current to previous pixels
    now, previous = noisy(texture[:, dx:]), noisy(texture[:, :W])
    field = VelocityField(velocity, now, previous, GridGeometry((W, H), (W, H)), pixel_grid(W, H))
    config = FitConfig()
    inliers = np.ones(len(samples(field, config.sample_step_px)[0]), bool)
    maps = plane_maps(field, homography, inliers, config)
    assert maps.change_noise == difference_noise(maps.difference[:, : W - dx])
    assert abs(maps.change_noise - (2.0 * np.sqrt(2) + 1.0)) < 0.5  # plus one level
    assert difference_noise(maps.difference) > maps.change_noise + 1.0


def test_a_still_camera_is_static_however_noisy_its_flow():
    """The class follows the plane's own speed: flow noise whose median
    length is 0.35 px/frame (a dim still camera) does not move the camera."""
    from motiondetect.constraint_ray.camera_fit import STATIC_SPEED_PX, CameraFit

    residual, measured = np.zeros((H, W, 2), np.float32), 0.35
    assert measured > STATIC_SPEED_PX  # the old rule would call both frames moving
    for plane_speed, label in ((0.02, "static"), (1.0, "plane (no parallax)")):
        fit = CameraFit(
            np.eye(3), residual, 0.3, 0.9, None, "", measured, plane_speed_px=plane_speed
        )
        assert fit.label == label


def test_off_ray_measures_across_the_line_to_the_epipole():
    epipole = np.array([160.0, 120.0, 1.0])
    points = np.array([[260.0, 120.0], [260.0, 120.0], [160.0, 20.0]])
    residual = np.array([[3.0, 0.0], [0.0, 2.0], [1.5, -4.0]])
    np.testing.assert_allclose(off_ray(residual, points, epipole), [0.0, 2.0, 1.5], atol=1e-6)
    # The blind spot: any motion along the ray, however large, passes.
    assert off_ray(np.array([[40.0, 0.0]]), points[:1], epipole)[0] == pytest.approx(0.0)
    # At infinity (third component 0) every ray is parallel to the epipole's direction.
    far = np.array([1.0, 0.0, 0.0])
    np.testing.assert_allclose(off_ray(residual, points, far), [0.0, 2.0, 4.0], atol=1e-6)
    # Without parallax the whole residual is off the ray.
    np.testing.assert_allclose(off_ray(residual[:1], points[:1], None), [3.0])


def test_distance_to_the_constraint_segment():
    start, step = np.array([1.0, 0.0]), np.array([2.0, 0.0])
    v = np.array([[1.0, 0.0], [4.0, 0.0], [9.0, 0.0], [2.0, 3.0], [-2.0, 0.0]])
    gap = gap_to_segment(v, start, step, bound=3.0)  # segment from x=1 to x=7
    np.testing.assert_allclose(gap, [[0, 0], [0, 0], [2, 0], [0, 3], [-3, 0]], atol=1e-6)
    np.testing.assert_allclose(np.hypot(*gap.T), [0.0, 0.0, 2.0, 3.0, 3.0], atol=1e-6)


def test_image_changed_finds_a_change_and_ignores_noise():
    from motiondetect.constraint_ray.camera_fit import CameraFit

    rng = np.random.default_rng(3)
    diff = np.abs(rng.normal(0, 3.0, (120, 160))).astype(np.uint8)  # the plane explains all
    diff[40:70, 60:100] += 30  # a mover changed the image here
    fit = CameraFit(None, None, 0.0, 1.0, None, plane_difference=diff)
    changed = fit.image_changed(3.0, 5)
    assert changed[45:65, 65:95].all()
    outside = np.ones_like(changed)
    outside[35:75, 55:105] = False
    assert changed[outside].mean() < 0.002


def _jolted_pan() -> tuple[list, set[int]]:
    """A pan with a smooth mover whose frames 9 and 10 are smeared by 5 % of
    the width, and those frames' numbers."""
    from .scenes import scene

    frames = list(scene("pan", ("smooth",), frames=14))
    jolted = {9, 10}
    for i in jolted:
        image = frames[i].image
        frames[i] = dataclasses.replace(frames[i], image=smeared(image, image.shape[1] // 20, 0.3))
    return frames, jolted


def test_a_smeared_frame_is_judged_and_its_mover_found():
    """A jolt smears the picture, not the motion: the flow still measures the
    pan and the mover, so the smeared frames are judged like the others
    (``blur_ratio`` 0, the default), and the mover is covered on them with
    nothing flagged apart from it. Measured: 1.00 and 0.96 of it covered."""
    frames, jolted = _jolted_pan()
    detector = MotionDetector("both")
    for frame in frames:
        result = detector.process(frame.image, frame.index, frame.index / 30)
        if frame.index not in jolted:
            continue
        assert result.reliable
        h, w = frame.mask.shape
        flagged, mover = result.input_mask(w, h) > 0, frame.mask > 0
        assert np.count_nonzero(flagged & mover) >= 0.9 * np.count_nonzero(mover)
        _, parts = cv2.connectedComponents(flagged.view(np.uint8))
        assert set(np.unique(parts[flagged])) <= set(np.unique(parts[flagged & mover]))


def test_heavily_blurred_frames_can_be_marked_unreliable():
    """With ``blur_ratio`` set, a frame whose sharpness falls below that share
    of its recent median says it cannot be judged."""
    frames, jolted = _jolted_pan()
    md = MotionDetector("both", FitConfig(blur_ratio=1 / 3))
    reasons = [md.process(f.image, f.index, f.index / 30).reason for f in frames]
    assert [i for i, r in enumerate(reasons) if r == "heavy blur"] == sorted(jolted)
    default = MotionDetector("both")
    reasons = [default.process(f.image, f.index, f.index / 30).reason for f in frames]
    assert "heavy blur" not in reasons


@pytest.mark.parametrize(
    ("velocity", "forward", "confirmed"),
    [
        ((3.0, 1.0), (3.0, 1.0), True),  # the same motion both ways
        ((0.0, 0.0), (0.7, 0.0), True),  # 0.49 <= 0.01 * 0.49 + 0.5
        ((0.0, 0.0), (0.72, 0.0), False),  # 0.5184 > 0.01 * 0.5184 + 0.5
        ((10.0, 0.0), (11.0, 0.0), True),  # 1 <= 0.01 * 221 + 0.5: the rule grows with speed
        ((10.0, 0.0), (-10.0, 0.0), False),  # a wrong match, as on a periodic texture
    ],
)
def test_forward_backward_check_is_the_published_rule(velocity, forward, confirmed):
    from motiondetect.measurement.dense_flow import confirmed_both_ways, pixel_grid

    h, w = 20, 30
    v = np.tile(np.float32(velocity), (h, w, 1))
    f = np.tile(np.float32(forward), (h, w, 1))
    got = confirmed_both_ways(v, f, pixel_grid(w, h) - v)
    assert got.shape == (h, w) and got.all() == confirmed and got.any() == confirmed


def test_forward_backward_check_reads_the_forward_flow_where_each_pixel_was():
    from motiondetect.measurement.dense_flow import confirmed_both_ways, pixel_grid

    h, w = 40, 60
    v = np.zeros((h, w, 2), np.float32)
    v[:, 30:] = (5.0, 0.0)  # the right half came from 5 px to the left
    f = np.zeros((h, w, 2), np.float32)
    f[:, 25:50] = (5.0, 0.0)  # ... where the forward flow moves it 5 px right
    got = confirmed_both_ways(v, f, pixel_grid(w, h) - v)
    assert got[:, :25].all() and got[:, 30:55].all()  # both halves confirmed
    assert not got[:, 25:30].any()  # still pixels whose source moved away
    assert not got[:, 55:].any()  # moved pixels whose source did not move


def test_forward_backward_check_on_a_list_of_points_equals_the_whole_frame():
    """Points are remapped in rows of at most 4096 (remap's maps hold under
    2^15 columns): 120000 of them give what a whole-frame remap gives."""
    from motiondetect.measurement.dense_flow import confirmed_both_ways, pixel_grid

    h, w = 300, 400
    rng = np.random.default_rng(3)
    v = cv2.GaussianBlur(rng.normal(0, 4, (h, w, 2)).astype(np.float32), (0, 0), 5) * 6
    f = v + cv2.GaussianBlur(rng.normal(0, 3, (h, w, 2)).astype(np.float32), (0, 0), 3) * 2
    source = pixel_grid(w, h) - v
    back = cv2.remap(f, source[..., 0], source[..., 1], cv2.INTER_LINEAR,
                     borderMode=cv2.BORDER_REPLICATE)  # fmt: skip
    gap2 = ((back - v) ** 2).sum(axis=-1)
    expected = gap2 <= 0.01 * ((back**2).sum(axis=-1) + (v**2).sum(axis=-1)) + 0.5
    assert 0.2 < expected.mean() < 0.8  # both answers are common
    assert np.array_equal(confirmed_both_ways(v, f, source), expected)
    ys, xs = np.nonzero(rng.random((h, w)) < 0.3)
    assert np.array_equal(confirmed_both_ways(v[ys, xs], f, source[ys, xs]), expected[ys, xs])
    none = np.zeros((0, 2), np.float32)  # no points: an empty answer, not remap's error
    assert confirmed_both_ways(none, f, none).shape == (0,)
