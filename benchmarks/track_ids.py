r"""One mover, one id: how often a labelled object's track id changes.

    python benchmarks/track_ids.py davis
    python benchmarks/track_ids.py davis,sample '{"track": {"min_iou": 0.1}}'

Issue 13 asks for a stable integer ``track`` id per object. DAVIS labels one
object per clip, so each frame's ground-truth mask is taken as one object.
On every scored frame where a box covers it (holds more than 5 % of its
pixels, as ``fragments.py`` counts), its *id* is the track of the box that
holds most of it. Printed per sequence: frames boxed, distinct ids, id
*switches* (boxed frames whose id differs from the last boxed frame's) and
the share of boxed frames the commonest id covers. Where a clip's mask
labels several movers (UCSD's pedestrians and cars, the samples' scenes),
several ids are right, so the counts mean most on DAVIS.
"""

from __future__ import annotations

from collections import Counter

import compare
import cv2
import numpy as np
import sweep
from fragments import COVER

from motiondetect.detection.detector import MotionDetector
from motiondetect.io.video import open_source, read_mask
from motiondetect.tools.evaluate import truth_masks


def main_id(truth: np.ndarray, regions: list) -> int | None:
    """The track of the region whose box holds most of the labelled pixels,
    when it holds more than :data:`COVER` of them; None otherwise."""
    positive, _ = truth_masks(truth)
    total = int(positive.sum())
    best, best_px = None, COVER * total
    for region in regions:
        x, y, w, h = region.bbox
        inside = int(positive[y : y + h, x : x + w].sum())
        if region.track is not None and total and inside > best_px:
            best, best_px = region.track, inside
    return best


def _run(job: tuple) -> tuple[str, int, int, int, int]:
    name, source, gt, configs = job
    cv2.setNumThreads(1)
    detector = MotionDetector("both", *configs)
    ids: list[int] = []
    with open_source(source) as frames:
        masks = compare.gt_masks(gt, frames)
        for frame in frames:
            regions = detector.process(frame.grey, frame.index, frame.time_s).regions
            if frame.index < compare.WARMUP or frame.index not in masks:
                continue
            track = main_id(read_mask(masks[frame.index]), regions)
            if track is not None:
                ids.append(track)
    switches = sum(a != b for a, b in zip(ids, ids[1:]))
    common = Counter(ids).most_common(1)[0][1] if ids else 0
    return name, len(ids), len(set(ids)), switches, common


def _line(label: str, boxed: int, ids: int, switches: int, common: int) -> str:
    share = common / max(boxed, 1)
    return f"{label:30s} boxed {boxed:4d}  ids {ids:3d}  switches {switches:3d}  one id {share:.3f}"


def main() -> None:
    groups, results = sweep.on_masked_sequences(__doc__, _run)
    for group in groups:
        rows = [r for r in results if r[0].startswith(group)]
        for name, *counts in rows:
            print(_line(f"  {name}", *counts))
        print(_line(group, *(sum(r[i] for r in rows) for i in range(1, 5))))


if __name__ == "__main__":
    main()
