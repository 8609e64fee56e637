"""Detector 1: geometry, bit encoding, Hough, classes and scenes (issue 3)."""

from __future__ import annotations

import numpy as np
import pytest

from motiondetect.constraint_ray import normal_filter as cr
from motiondetect.constraint_ray.egomotion import EgoMotion
from motiondetect.constraint_ray.hough import STILL, UNKNOWN, coarse_field
from motiondetect.constraint_ray.normal_filter import ConstraintRayConfig
from motiondetect.constraint_ray.observer_motion import UNBOUNDED, canonical_library, classify
from motiondetect.measurement.normal_flow import GridGeometry, NormalFlowField

from .scenes import class_accuracy, run_detector, scene

RNG = np.random.default_rng(7)


# --- Figure 4 geometry --------------------------------------------------------


def test_xor_of_disks_matches_brute_force_sampling_of_the_segment():
    for _ in range(200):
        v1, v2 = RNG.normal(0, 3, 2), RNG.normal(0, 3, 2)
        theta = RNG.uniform(0, 2 * np.pi)
        n = np.array([np.cos(theta), np.sin(theta)])
        s = np.linspace(0, 1, 4001)[:, None]
        projections = (v1 + s * (v2 - v1)) @ n  # every normal flow the segment allows
        m = RNG.uniform(-6, 6)
        brute = projections.min() - 1e-3 <= m <= projections.max() + 1e-3
        margin = min(abs(m - projections.min()), abs(m - projections.max()), abs(m))
        if margin < 1e-2:
            continue  # on a boundary (or the origin, which XOR excludes): measure zero
        assert bool(cr.xor_of_disks(m * n, v1, v2)) == brute
        lo, hi = cr.allowed_interval(v1, v2 - v1, 1.0, n[0], n[1])
        assert (lo <= m <= hi) == brute


def test_unbounded_depth_is_a_disk_and_a_half_plane():
    for _ in range(200):
        vw, vxy = RNG.normal(0, 2, 2), RNG.normal(0, 2, 2)
        theta = RNG.uniform(0, 2 * np.pi)
        n = np.array([np.cos(theta), np.sin(theta)])
        m = RNG.uniform(-8, 8)
        lo, hi = cr.allowed_interval(vw, vxy, UNBOUNDED, n[0], n[1])
        e1, slope = vw @ n, vxy @ n
        if abs(m) < 1e-2 or abs(m - e1) < 1e-2 or abs(slope) < 1e-2:
            continue
        expected = (m >= e1) if slope > 0 else (m <= e1)
        assert (lo <= m <= hi) == expected
        assert bool(cr.disk_and_half_plane(m * n, vw, vxy)) == expected
        far = vw + 1e6 * vxy  # a finite segment tends to the same region
        assert bool(cr.xor_of_disks(m * n, vw, far)) == expected


def test_interval_bit_encoding_round_trip():
    for lo, hi in [(-0.3, 0.3), (0.5, 4.0), (-8.0, -1.0), (1.1, 1.2), (-100.0, 100.0)]:
        mask = int(cr.encode_interval(np.array(lo), np.array(hi)))
        a, b = cr.decode_mask(mask)
        assert a <= lo and b >= hi  # the encoding never forbids an allowed value
        bits = [i for i in range(32) if mask >> i & 1]
        assert bits == list(range(bits[0], bits[-1] + 1))  # contiguous


def test_bit_test_agrees_with_the_exact_interval():
    vw = np.full((64, 64, 2), [0.5, 0.0], np.float32)
    vxy = np.full((64, 64, 2), [1.0, 0.2], np.float32)
    from motiondetect.constraint_ray.observer_motion import ObserverMotion

    model = ObserverMotion(1, {}, 1.0, vw, vxy, 3.0)
    filt = cr.filter_image(model)
    assert filt.shape == (64, 64, 16)
    theta = RNG.uniform(-np.pi, np.pi, (64, 64)).astype(np.float32)
    m = RNG.uniform(-6, 6, (64, 64)).astype(np.float32)
    field = NormalFlowField(
        m,
        theta,
        np.ones_like(m),
        np.ones((64, 64), bool),
        np.zeros((64, 64), np.uint8),
        GridGeometry((512, 512), (512, 512)),
    )
    tol = np.full((64, 64), 0.05, np.float32)
    flagged = cr.check_measurements(model, field, tol)
    lo, hi = cr.allowed_interval(vw, vxy, 3.0, np.cos(theta), np.sin(theta))
    outside = (m + 1.0 < lo) | (m - 1.0 > hi)  # clearly outside: must be flagged
    inside = (m >= lo) & (m <= hi)  # inside: must never be flagged
    assert flagged[outside].mean() > 0.95
    assert not flagged[inside].any()


# --- Hough and classification ---------------------------------------------------


def synthetic_field(flow_fn, geometry=None, noise=0.0):
    geometry = geometry or GridGeometry((512, 512), (512, 512))
    x, y = geometry.cell_centres_px()
    vx, vy = flow_fn(x, y)
    theta = RNG.uniform(-np.pi, np.pi, (64, 64)).astype(np.float32)
    m = vx * np.cos(theta) + vy * np.sin(theta) + RNG.normal(0, noise, (64, 64))
    return NormalFlowField(
        m.astype(np.float32),
        theta,
        np.full((64, 64), 20.0, np.float32),
        np.ones((64, 64), bool),
        np.zeros((64, 64), np.uint8),
        geometry,
    )


@pytest.mark.parametrize("angle_deg", [0, 30, 90, 135, 200, 315])
def test_hough_recovers_a_known_uniform_flow(angle_deg):
    a = np.deg2rad(angle_deg)
    v = 2.5 * np.array([np.cos(a), np.sin(a)])
    coarse = coarse_field(synthetic_field(lambda x, y: (v[0] + 0 * x, v[1] + 0 * y), noise=0.05))
    assert coarse.known.all()
    np.testing.assert_allclose(coarse.flow_px.reshape(-1, 2), np.tile(v, (16, 1)), atol=0.1)
    assert (coarse.direction_index == round(angle_deg / 45) % 8).all()


def test_hough_says_unknown_where_there_is_no_data():
    field = synthetic_field(lambda x, y: (1.0 + 0 * x, 0 * y))
    valid = field.valid.copy()
    valid[:16, :16] = False
    field = NormalFlowField(
        field.flow_px, field.direction_rad, field.gradient, valid, field.level, field.geometry
    )
    coarse = coarse_field(field)
    assert coarse.direction_index[0, 0] == UNKNOWN
    assert coarse.known.sum() == 15


def test_still_regions_and_static_observer():
    coarse = coarse_field(synthetic_field(lambda x, y: (0 * x, 0 * y), noise=0.02))
    assert (coarse.direction_index == STILL).all()
    _, class_id, conf = classify(coarse, GridGeometry((512, 512), (512, 512)))
    assert class_id == 0 and conf > 0.9


W4, H4 = 512, 384


def _expansion(focus, rate=0.01):
    return lambda x, y: (rate * (x - focus[0]), rate * (y - focus[1]))


# Flow fields of known observer motions (not the library's own templates).
KNOWN_MOTIONS = {
    "translation right": (lambda x, y: (2.0 + 0 * x, 0 * y), {1}),
    "translation down-left": (lambda x, y: (-1.5 + 0 * x, 1.5 + 0 * y), {1}),
    "forward, focus at the centre": (_expansion((W4 / 2, H4 / 2)), {2}),
    "forward, focus off centre": (_expansion((0.25 * W4, 0.7 * H4)), {2, 3}),
    "backward (contraction)": (_expansion((W4 / 2, H4 / 2), rate=-0.01), {2, 3}),
    "fixation: near half one way, far half the other": (
        lambda x, y: (np.where(y > H4 / 2, -2.0, 2.0), 0 * y),
        {5},
    ),
}


@pytest.mark.parametrize("name", sorted(KNOWN_MOTIONS))
def test_known_observer_motions_classify_right(name):
    flow, classes = KNOWN_MOTIONS[name]
    geometry = GridGeometry((W4, H4), (W4, H4))
    coarse = coarse_field(synthetic_field(flow, geometry, noise=0.05))
    _, class_id, confidence = classify(coarse, geometry)
    assert class_id in classes and confidence > 0.3


def test_library_has_all_five_classes():
    ids = {e.class_id for e in canonical_library(GridGeometry((320, 240), (512, 384)))}
    assert ids == {1, 2, 3, 4, 5}


# --- Synthetic scenes with exact ground truth --------------------------------------

# Per class: (minimum class accuracy, minimum object recall, maximum false-alarm
# regions per frame on the rigid scene), on these 24-frame test scenes. Measured
# (class accuracy / object recall / FA per frame): static 1.00 / 1.00 / 0.00,
# uniform 1.00 / 1.00 / 0.18, pan 1.00 / 1.00 / 0.05, forward 1.00 / 0.64 / 0.14,
# oblique 1.00 / 1.00 / 0.36, forward-yaw 0.59 / 0.68 / 0.73, fixation 1.00 /
# 0.00 / 0.00 (the fixation miss is documented in docs/detectors.md). The bounds
# sit just past those figures, so a regression fails.
SCENE_BOUNDS = {
    "static": (0.95, 0.95, 0.05),
    "uniform": (0.95, 0.95, 0.3),
    "pan": (0.95, 0.95, 0.15),
    "forward": (0.95, 0.55, 0.25),
    "oblique": (0.95, 0.95, 0.45),
    "forward-yaw": (0.5, 0.55, 0.85),
    "fixation": (0.95, None, 0.1),
}


@pytest.mark.slow
@pytest.mark.parametrize("camera", list(SCENE_BOUNDS))
def test_scene_classes_recall_and_false_alarms(camera):
    min_class, min_recall, max_fa = SCENE_BOUNDS[camera]
    rigid, classes, _ = run_detector(scene(camera))
    assert class_accuracy(camera, classes) >= min_class
    metrics = rigid.metrics()
    assert metrics["false_alarm_regions_per_frame"] <= max_fa
    if min_recall is not None:
        moving, _, _ = run_detector(scene(camera, ("smooth",)))
        assert moving.metrics()["object_recall"] >= min_recall


@pytest.mark.slow
def test_blind_spot_motion_along_the_constraint_ray_is_not_flagged():
    """Section 3.3: an object moving in the background flow's direction is missed."""
    counts, _, _ = run_detector(
        scene("uniform", ("on-ray",)), constraint_ray=ConstraintRayConfig(ego_model="paper")
    )
    assert counts.metrics()["object_recall"] <= 0.1
    off_ray, _, _ = run_detector(
        scene("uniform", ("smooth",)), constraint_ray=ConstraintRayConfig(ego_model="paper")
    )
    assert off_ray.metrics()["object_recall"] >= 0.8


def test_tracking_shot_needs_the_fitted_lower_bound():
    """NOTES 3: a followed subject has near-zero flow while the world streams past."""
    subject = np.zeros((64, 64), bool)
    subject[24:40, 24:40] = True

    def flow(x, y):
        background = np.where(subject, 0.0, -3.0 - 0.5 * (y / 512))  # depth varies
        return background, 0 * y

    field = synthetic_field(flow, noise=0.05)
    fitted = cr.ConstraintRayDetector(ConstraintRayConfig(ego_model="fitted")).process(field)
    paper = cr.ConstraintRayDetector(ConstraintRayConfig(ego_model="paper")).process(field)
    assert fitted.observer.class_id == paper.observer.class_id == 1
    assert fitted.observer.params["speed_range"][0] > 2.0
    assert fitted.flagged[subject].mean() > 0.5
    assert fitted.flagged[~subject].mean() < 0.02
    assert paper.flagged[subject].mean() < 0.05


@pytest.mark.slow
@pytest.mark.parametrize("camera", ["forward", "uniform"])
def test_known_egomotion_detects_the_mover(tmp_path, camera):
    from motiondetect.tools.synth import SynthConfig, write_sequence

    config = SynthConfig(camera=camera, movers=("smooth",), frames=16, supersample=1)
    write_sequence(config, tmp_path)
    ego = EgoMotion.load(tmp_path / "scene.json")
    counts, classes, _ = run_detector(scene(camera, ("smooth",), frames=16), egomotion=ego)
    assert set(classes) == {6}
    assert counts.metrics()["object_recall"] >= 0.9
    assert counts.metrics()["false_alarm_regions_per_frame"] <= 0.3
