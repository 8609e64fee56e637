"""evaluate: changedetection.net metrics on tiny hand-made masks (issue 6)."""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np
import pytest

from motiondetect.io.video import read_mask
from motiondetect.tools.evaluate import (
    Counts,
    EvaluateError,
    evaluate_sequence,
    score_box,
    score_frame,
)
from motiondetect.tools.ground_truth import aligned_boxes, aligned_truth, index_by_number

from .cli_outputs import invoke
from .logs import warnings_logged
from .velocity_scenes import pan_with_mover


def test_metrics_equal_hand_computed_numbers():
    gt = np.zeros((4, 5), np.uint8)
    gt[0, :3] = 255  # 3 moving pixels
    gt[3, 4] = 170  # unknown: not scored
    pred = np.zeros((4, 5), np.uint8)
    pred[0, :2] = 255  # 2 TP
    pred[2, 2] = 255  # 1 FP, an isolated region touching nothing
    pred[3, 4] = 255  # on an unknown pixel: ignored
    c = score_frame(pred, gt, min_object_px=1)
    assert (c.tp, c.fp, c.fn, c.tn) == (2, 1, 1, 15)
    m = c.metrics()
    assert m["recall"] == pytest.approx(2 / 3)
    assert m["precision"] == pytest.approx(2 / 3)
    assert m["specificity"] == pytest.approx(15 / 16)
    assert m["fpr"] == pytest.approx(1 / 16)
    assert m["fnr"] == pytest.approx(1 / 3)
    assert m["pwc"] == pytest.approx(100 * 2 / 19)
    assert m["f_measure"] == pytest.approx(2 / 3)
    assert c.objects == 1 and c.objects_hit == 1
    assert c.false_alarm_regions == 1  # the unknown-pixel blob touches "unknown": not a false alarm


def test_object_recall_needs_ten_percent():
    gt = np.zeros((20, 20), np.uint8)
    gt[:10, :10] = 255  # 100 px
    pred = np.zeros_like(gt)
    pred[0, :9] = 255  # 9 %
    assert score_frame(pred, gt).objects_hit == 0
    pred[1, 0] = 255  # 10 %
    assert score_frame(pred, gt).objects_hit == 1


def write(folder, name, mask):
    folder.mkdir(parents=True, exist_ok=True)
    cv2.imwrite(str(folder / name), mask)


def test_sequences_align_warm_up_and_temporal_roi(tmp_path):
    gt_dir, pred_dir = tmp_path / "seq" / "groundtruth", tmp_path / "pred" / "masks"
    full = np.full((8, 8), 255, np.uint8)
    for n in range(1, 7):  # UCSD style: gt0001 is frame 0
        write(gt_dir, f"gt{n:04d}.png", full)
        write(pred_dir, f"{n - 1:06d}.png", full if n % 2 else np.zeros_like(full))
    score = evaluate_sequence(tmp_path / "pred", tmp_path / "seq", warmup=2)
    assert score.counts.frames == 4  # frames 0 and 1 are warm-up
    assert score.counts.tp == 2 * 64 and score.counts.fn == 2 * 64
    (tmp_path / "seq" / "temporalROI.txt").write_text("4 5\n")
    score = evaluate_sequence(tmp_path / "pred", tmp_path / "seq", warmup=0)
    assert score.counts.frames == 2


def test_pooled_counts_add():
    a, b = Counts(tp=1, fp=2, frames=1), Counts(tp=3, fn=1, frames=2)
    a.add(b)
    assert (a.tp, a.fp, a.fn, a.frames) == (4, 2, 1, 3)


def test_a_box_is_found_when_a_tenth_of_it_is_flagged():
    pred = np.zeros((20, 30), np.uint8)
    box = (10, 5, 10, 10)  # x, y, w, h: 100 px
    pred[5, 10:19] = 255  # 9 px inside
    pred[0:5, :] = 255  # all outside the box
    assert score_box(pred, box).objects_hit == 0
    pred[6, 10] = 255  # 10 px inside
    c = score_box(pred, box)
    assert (c.objects, c.objects_hit, c.frames, c.box_frames) == (1, 1, 1, 1)
    m = c.metrics()  # a box is not a mask: nothing else can be scored
    assert m["precision"] is None and m["false_alarm_regions_per_frame"] is None
    assert score_box(pred, (40, 40, 5, 5)).objects_hit == 0  # off the frame


def test_box_files_score_object_recall(tmp_path):
    seq = tmp_path / "seq"
    seq.mkdir()
    # OTB style: line i is frame i; tab- or comma-separated
    (seq / "groundtruth_rect.txt").write_text("0,0,4,4\n0,0,4,4\n4\t4\t4\t4\n0,0,4,4\n")
    corner = np.zeros((8, 8), np.uint8)
    corner[:4, :4] = 255
    for index in range(4):
        write(tmp_path / "pred" / "masks", f"{index:06d}.png", corner)
    score = evaluate_sequence(tmp_path / "pred", seq, warmup=1)
    assert (score.counts.frames, score.counts.objects_hit) == (3, 2)  # frame 2's box is missed
    (seq / "groundtruth_rect.txt").write_text("0,0,4\n")
    with pytest.raises(EvaluateError, match="expected 'x,y,w,h'"):
        evaluate_sequence(tmp_path / "pred", seq / "groundtruth_rect.txt")


def test_ground_truth_finds_its_frame_by_the_files_numbers():
    gt = [Path(f"{n:05d}.png") for n in range(12, 40, 3)]  # starts after the frames do
    numbers = index_by_number((n, i) for i, n in enumerate(range(0, 40, 3)))  # gapped
    aligned = aligned_truth(gt, numbers)
    assert aligned[4] == Path("00012.png") and aligned[12] == Path("00036.png")
    del numbers[15]  # its file was unreadable: its truth scores nothing
    assert Path("00015.png") not in aligned_truth(gt, numbers).values()
    # A video (no numbers), or numbers the truth does not use: GT's own offset
    assert aligned_truth(gt, None)[0] == aligned_truth(gt, {1: 0})[0] == Path("00012.png")
    assert aligned_truth(gt, None)[3] == Path("00015.png")
    assert index_by_number([(3, 0), (3, 1)]) is None  # two cameras' frames: ambiguous
    assert index_by_number([(-1, 0)]) is None  # a file without a number


def test_a_gapped_frames_folder_is_scored_against_its_own_frames(tmp_path):
    """Frames numbered 30, 33, ... with one file unreadable, ground truth
    only from frame 42: the frames.jsonl numbers align them, and the scores
    are those of each mask against its own frame's truth."""
    seq, gt_dir = tmp_path / "seq", tmp_path / "truth" / "groundtruth"
    seq.mkdir()
    clip = pan_with_mover(lambda t: (30 + 6 * t, 90), frames=16, pan=2.0)
    for t, (image, mask) in enumerate(clip):
        number = 30 + 3 * t
        cv2.imwrite(str(seq / f"{number:05d}.png"), image if t != 8 else image[:10])
        if t >= 4:
            write(gt_dir, f"gt{number:05d}.png", mask.astype(np.uint8) * 255)
    out = tmp_path / "out"
    assert invoke("detect", seq, "-o", out, "-q", "--masks", "--no-video").exit_code == 0
    lines = (out / "seq" / "frames.jsonl").read_text(encoding="utf-8").splitlines()
    records = [json.loads(line) for line in lines]
    assert [r["number"] for r in records] == [30 + 3 * t for t in range(16) if t != 8]
    with warnings_logged() as warned:
        score = evaluate_sequence(out / "seq", tmp_path / "truth", warmup=3)
    assert any("start at 42 and the frame files' at 30" in m for m in warned), warned
    expected = Counts()
    for t in range(4, 16):
        if t != 8:
            pred = read_mask(out / "seq" / "masks" / f"{t:06d}.png")
            expected.add(score_frame(pred, clip[t][1].astype(np.uint8) * 255))
    assert score.counts == expected and score.counts.frames == 11
    assert score.counts.objects_hit >= 9  # the mover found on its own frames


def test_box_lines_follow_the_frame_files_numbers(tmp_path):
    """OTB's line i is the frame numbered first + i: with file 0003 missing
    from the folder, the frame read from 0004 (index 2) is scored against
    line 3, not line 2."""
    assert aligned_boxes(5, {1: 0, 2: 1, 4: 2, 5: 3}) == {0: 0, 1: 1, 2: 3, 3: 4}
    assert aligned_boxes(3, {2: 1, 3: 2}) == {1: 1, 2: 2}  # file 0001 unreadable
    assert aligned_boxes(3, None) == {0: 0, 1: 1, 2: 2}
    seq, pred = tmp_path / "seq", tmp_path / "pred"
    seq.mkdir()
    corners = [(0, 0), (4, 0), (0, 4), (4, 4), (0, 0)]  # line k boxes corner k
    (seq / "groundtruth_rect.txt").write_text("".join(f"{x},{y},4,4\n" for x, y in corners))
    records = []
    for index, number in enumerate((1, 2, 4, 5)):
        mask = np.zeros((8, 8), np.uint8)
        x, y = corners[number - 1]
        mask[y : y + 4, x : x + 4] = 255  # the frame's own box flagged
        write(pred / "masks", f"{index:06d}.png", mask)
        records.append(json.dumps({"frame": index, "number": number}))
    (pred / "frames.jsonl").write_text("\n".join(records) + "\n")
    score = evaluate_sequence(pred, seq, warmup=0)
    assert (score.counts.frames, score.counts.objects_hit) == (4, 4)
    (pred / "frames.jsonl").unlink()  # by place: frames 2 and 3 meet the wrong lines
    assert evaluate_sequence(pred, seq, warmup=0).counts.objects_hit == 2
