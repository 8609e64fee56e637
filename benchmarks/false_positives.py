r"""Where the default's false-positive cells lie: next to the labelled mover or away from it.

    python benchmarks/false_positives.py davis
    python benchmarks/false_positives.py davis,ucsd --ring 3

Per sequence with mask ground truth, the cell tallies of ``motiondetect
evaluate`` (10x10-pixel cells, frames 0-1 unscored) with the false positives
split in two: "near" cells lie within ``--ring`` cells of a cell the truth
touches (the outline overshooting the mover), "far" cells beyond (other
movers, parallax, clutter). Cell F1 is ``2 tp / (2 tp + near + far + fn)``,
so the split says which of the two a better outline could win back.
"""

from __future__ import annotations

import argparse
from multiprocessing import Pool

import compare
import cv2
import numpy as np

from motiondetect.detection.detector import MotionDetector
from motiondetect.io.video import open_source, read_mask
from motiondetect.tools.evaluate import cell_classes, cell_shares, truth_masks


def tally(job: tuple) -> tuple[str, np.ndarray]:
    """(name, [tp, near fp, far fp, fn]) of one sequence."""
    name, source, gt, ring = job
    cv2.setNumThreads(1)
    detector = MotionDetector("both")
    kernel = np.ones((2 * ring + 1, 2 * ring + 1), np.uint8)
    counts = np.zeros(4, np.int64)
    with open_source(source) as frames:
        masks = compare.gt_masks(gt, frames)
        for frame in frames:
            result = detector.process(frame.grey, frame.index, frame.time_s)
            if frame.index < compare.WARMUP or frame.index not in masks:
                continue
            mover, unknown = truth_masks(read_mask(masks[frame.index]))
            h, w = mover.shape
            flagged = result.input_mask(w, h) > 0
            positive, negative, flagged = cell_classes(flagged, mover, mover | unknown)
            touched = (cell_shares(mover) > 0).astype(np.uint8)
            near = cv2.dilate(touched, kernel) > 0
            false = flagged & negative
            counts += [
                (flagged & positive).sum(),
                (false & near).sum(),
                (false & ~near).sum(),
                (~flagged & positive).sum(),
            ]
    return name, counts


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("datasets", help="comma-separated: davis,ucsd,sbi,sample")
    parser.add_argument("--ring", type=int, default=3, help="cells counted as next to the mover")
    parser.add_argument("--jobs", type=int, default=2)
    args = parser.parse_args()
    groups = args.datasets.split(",")
    jobs = [
        (name, source, gt, args.ring)
        for name, source, gt, _ in compare.sequences(quick=False)
        if gt is not None and gt.suffix != ".txt" and any(name.startswith(g) for g in groups)
    ]
    with Pool(args.jobs) as pool:
        results = pool.map(tally, jobs, chunksize=1)
    print(f"{'sequence':28s} {'tp':>8s} {'fp near':>8s} {'fp far':>8s} {'fn':>8s}  cell F1")
    for group in groups:
        pooled = np.zeros(4, np.int64)
        for name, counts in results:
            if name.startswith(group):
                pooled += counts
                print(f"  {name:26s} " + " ".join(f"{c:8d}" for c in counts))
        tp, near, far, fn = pooled
        f1 = 2 * tp / max(2 * tp + near + far + fn, 1)
        print(f"{group:28s} " + " ".join(f"{c:8d}" for c in pooled) + f"  {f1:.3f}")


if __name__ == "__main__":
    main()
