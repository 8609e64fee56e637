r"""Where object recall is lost: missed parts of a found mover, or missed movers.

    python benchmarks/misses.py davis
    python benchmarks/misses.py davis,ucsd,sample '{"velocity_ray": {"carry": 0}}'

``motiondetect evaluate`` (and so ``compare.py``) counts every connected
part of a ground-truth mask of at least 20 px as an object, found when 10 %
of it is flagged. One animal can then be several objects: DAVIS cows'
front legs below the fence wire are parts of their own, and they stand on
the ground while the cow walks. For each scored frame this splits the
misses in two: a *part* missed while the frame's largest part (the mover's
body) is found, or a *mover* missed, its largest part not found (with every
other part of it on that frame). The split assumes one labelled mover per
frame, as DAVIS and UCSD's moving-camera clips label; where several are
labelled (UCSD peds and traffic, the samples with two movers) a missed
"part" may be another mover. Scores come from ``compare.Ours`` (the
tool's default, frame skipping as ``compare.py``), or from the config
sections given as JSON (``sweep.configs``).
"""

from __future__ import annotations

import compare
import cv2
import numpy as np
import sweep
from fragments import MIN_OBJECT_PX

from motiondetect.io.video import open_source, read_mask
from motiondetect.tools.evaluate import HIT_FRACTION, truth_masks


def found_parts(truth: np.ndarray, flagged: np.ndarray) -> list[tuple[int, bool]]:
    """Each labelled part of ``truth`` (a ground-truth mask) as (area, found),
    largest first; ``flagged`` (h, w) bool at the mask's size."""
    positive, _ = truth_masks(truth)
    n, labels, stats, _ = cv2.connectedComponentsWithStats(positive.view(np.uint8), connectivity=8)
    parts = [
        (int(stats[k, cv2.CC_STAT_AREA]), bool(flagged[labels == k].mean() >= HIT_FRACTION))
        for k in range(1, n)
        if stats[k, cv2.CC_STAT_AREA] >= MIN_OBJECT_PX
    ]
    return sorted(parts, reverse=True)


def _run(job: tuple) -> tuple[str, tuple[int, int, int, int, int]]:
    name, source, gt, configs = job
    cv2.setNumThreads(1)
    ours = compare.Ours(configs=configs)
    found = parts = movers = frames = lost = 0
    with open_source(source) as video:
        masks = compare.gt_masks(gt, video)
        for frame in video:
            pred = ours(frame.grey, frame.time_s)
            if frame.index < compare.WARMUP or frame.index not in masks:
                continue
            truth = read_mask(masks[frame.index])
            if pred.shape != truth.shape:
                pred = cv2.resize(pred, truth.shape[::-1], interpolation=cv2.INTER_NEAREST_EXACT)
            counted = found_parts(truth, pred > 127)
            if not counted:
                continue
            frames += 1
            hits = sum(hit for _, hit in counted)
            found += hits
            if counted[0][1]:
                parts += len(counted) - hits
            else:
                movers += len(counted) - hits
                lost += 1
    return name, (frames, found, parts, movers, lost)


def _line(label: str, counts: tuple[int, int, int, int, int]) -> str:
    frames, found, parts, movers, lost = counts
    total, shown = found + parts + movers, frames - lost
    return (
        f"{label:30s} found {found:4d} of {total:4d} ({found / max(total, 1):.3f})  "
        f"missed: parts of a found mover {parts:4d}, movers {movers:4d}  "
        f"largest part found on {shown} of {frames} frames ({shown / max(frames, 1):.3f})"
    )


def main() -> None:
    groups, results = sweep.on_masked_sequences(__doc__, _run)
    sweep.print_by_group(groups, results, _line, lambda rows: tuple(map(sum, zip(*rows))))


if __name__ == "__main__":
    main()
