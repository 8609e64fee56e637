"""Regression on the committed sample videos and their exact ground truth.

Measured with the defaults (object recall / cell F1 / false-alarm regions
per frame), and with each clip's true camera motion. The bounds sit just past
these figures, so any regression fails; improvements should tighten them.
The rigid-only scene's false alarms were DIS's errors (matches to the wrong
brick of the wall, and content entering the view or uncovered by the near
boxes); the forward-backward check takes most of them out (docs/detectors.md).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from motiondetect.constraint_ray.egomotion import EgoMotion
from motiondetect.detection.detector import MotionDetector
from motiondetect.io.video import open_source, read_mask
from motiondetect.measurement.dense_flow import DenseFlowConfig
from motiondetect.tools.evaluate import Counts, score_frame

SAMPLES = Path(__file__).resolve().parents[1] / "sample_videos"

#: sample -> (min object recall, min cell F1, max FA/frame); measured figures in comments.
BOUNDS = {
    "fixation_waving": (0.90, 0.68, 0.5),  # 0.95 / 0.72 / 0.38
    "forward_crossing": (0.93, 0.94, 0.15),  # 0.96 / 0.97 / 0.07
    "forwardyaw_waving": (0.85, 0.72, 0.1),  # 0.90 / 0.75 / 0.03
    "handheld_emerging": (0.92, 0.93, 0.1),  # 0.94 / 0.96 / 0.00
    "oblique_crossing": (0.95, 0.94, 0.1),  # 1.00 / 0.97 / 0.02
    "pan_blindspot": (0.58, 0.66, 0.1),  # 0.61 / 0.69 / 0.02 (one mover is on its ray)
    "static_walker": (0.95, 0.96, 0.1),  # 1.00 / 0.99 / 0.00
    "uniform_mixed": (0.90, 0.92, 0.15),  # 0.94 / 0.95 / 0.09
    "uniform_rigid": (None, None, 0.1),  # - / - / 0.05: no mover at all (issue 13's line)
}


#: With the true camera motion (``scene.json`` as ``--egomotion``), the
#: constraint ray alone; measured figures in comments. Before its rigid-scene
#: false alarms were gated like the fitted path's, uniform_rigid gave 3.14 per
#: frame and the movers' scenes 1.98-3.48 (docs/egomotion.md); before the
#: forward-backward check, 0.59, and forward_crossing 0.50.
KNOWN_BOUNDS = {
    # The walker leaving the frame on the last two frames is covered on 6-8 % of
    # its pixels once outlined by the image change (11-15 % with the wider
    # gate's band), under object recall's 10 %: 0.94 against 1.00.
    "forward_crossing": (0.92, 0.94, 0.1),  # 0.94 / 0.97 / 0.03
    "oblique_crossing": (0.95, 0.94, 0.1),  # 1.00 / 0.96 / 0.02
    "uniform_rigid": (None, None, 0.1),  # - / - / 0.02: no mover at all
}


def sample_counts(folder: Path, detector: MotionDetector) -> Counts:
    """The detector's scores over a sample clip, after its two warm-up frames."""
    counts = Counts()
    with open_source(folder / "video.mp4") as source:
        for frame in source:
            result = detector.process(frame.image, frame.index, frame.time_s)
            if frame.index < 2:
                continue
            truth = read_mask(folder / "truth" / f"{frame.index:06d}.png")
            h, w = truth.shape
            counts.add(score_frame(result.input_mask(w, h), truth))
    return counts


def check_bounds(counts: Counts, bounds: tuple) -> None:
    min_recall, min_cell_f1, max_false_alarms = bounds
    m = counts.metrics()
    assert m["frames"] == 58
    assert m["false_alarm_regions_per_frame"] <= max_false_alarms
    if min_recall is not None:
        assert m["object_recall"] >= min_recall
        assert m["cell_f1"] >= min_cell_f1


@pytest.mark.parametrize("name", sorted(BOUNDS))
def test_sample_against_its_truth(name):
    check_bounds(sample_counts(SAMPLES / name, MotionDetector()), BOUNDS[name])


@pytest.mark.parametrize("name", sorted(KNOWN_BOUNDS))
def test_sample_with_its_true_camera_motion(name):
    folder = SAMPLES / name
    detector = MotionDetector("constraint-ray", egomotion=EgoMotion.load(folder / "scene.json"))
    check_bounds(sample_counts(folder, detector), KNOWN_BOUNDS[name])


def _rigid_only_run(output, **sections):
    """``process_input`` on the rigid-only sample, with config ``sections``."""
    from motiondetect.app.inputs import InputJob
    from motiondetect.app.process import process_input
    from motiondetect.app.settings import make_settings

    clip = SAMPLES / "uniform_rigid" / "video.mp4"
    settings = make_settings({"output": output, "video": False, "timeline": False, **sections})
    return process_input(InputJob(clip, "rigid"), settings)


def test_rigid_only_scene_has_no_event_and_the_two_way_check_is_why(tmp_path):
    result = _rigid_only_run(tmp_path)
    assert result.status == "done" and result.summary["totals"]["events"] == 0
    unchecked = MotionDetector("both", DenseFlowConfig(check_preset="off"))
    m = sample_counts(SAMPLES / "uniform_rigid", unchecked).metrics()
    assert m["false_alarm_regions_per_frame"] > 0.2  # 0.34: DIS's errors, unchecked


@pytest.mark.parametrize("seed", [1, 2])
def test_rigid_only_scene_has_no_event_on_other_ransac_draws(tmp_path, seed):
    # Behind a near box's trailing edge the view uncovers wall whose flow DIS
    # fills in wrongly, by up to 6 px, for frames: the summed residual added
    # it up and flagged it on 3 frames of 60 (an event) on seeds 1-7, until
    # its seeds too had to be confirmed by the flow measured the other way.
    result = _rigid_only_run(tmp_path, fit={"seed": seed})
    assert result.status == "done" and result.summary["settings"]["configs"]["fit"]["seed"] == seed
    assert result.summary["totals"]["events"] == 0
    assert result.summary["totals"]["detections"] <= 1


def _after_gaps(folder: Path, detector: MotionDetector) -> Counts:
    """Scores on the frames after a gap, every fourth frame's file dropped
    (as a frames folder skips an unreadable file)."""
    counts = Counts()
    with open_source(folder / "video.mp4") as source:
        for frame in source:
            if frame.index % 4 == 3:
                continue  # the unreadable file
            result = detector.process(frame.image, frame.index, frame.time_s)
            if frame.index % 4 == 0 and frame.index > 2:
                truth = read_mask(folder / "truth" / f"{frame.index:06d}.png")
                counts.add(score_frame(result.input_mask(*truth.shape[::-1]), truth))
    return counts


def test_known_motion_is_composed_across_a_skipped_frame():
    """A frame file skipped as unreadable leaves the flow spanning two steps:
    the known motion is both steps composed, exactly the poses' difference.
    On the velocity path the mover is then found on the frames after each
    gap (0.96 of them; 0.57 with the single step the file gives for that
    frame); on the normal path the false alarms there fall (0.21 regions a
    frame against 1.00)."""
    folder = SAMPLES / "pan_blindspot"
    ego = EgoMotion.load(folder / "scene.json")
    poses = {
        e["frame"]: np.asarray(e["camera_to_world"])
        for e in json.loads((folder / "scene.json").read_text())["frames"]
    }
    rotation, translation = ego.spanning(4, 6)
    direct = np.linalg.inv(poses[6]) @ poses[4]  # opencv convention: no flip
    assert np.allclose(rotation, direct[:3, :3]) and np.allclose(translation, direct[:3, 3])
    assert ego.spanning(6, 6) is None and ego.spanning(-2, 1) is None
    velocity = _after_gaps(folder, MotionDetector("constraint-ray", egomotion=ego))
    assert velocity.frames == 14 and velocity.metrics()["object_recall"] >= 0.85
    normal = _after_gaps(folder, MotionDetector("constraint-ray", measure="normal", egomotion=ego))
    assert normal.metrics()["false_alarm_regions_per_frame"] <= 0.5
