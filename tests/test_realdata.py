"""Real clips from ../shared/data (skipped when absent): runs complete, outputs valid."""

from __future__ import annotations

import json

import cv2
import numpy as np
import pytest
from click.testing import CliRunner
from motiondetect_cli.main import main

from motiondetect.detection.detector import MotionDetector
from motiondetect.detection.objects import TrackConfig
from motiondetect.io.video import open_source
from motiondetect.tools.evaluate import evaluate_sequence

from .cli_outputs import check_outputs
from .conftest import shared_path

pytestmark = pytest.mark.realdata


def detect(tmp_path, source, *extra):
    result = CliRunner().invoke(
        main,
        [
            "detect",
            str(source),
            "-o",
            str(tmp_path),
            "-q",
            "--no-video",
            "--masks",
            *map(str, extra),
        ],
    )
    assert result.exit_code == 0, result.output
    return tmp_path / (source.name if source.is_dir() else source.stem)


# Measured with the defaults (object recall, cell F1, false-alarm regions per frame):
# blackswan 1.00 / 0.58 / 1.35, birds 0.64 / 0.11 / 2.14, IBMtest2 1.00 / 0.86 / 0.05.
# The bounds sit under (or over) those figures so that a regression fails. Keeping
# only pixels near an image change (TrackConfig.support_sigmas) raised cell F1 from
# 0.46 / 0.05 / 0.58; it also splits flagged water and sky into more pieces, which
# raised the false-alarm counts of blackswan and birds from 0.21 / 0.64.
@pytest.mark.parametrize(
    ("folder", "frames_dir", "min_object_recall", "min_cell_f1", "max_false_alarms"),
    [
        ("davis/blackswan", "JPEGImages", 0.9, 0.48, 1.8),
        # A fast pan over motion-blurred grass: judged since the fit's confidence
        # counts what the image determines (0.92 / 0.46 / 0.33; before, 22 of 62
        # frames had "too few inliers": 0.55 / 0.32 / 0.05). Outlining objects by
        # the image change (TrackConfig.outline_px) gives 0.84 / 0.46 / 0.31: on
        # five frames the followed rider is covered on 5-8 % of its pixels, not
        # 16-24 %, where the wider band reached into it.
        ("davis/motocross-bumps", "JPEGImages", 0.8, 0.40, 0.6),
        # A plain, light dog the camera follows: its flank shows no image change,
        # so the interior step puts it back (1.00 / 0.84 / 0.00; 0.78 cell F1 while
        # the outline and the trim, which need that change, cut it out again).
        ("davis/dog", "JPEGImages", 0.95, 0.81, 0.2),
        # Wading birds before breaking waves: 0.52 / 0.15 / 0.43 since the animate
        # prediction follows the fitted change of the camera's motion (0.70 / 0.15
        # / 0.35 while it was the difference of two frames' planes, which jump by
        # several px over the waves: a third of its hits came with those jumps).
        # With the change noise measured where both frames see, 0.476 / 0.139 /
        # 0.54 on this draw (50 of 105 objects), but 57.5 on average over four
        # draws against 56 before (54-58 then, 50-62 now).
        ("ucsd/birds", "in", 0.45, 0.12, 1.0),
        ("sbi/IBMtest2", "input", 0.9, 0.75, 0.5),
    ],
)
def test_image_sequences_complete_and_score(
    tmp_path, folder, frames_dir, min_object_recall, min_cell_f1, max_false_alarms
):
    root = shared_path(*folder.split("/"))
    out = detect(tmp_path, root / frames_dir)
    n = len([p for p in (root / frames_dir).iterdir() if p.suffix.lower() in (".jpg", ".png")])
    check_outputs(out, n, video=False)
    score = evaluate_sequence(out, root, warmup=2)
    assert score.counts.frames >= n - 3
    m = score.counts.metrics()
    assert m["object_recall"] >= min_object_recall
    assert m["cell_f1"] >= min_cell_f1
    assert m["false_alarm_regions_per_frame"] <= max_false_alarms


# The cows graze at about 0.5 work px/frame: the one-frame image change misses
# their plain bodies, the three-frame change does not. Measured cell F1: 0.483
# with one frame, 0.640 with three (the default).
def test_slow_movers_are_supported_over_three_frames(tmp_path):
    root = shared_path("davis", "cows")
    scores = {}
    for frames in (1, 3):
        config = tmp_path / f"support{frames}.toml"
        config.write_text(f"[track]\nsupport_frames = {frames}\n", encoding="utf-8")
        out = detect(tmp_path / str(frames), root / "JPEGImages", "--config", config)
        scores[frames] = evaluate_sequence(out, root, warmup=2).counts.metrics()["cell_f1"]
    # the gain is 0.048-0.056 over RANSAC's draws 0-3 (0.050 on draw 0 with
    # the frames read as BGR made grey, 0.0496 reading their luma)
    assert scores[3] > scores[1] + 0.04


# DragonBaby: handheld, jerky pans; the box is the child's face. Measured with the
# defaults: the face box is found on 0.89 of the scored frames (8 of the 111 are
# unreliable: blur or motion beyond the band). The clip is letterboxed: black bars
# of 39 px above and below its 640x360 frames, so only the picture is measured.
def test_otb_box_ground_truth_scores_the_handheld_clip(tmp_path):
    root = shared_path("otb", "DragonBaby")
    out = detect(tmp_path, root / "img")
    score = evaluate_sequence(out, root, warmup=2)
    assert score.counts.frames == 111 and score.counts.box_frames == 111
    m = score.counts.metrics()
    assert m["object_recall"] >= 0.8
    assert m["precision"] is None and m["false_alarm_regions_per_frame"] is None
    summary = json.loads((out / "summary.json").read_text())
    assert summary["totals"]["picture"] == [0, 39, 640, 282]
    for line in (out / "frames.jsonl").read_text().splitlines():
        for det in json.loads(line)["detections"]:
            assert 39 <= det["bbox"][1] and sum(det["bbox"][1::2]) <= 39 + 282


def test_woman_mp4_completes(tmp_path):
    source = shared_path("woman", "woman.mp4")
    out = detect(tmp_path, source)
    summary = check_outputs(out, 479, video=False)
    assert summary["input"]["width"] == 352 and summary["status"] == "complete"
    lines = (out / "frames.jsonl").read_text(encoding="utf-8").splitlines()
    records = {r["frame"]: r for r in map(json.loads, lines)}
    for frame in range(440, 451):  # the fast turn: box her, or say it cannot tell
        record = records[frame]
        if not record["reliable"]:
            assert record["reason"]
            continue
        x, y, w, h = max(record["detections"], key=lambda d: d["area_px"])["bbox"]
        assert w * h < 0.5 * 352 * 288  # a box on her, not on the whole picture
        # Where she walks. At the turn's end (447-450) she is at x 96-148, and
        # on some RANSAC draws one of those frames boxes only her upper body
        # (measured over seeds 0-7: 3 draws reading the luma, 1 the BGR made
        # grey; seed 0's frame 449: x 95-125, y 78-116).
        assert x < 200 and x + w > 120 and y < 190 and y + h > 110
    # Soft frames are judged (blur_ratio 0): the turn's last frames, and the
    # zoom onto her after it, where she walks at x 210-290. Measured: every
    # frame of the turn, 8 of the zoom's 10 frames, each with her box only.
    assert all(records[f]["reliable"] for f in range(440, 451))
    zoom = [records[f]["detections"] for f in range(453, 463)]
    assert all(records[f]["reliable"] for f in range(453, 463))
    assert sum(any(d["bbox"][0] < 290 and sum(d["bbox"][::2]) > 210 for d in z) for z in zoom) >= 7
    assert all(len(z) <= 1 for z in zoom)


def test_fox_with_known_egomotion(tmp_path):
    root = shared_path("fox")
    out = detect(
        tmp_path,
        root / "images",
        "--detector",
        "constraint-ray",
        "--egomotion",
        root / "transforms.json",
        "--work-size",
        "384",
    )
    records = [json.loads(x) for x in (out / "frames.jsonl").read_text().splitlines()]
    known = [r for r in records if r["observer_motion"]["name"] == "known-egomotion"]
    assert len(known) >= 45  # every frame whose predecessor has a pose
    # Nothing moves: the mounted head's parallax lies on its known rays. 14
    # boxes in 50 frames (85 before the known path had the fit's gates, 33
    # before the forward-backward check).
    assert sum(len(r["detections"]) for r in records) <= 20


def test_fox_near_rigid_head_is_dropped_over_time():
    """Without ego-motion: the mounted head, rigid and in front of the wall,
    keeps its depth on the constraint ray, so most of its frames are not
    reported (measured: 25 regions in 50 frames, against 49 with the test off;
    28 before the animate labels were cleared at cuts, 33 before each depth
    carried the bounds it was measured to)."""
    counts = []
    for share in (TrackConfig().rigid_share, 0.0):
        detector = MotionDetector("both", TrackConfig(rigid_share=share))
        with open_source(shared_path("fox", "images")) as frames:
            counts.append(sum(len(detector.process(f.image, f.index, 0.0).regions) for f in frames))
    assert counts[0] <= 28
    assert counts[0] <= 0.6 * counts[1]


def test_a_part_of_the_vehicle_in_view_is_taken_out_on_a_real_pan():
    """DAVIS dog with a dashboard in view: the bottom 15 % of the frame covered
    on every frame by the first frame's texture, mirrored and darkened to 60 %.
    Its plane difference stays under 5 sigmas of the moving scene's
    difference noise (7-10 grey levels here), so only its measured velocity,
    zero within 0.1 px, is evidence, counting more on frames where the
    handheld camera jolts. Measured: flags more than 20 px inside it on
    frames 3-7, none from frame 8 on (from frame 31 without the jolts'
    weight; without the velocity evidence, on 26 of the 29 frames after
    frame 30). Since tracks continue only at a box overlap of 0.2 (``min_iou``),
    they are first reported on frame 3, not 2. The dog is found on every
    judged frame."""
    detector = MotionDetector("both")
    inside, missed = [], 0
    with open_source(shared_path("davis", "dog", "JPEGImages")) as frames:
        for frame in frames:
            height, width = frame.image.shape[:2]
            covered = np.zeros((height, width), bool)
            covered[round(0.85 * height) :] = True
            if frame.index == 0:
                dashboard = (frame.image[::-1, ::-1] * 0.6).astype(np.uint8)
                deep = cv2.erode(covered.view(np.uint8), np.ones((41, 41), np.uint8)) > 0
            image = np.where(covered[..., None], dashboard, frame.image)
            result = detector.process(image, frame.index, frame.time_s)
            inside.append(bool(((result.input_mask(width, height) > 0) & deep).any()))
            missed += frame.index >= 2 and not result.regions
    assert all(inside[3:8])  # the problem, while the evidence builds up
    assert not any(inside[12:])
    assert missed == 0
