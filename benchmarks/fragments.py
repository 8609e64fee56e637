r"""One mover, several boxes: how often a labelled object is reported in parts.

    python benchmarks/fragments.py davis
    python benchmarks/fragments.py davis,ucsd,sbi,sample '{"track": {"persistence": 3}}'

Issue 13 asks for objects, not fragments: one person should be one box. For
every labelled object (a connected part of a ground-truth mask, as
``motiondetect evaluate`` counts them) on every scored frame, a box
*covers* it when more than 5 % of the object's pixels lie inside the box.
The object is *boxed* when at least one box covers it, and *split* when two
or more do. Scores come from the default detector, or from the config
sections given as JSON (``sweep.configs``). Only data sets with masks are
counted: OTB has one box per frame, and the fox clip has no mover.
"""

from __future__ import annotations

import cv2
import numpy as np
import sweep

from motiondetect.tools.evaluate import truth_masks

#: Share of an object's pixels a box must hold to cover it.
COVER = 0.05
#: Smallest object counted, px (``motiondetect evaluate``'s default).
MIN_OBJECT_PX = 20


def boxes_per_object(truth: np.ndarray, boxes: list) -> list[int]:
    """For each labelled object in ``truth`` (a ground-truth mask), how many of
    ``boxes`` ((x, y, w, h) in its pixels) cover it."""
    positive, _ = truth_masks(truth)
    n, labels, stats, _ = cv2.connectedComponentsWithStats(positive.view(np.uint8), connectivity=8)
    counts = []
    for label in range(1, n):
        area = stats[label, cv2.CC_STAT_AREA]
        if area < MIN_OBJECT_PX:
            continue
        inside = (labels[y : y + h, x : x + w] == label for x, y, w, h in boxes)
        counts.append(sum(int(part.sum()) > COVER * area for part in inside))
    return counts


def _run(job: tuple) -> tuple[str, tuple[int, int]]:
    boxed = split = 0
    for result, truth in sweep.scored_frames(job):
        counts = boxes_per_object(truth, [region.bbox for region in result.regions])
        boxed += sum(c >= 1 for c in counts)
        split += sum(c >= 2 for c in counts)
    return job[0], (boxed, split)


def _line(label: str, counts: tuple[int, int]) -> str:
    boxed, split = counts
    return f"{label:28s} boxed {boxed:4d}  split {split:4d} ({split / max(boxed, 1):.2f})"


def main() -> None:
    groups, results = sweep.on_masked_sequences(__doc__, _run)
    sweep.print_by_group(groups, results, _line, lambda rows: tuple(map(sum, zip(*rows))))


if __name__ == "__main__":
    main()
