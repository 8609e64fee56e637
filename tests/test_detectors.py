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
