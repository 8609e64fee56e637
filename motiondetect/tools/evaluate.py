"""Score predicted masks against ground truth, changedetection.net style.

Ground truth is a folder of PNG masks in any of these layouts (or a
sequence folder holding one such folder as ``groundtruth/``,
``Annotations/``, ``truth/`` or ``masks/``):

* CDnet / SBI / UCSD: ``gtNNNNNN.png``; 0 static, 50 shadow (static),
  85 outside the region of interest and 170 unknown (both not scored),
  255 moving;
* DAVIS: ``NNNNN.png``, 0/255;
* motiondetect synth: ``truth/NNNNNN.png``, 0/170/255.

Or it is a text file of boxes, one ``x,y,w,h`` line per frame from the
first (OTB's ``groundtruth_rect.txt``, comma- or tab-separated; a sequence
folder holding that file also works). A box is not a mask and other movers
are not boxed, so only object recall is scored there: the target is found
when at least ``HIT_FRACTION`` of its box is flagged. Line ``i`` is the
frame numbered ``first + i`` (:func:`aligned_boxes`).

GT files are matched to predicted frames by the number in their names
(:func:`aligned_truth`). Where the input was a frames folder, its
``frames.jsonl`` records each frame file's number, and GT number ``n``
scores the frame read from the file numbered ``n``: GT that starts after
the first frame, frames numbered with gaps and files skipped as unreadable
all stay aligned. Otherwise (a video, or no GT number among the files') GT
is aligned by subtracting the smallest GT number (UCSD starts at 1, the
others at 0), so GT number ``n`` scores predicted frame ``n - first``. A
``temporalROI.txt`` next to the GT folder limits the frames scored.
Predictions are ``masks/NNNNNN.png`` (0-based frame index) as
``motiondetect detect --masks`` writes them.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np

from motiondetect.io.files import last_number
from motiondetect.io.video import read_mask
from motiondetect.tools.ground_truth import (
    EvaluateError,
    aligned_boxes,
    aligned_truth,
    find_gt_boxes,
    find_gt_folder,
    first_file_number,
    numbered_alike,
    read_boxes,
    recorded_numbers,
    temporal_roi,
)

log = logging.getLogger(__name__)

UNKNOWN_VALUES = (85, 170)
HIT_FRACTION = 0.1  # an object is found when at least this share of it is flagged


@dataclass
class Counts:
    """Pixel and object tallies for one sequence (or pooled)."""

    tp: int = 0
    fp: int = 0
    fn: int = 0
    tn: int = 0
    objects: int = 0
    objects_hit: int = 0
    false_alarm_regions: int = 0
    frames: int = 0
    cell_tp: int = 0
    cell_fp: int = 0
    cell_fn: int = 0
    box_frames: int = 0

    def add(self, other: Counts) -> None:
        for name in self.__dataclass_fields__:
            setattr(self, name, getattr(self, name) + getattr(other, name))

    def metrics(self) -> dict[str, float | None]:
        def ratio(a: float, b: float) -> float | None:
            return a / b if b else None

        recall = ratio(self.tp, self.tp + self.fn)
        precision = ratio(self.tp, self.tp + self.fp)
        total = self.tp + self.fp + self.fn + self.tn
        f = (
            2 * precision * recall / (precision + recall)
            if precision and recall
            else (0.0 if precision is not None and recall is not None else None)
        )
        return {
            "recall": recall,
            "specificity": ratio(self.tn, self.tn + self.fp),
            "fpr": ratio(self.fp, self.fp + self.tn),
            "fnr": ratio(self.fn, self.tp + self.fn),
            "pwc": ratio(100.0 * (self.fn + self.fp), total),
            "precision": precision,
            "f_measure": f,
            "object_recall": ratio(self.objects_hit, self.objects),
            "false_alarm_regions_per_frame": ratio(
                self.false_alarm_regions, self.frames - self.box_frames
            ),
            "cell_f1": ratio(2 * self.cell_tp, 2 * self.cell_tp + self.cell_fp + self.cell_fn),
            "frames": self.frames,
        }


@dataclass
class SequenceScore:
    name: str
    counts: Counts = field(default_factory=Counts)


#: Cell-level scoring: cells of CELL_PX x CELL_PX input pixels.
CELL_PX = 10
CELL_POSITIVE = 0.3  # a cell is a mover when at least this share of it is mover
CELL_NEGATIVE = 0.05  # ... background when at most this share is mover or unknown
CELL_FLAGGED = 0.3  # ... flagged when at least this share of it is flagged


def cell_shares(mask: np.ndarray) -> np.ndarray:
    """Share of each whole ``CELL_PX`` x ``CELL_PX`` cell that ``mask`` covers,
    (h // CELL_PX, w // CELL_PX) float32 (partial cells at the edges dropped)."""
    h, w = mask.shape
    rows, cols = h // CELL_PX, w // CELL_PX
    cropped = mask[: rows * CELL_PX, : cols * CELL_PX].astype(np.float32)
    return cropped.reshape(rows, CELL_PX, cols, CELL_PX).mean(axis=(1, 3))


def cell_classes(
    flagged: np.ndarray, positive: np.ndarray, mover_or_unknown: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each 10x10-pixel cell's class: (positive, negative, flagged), (rows, cols) bool each.

    A cell is positive when >= 30 % of its pixels are mover, negative when
    <= 5 % are mover or unknown, and unscored in between; it is flagged when
    >= 30 % of its pixels are flagged.
    """
    return (
        cell_shares(positive) >= CELL_POSITIVE,
        cell_shares(mover_or_unknown) <= CELL_NEGATIVE,
        cell_shares(flagged) >= CELL_FLAGGED,
    )


def cell_counts(flagged: np.ndarray, positive: np.ndarray, mover_or_unknown: np.ndarray):
    """Cell-level (tp, fp, fn) over 10x10-pixel cells (:func:`cell_classes`)."""
    pos, neg, hit = cell_classes(flagged, positive, mover_or_unknown)
    return int((pos & hit).sum()), int((neg & hit).sum()), int((pos & ~hit).sum())


def truth_masks(gt: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(mover, unknown) pixels of a ground-truth mask, (h, w) bool each: see
    the module doc for its values."""
    unknown = np.isin(gt, UNKNOWN_VALUES)
    return (gt >= 128) & ~unknown, unknown


def score_frame(
    pred: np.ndarray,
    gt: np.ndarray,
    min_object_px: int = 20,
    hit_fraction: float = HIT_FRACTION,
) -> Counts:
    """Tally one frame. ``pred`` > 127 is flagged; see the module doc for ``gt``."""
    if pred.shape != gt.shape:
        pred = cv2.resize(pred, (gt.shape[1], gt.shape[0]), interpolation=cv2.INTER_NEAREST_EXACT)
    flagged = pred > 127
    positive, ignore = truth_masks(gt)
    scored = ~ignore
    c = Counts(frames=1)
    c.tp = int((flagged & positive).sum())
    c.fp = int((flagged & ~positive & scored).sum())
    c.fn = int((~flagged & positive).sum())
    c.tn = int((~flagged & ~positive & scored).sum())
    n, labels, stats, _ = cv2.connectedComponentsWithStats(
        positive.astype(np.uint8), connectivity=8
    )
    for label in range(1, n):
        if stats[label, cv2.CC_STAT_AREA] < min_object_px:
            continue
        c.objects += 1
        c.objects_hit += bool(flagged[labels == label].mean() >= hit_fraction)
    c.cell_tp, c.cell_fp, c.cell_fn = cell_counts(flagged, positive, positive | ignore)
    moving_or_unknown = positive | (gt == 170)
    n, labels = cv2.connectedComponents(flagged.astype(np.uint8), connectivity=8)
    if n > 1:
        touching = np.unique(labels[moving_or_unknown & flagged])
        c.false_alarm_regions = int(n - 1 - np.count_nonzero(touching))
    return c


def score_box(pred: np.ndarray, box: tuple[int, int, int, int]) -> Counts:
    """Tally one frame against one target box (object recall only)."""
    x, y, w, h = box
    inside = pred[max(y, 0) : max(y + h, 0), max(x, 0) : max(x + w, 0)] > 127
    hit = inside.size > 0 and inside.mean() >= HIT_FRACTION
    return Counts(frames=1, box_frames=1, objects=1, objects_hit=int(hit))


def _evaluate_boxes(pred_dir: Path, boxes: list, warmup: int, score: SequenceScore) -> None:
    preds = {last_number(p): p for p in pred_dir.glob("*.png") if last_number(p) is not None}
    for index, line in aligned_boxes(len(boxes), recorded_numbers(pred_dir)).items():
        mask = read_mask(preds[index]) if index >= warmup and index in preds else None
        if mask is not None:
            score.counts.add(score_box(mask, boxes[line]))


def evaluate_sequence(
    pred: Path, gt: Path, *, warmup: int = 1, name: str | None = None, min_object_px: int = 20
) -> SequenceScore:
    """Score one sequence: ``pred`` is an output folder (or its ``masks/``)."""
    pred_dir = pred / "masks" if (pred / "masks").is_dir() else pred
    if not pred_dir.is_dir():
        raise EvaluateError(f"{pred}: no predicted masks (run detect with --masks)")
    score = SequenceScore(name or pred.name)
    box_file = find_gt_boxes(gt)
    if box_file is not None:
        _evaluate_boxes(pred_dir, read_boxes(box_file), warmup, score)
        if score.counts.frames == 0:
            raise EvaluateError(f"{pred}: no predicted frame matches the boxes in {box_file}")
        return score
    gt_dir = find_gt_folder(gt)
    gt_files = sorted(
        (
            p
            for p in gt_dir.iterdir()
            if p.suffix.lower() in (".png", ".bmp") and last_number(p) is not None
        ),
        key=last_number,
    )
    if not gt_files:
        raise EvaluateError(f"{gt}: no ground-truth masks found")
    roi = temporal_roi(gt_dir)
    preds = {last_number(p): p for p in pred_dir.glob("*.png") if last_number(p) is not None}
    numbers = recorded_numbers(pred_dir)
    aligned = aligned_truth(gt_files, numbers)
    first_gt = last_number(gt_files[0])
    if numbered_alike(gt_files, numbers) and first_gt != first_file_number(numbers):
        log.warning(
            "%s: the truth's numbers start at %d and the frame files' at %d; each truth file "
            "is scored against the frame whose file has its number", gt, first_gt,
            first_file_number(numbers),
        )  # fmt: skip
    for index, gt_file in aligned.items():
        number = last_number(gt_file)
        if index < warmup or (roi and not roi[0] <= number <= roi[1]):
            continue
        pred_file = preds.get(index)
        gt_mask = read_mask(gt_file)
        if pred_file is None or gt_mask is None:
            continue
        pred_mask = read_mask(pred_file)
        if pred_mask is None:
            continue
        score.counts.add(score_frame(pred_mask, gt_mask, min_object_px))
    if score.counts.frames == 0:
        raise EvaluateError(f"{pred}: no predicted frame matches the ground truth in {gt}")
    return score


def evaluate(pred: Path, gt: Path, *, warmup: int = 1) -> list[SequenceScore]:
    """One sequence, or a batch: sub-folders of ``pred`` matched by name in ``gt``."""
    if (pred / "masks").is_dir() or any(pred.glob("*.png")):
        return [evaluate_sequence(pred, gt, warmup=warmup)]
    scores = []
    for sub in sorted(p for p in pred.iterdir() if p.is_dir()):
        if (gt / sub.name).is_dir() and (sub / "masks").is_dir():
            scores.append(evaluate_sequence(sub, gt / sub.name, warmup=warmup, name=sub.name))
    if not scores:
        raise EvaluateError(f"{pred}: found no predicted sequence matching {gt}")
    return scores


COLUMNS = (
    "recall",
    "specificity",
    "fpr",
    "fnr",
    "pwc",
    "precision",
    "f_measure",
    "object_recall",
    "false_alarm_regions_per_frame",
    "cell_f1",
    "frames",
)


def table_rows(scores: list[SequenceScore]) -> list[dict]:
    rows = [{"sequence": s.name, **s.counts.metrics()} for s in scores]
    if len(scores) > 1:
        pooled = Counts()
        for s in scores:
            pooled.add(s.counts)
        rows.append({"sequence": "overall", **pooled.metrics()})
    return rows


def format_table(rows: list[dict]) -> str:
    heads = [
        "sequence",
        "recall",
        "spec",
        "FPR",
        "FNR",
        "PWC",
        "prec",
        "F",
        "obj.rec",
        "FA/frm",
        "cellF1",
        "frames",
    ]
    lines = ["  ".join(f"{h:>8s}" if i else f"{h:<16s}" for i, h in enumerate(heads))]
    for row in rows:
        cells = [f"{row['sequence'][:16]:<16s}"]
        for key in COLUMNS:
            v = row[key]
            cells.append(
                f"{'-':>8s}" if v is None else (f"{v:8d}" if key == "frames" else f"{v:8.3f}")
            )
        lines.append("  ".join(cells))
    return "\n".join(lines)
