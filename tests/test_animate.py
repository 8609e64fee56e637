"""Detector 2: footprints, bit encoding, the constraint map and scenes (issue 4)."""

from __future__ import annotations

import numpy as np
import pytest

from motiondetect import animate as an
from motiondetect.animate import AnimateConfig
from motiondetect.pipeline import GridGeometry, NormalFlowField

from .scenes import run_detector, scene

SQUARE = GridGeometry((512, 512), (512, 512))  # 8 px cells


@pytest.mark.parametrize("k", range(16))
def test_footprint_geometry_for_each_direction(k):
    angle = k * 2 * np.pi / 16
    along = np.array([np.cos(angle), np.sin(angle)])
    cells = an.footprint_cells(16.0, angle, (8.0, 8.0), max_speed_px=16.0, counterflow_cells=1.0)
    offsets = cells[:, ::-1].astype(float) * 8.0  # (dx, dy) in px
    proj = offsets @ along
    assert (0, 0) in {tuple(c) for c in cells}  # through the generating point
    assert proj.max() >= 16.0 - 6  # reaches the predicted position
    assert proj.min() <= -8.0 + 6  # and a little beyond on the counterflow side
    assert proj.min() >= -8.0 - 6  # but no further
    assert proj.max() <= 16.0 + 6
    across = offsets @ np.array([-along[1], along[0]])
    assert np.abs(across).max() <= 6  # no speed left to move across the flow


def test_footprint_bar_spans_the_constraint_line():
    cells = an.footprint_cells(0.0, 0.0, (8.0, 8.0), max_speed_px=16.0, counterflow_cells=0.0)
    # m = 0 along x: anywhere up to 16 px along y is possible.
    assert {(-2, 0), (2, 0)} <= {tuple(c) for c in cells}
    assert (0, 2) not in {tuple(c) for c in cells}


def test_value_bit_encoding_round_trip():
    for d in range(an.VALUE_DIRECTIONS):
        for mag in range(an.VALUE_MAGNITUDES):
            bit = an.encode_bit(d, mag)
            assert an.decode_bit(bit) == ("moving", d, mag)
            angle = d * 2 * np.pi / an.VALUE_DIRECTIONS
            speed = [0.45, 0.9, 1.8, 3.6, 7.2, 12.0][mag]
            assert an.value_bits(np.array(speed), np.array(angle), 0.3) == bit
            assert an.value_bits(np.array(-speed), np.array(angle + np.pi), 0.3) == bit
    assert an.decode_bit(an.STILL_BIT) == ("still", -1, -1)
    assert an.value_bits(np.array(0.1), np.array(1.0), 0.3) == an.STILL_BIT


def field_with(values: dict, geometry=SQUARE) -> NormalFlowField:
    flow = np.zeros((64, 64), np.float32)
    theta = np.zeros((64, 64), np.float32)
    valid = np.zeros((64, 64), bool)
    for (r, c), (m, t) in values.items():
        flow[r, c], theta[r, c], valid[r, c] = m, t, True
    return NormalFlowField(
        flow,
        theta,
        np.full((64, 64), 20.0, np.float32),
        valid,
        np.zeros((64, 64), np.uint8),
        geometry,
    )


def test_overlapping_footprints_or_together():
    cfg = AnimateConfig()
    left = field_with({(30, 30): (1.0, 0.0)})
    right = field_with({(30, 31): (3.0, np.pi / 2)})
    both = field_with({(30, 30): (1.0, 0.0), (30, 31): (3.0, np.pi / 2)})
    m1, m2, m12 = (an.constraint_map(f, cfg) for f in (left, right, both))
    np.testing.assert_array_equal(m12, m1 | m2)
    overlap = (m1 != 0) & (m2 != 0)
    assert overlap.any()
    assert all(bin(int(v)).count("1") >= 2 for v in m12[overlap])


def test_a_reversal_is_flagged_and_continuation_is_not():
    cfg = AnimateConfig(min_neighbours=0, min_cells=1, jitter_compensation=False, border_cells=0)
    block = {(r, c): (2.0, 0.0) for r in range(28, 36) for c in range(28, 36)}
    same = {(r, c): (2.0, 0.0) for r in range(28, 36) for c in range(29, 37)}
    reverse = {(r, c): (-2.0, 0.0) for r in range(28, 36) for c in range(29, 37)}
    det = an.AnimateDetector(cfg)
    det.process(field_with(block))
    assert not det.process(field_with(same)).flagged.any()
    det = an.AnimateDetector(cfg)
    det.process(field_with(block))
    assert det.process(field_with(reverse)).flagged.sum() >= 32


def test_first_appearance_policy():
    empty = field_with({})
    new = field_with({(r, c): (3.0, 0.0) for r in range(20, 26) for c in range(20, 26)})
    for policy, expected in (("ignore", False), ("flag", True)):
        det = an.AnimateDetector(AnimateConfig(first_appearance=policy, min_neighbours=0))
        det.process(empty)
        assert det.process(new).flagged.any() == expected


def test_global_flow_recovers_a_uniform_shift():
    rng = np.random.default_rng(3)
    theta = rng.uniform(-np.pi, np.pi, (64, 64)).astype(np.float32)
    v = np.array([1.5, -0.7])
    m = (v[0] * np.cos(theta) + v[1] * np.sin(theta)).astype(np.float32)
    m[:8] = 9.0  # a mover must not drag it
    field = NormalFlowField(
        m,
        theta,
        np.full((64, 64), 20.0, np.float32),
        np.ones((64, 64), bool),
        np.zeros((64, 64), np.uint8),
        SQUARE,
    )
    np.testing.assert_allclose(an.global_flow(field), v, atol=0.05)


# --- Synthetic scenes ---------------------------------------------------------

PERIOD = 20  # a reversal every 10 frames


def reversal_recall(results, frames) -> tuple[float, float]:
    near, other = [], []
    for res, fr in zip(results, frames):
        if fr.index < 2 or 1 not in fr.visible:
            continue
        obj = fr.movers == 1
        if obj.sum() < 50:
            continue
        import cv2

        flag = cv2.resize(
            res.flagged.astype(np.uint8), obj.shape[::-1], interpolation=cv2.INTER_NEAREST
        ).astype(bool)
        hit = flag[obj].mean() >= 0.1
        phase = (fr.index % (PERIOD / 2)) - PERIOD / 4
        (near if abs(phase) <= 1.5 else other).append(hit)
    return float(np.mean(near)), float(np.mean(other))


@pytest.mark.slow
def test_oscillating_object_is_flagged_near_its_reversals():
    frames = scene("uniform", ("animate",), frames=44, period_frames=PERIOD)
    _, _, results = run_detector(frames, "animate")
    near, _ = reversal_recall(results, frames)
    # Measured 0.58 (docs/detectors.md); the target of 0.8 is not met yet.
    assert near >= 0.5


@pytest.mark.slow
def test_smooth_and_emerging_objects_are_rarely_flagged():
    for movers in (("smooth",), ("emerging",)):
        counts, _, _ = run_detector(scene("uniform", movers, frames=30), "animate")
        assert counts.metrics()["object_recall"] <= 0.15


@pytest.mark.slow
def test_rigid_scene_false_alarms():
    counts, _, _ = run_detector(scene("uniform", frames=30), "animate")
    # Measured 0.34 regions/frame; the target of 0.2 is not met yet.
    assert counts.metrics()["false_alarm_regions_per_frame"] <= 0.5


@pytest.mark.slow
def test_jitter_compensation_helps():
    frames = scene("uniform", frames=30, jitter_deg=0.15)
    on, _, _ = run_detector(frames, "animate", animate=AnimateConfig(jitter_compensation=True))
    off, _, _ = run_detector(frames, "animate", animate=AnimateConfig(jitter_compensation=False))
    fa_on = on.metrics()["false_alarm_regions_per_frame"]
    fa_off = off.metrics()["false_alarm_regions_per_frame"]
    assert fa_on * 4 < fa_off


@pytest.mark.slow
def test_both_detectors_fused_record_who_found_what():
    frames = scene("uniform", ("smooth", "animate"), frames=24, period_frames=PERIOD)
    _, _, results = run_detector(frames, "both")
    found = {d for res in results for r in res.regions for d in r.detectors}
    assert found == {"constraint-ray", "animate"}
    for res in results:
        for r in res.regions:
            for name in r.detectors:
                assert res.outputs[name].flagged[r.cells[:, 0], r.cells[:, 1]].any()
