"""The shared config range check: every config rejects NaN, negatives and bad choices."""

from __future__ import annotations

import math

import pytest

from motiondetect.animate.normal_footprints import AnimateConfig
from motiondetect.animate.velocity_footprints import VelocityAnimateConfig
from motiondetect.constraint_ray.fit_config import FitConfig
from motiondetect.constraint_ray.normal_filter import ConstraintRayConfig
from motiondetect.constraint_ray.velocity_filter import VelocityRayConfig
from motiondetect.detection.objects import TrackConfig
from motiondetect.measurement.dense_flow import DenseFlowConfig

CASES = [
    (AnimateConfig, "noise_grey", "accel_px", ("first_appearance", "sometimes")),
    (ConstraintRayConfig, "noise_sigmas", None, ("ego_model", "guess")),
    (FitConfig, "ransac_px", "min_inlier_share", None),
    (VelocityRayConfig, "floor_px", "close_px", None),
    (VelocityAnimateConfig, "floor_px", "spread_px", None),
    (TrackConfig, "persistence", "gap_px", None),
    (DenseFlowConfig, "work_size", None, ("preset", "slowest")),
]


@pytest.mark.parametrize(("cls", "positive", "non_negative", "choice"), CASES)
def test_configs_reject_out_of_range_values(cls, positive, non_negative, choice):
    cls()  # the defaults are valid
    for bad in (0, -1, math.nan, "big"):
        with pytest.raises(ValueError, match=positive):
            cls(**{positive: bad})
    if non_negative:
        cls(**{non_negative: 0})
        for bad in (-1, math.nan):
            with pytest.raises(ValueError, match=non_negative):
                cls(**{non_negative: bad})
    if choice:
        with pytest.raises(ValueError, match=choice[0]):
            cls(**{choice[0]: choice[1]})


def test_the_edge_error_ratio_is_at_least_one():
    VelocityRayConfig(edge_error_ratio=1.0)  # off
    for bad in (0.5, 0, -2, math.nan, "big", True):
        with pytest.raises(ValueError, match="edge_error_ratio"):
            VelocityRayConfig(edge_error_ratio=bad)
