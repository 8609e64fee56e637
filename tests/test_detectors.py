"""Every registered detector satisfies the Detector protocol and runs on a sample clip."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from motiondetect.detection.base import DETECTOR_SETS, Detector, DetectorOutput, registry
from motiondetect.detection.detector import FrameResult, MotionDetector
from motiondetect.io.video import open_source

SAMPLE = Path(__file__).resolve().parents[1] / "sample_videos" / "uniform_mixed"
MEASURE_OF = {
    name: m for m, sets in DETECTOR_SETS.items() for names in sets.values() for name in names
}


@pytest.mark.parametrize("name", sorted(registry()))
def test_detector_satisfies_the_protocol_and_runs(name):
    cls = registry()[name]
    detector = cls()
    assert isinstance(detector, Detector)
    assert cls.name == name and cls.measurement == MEASURE_OF[name]
    assert isinstance(detector.config, cls.config_type)
    kind = next(k for k, names in DETECTOR_SETS[cls.measurement].items() if names == (name,))
    md = MotionDetector(kind, measure=cls.measurement, persistence=1)
    flagged_on_mover = 0
    with open_source(SAMPLE / "video.mp4") as source:
        for frame in source:
            result = md.process(frame.image, frame.index, frame.time_s)
            if frame.index == 0:
                assert result.warm_up
                continue
            out = result.outputs[name]
            assert isinstance(out, DetectorOutput)
            assert out.flagged.shape == (64, 64) and out.flagged.dtype == bool
            assert out.strength.shape == (64, 64)
            assert np.all((out.strength >= 0) & (out.strength <= 1))
            flagged_on_mover += bool(result.regions)
            if frame.index >= 30:
                break
    assert flagged_on_mover > 0  # the sample has movers every detector can see
    detector.reset()  # and reset is callable on a fresh detector


def test_registry_names_match_the_detector_sets():
    named = {n for sets in DETECTOR_SETS.values() for names in sets.values() for n in names}
    assert named == set(registry())


def test_input_mask_keeps_the_work_mask_centred():
    """Scaling a work mask to the input maps pixel centres to pixel centres
    (no half-pixel shift at a non-integer scale)."""
    mask = np.zeros((9, 16), bool)
    mask[3:6, 5:9] = True  # centre (6.5, 4) in work pixels
    result = FrameResult(0, 0.0, [], np.zeros((64, 64), bool), None, None, None, mask=mask)
    ys, xs = np.nonzero(result.input_mask(43, 24))
    assert abs(xs.mean() - ((6.5 + 0.5) * 43 / 16 - 0.5)) < 0.5
    assert abs(ys.mean() - ((4 + 0.5) * 24 / 9 - 0.5)) < 0.5


def test_a_velocity_output_derives_its_grid_from_the_pixel_mask():
    """The 64x64 grid of the velocity path is computed when first read, and
    is what the pixel mask and strength give (each flagged cell a quarter
    flagged, its strength the cell's mean)."""
    mask = np.zeros((256, 320), bool)
    mask[40:80, 100:160] = True  # cells 10-19 down, 20-31 across
    strength = np.where(mask, 0.5, 0.0).astype(np.float32)
    out = DetectorOutput.from_mask(mask, strength)
    assert out.grid is None and out.grid_strength is None
    rows, cols = np.nonzero(out.flagged)
    assert (rows.min(), rows.max(), cols.min(), cols.max()) == (10, 19, 20, 31)
    np.testing.assert_allclose(out.strength[out.flagged], 0.5, atol=1e-6)
    assert not out.strength[~out.flagged].any()
    assert out.flagged is out.flagged  # computed once
    empty = DetectorOutput.from_mask(np.zeros_like(mask), strength * 0)
    assert empty.grid is not None and not empty.flagged.any()
