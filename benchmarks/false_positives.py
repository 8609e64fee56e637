r"""Where the default's false-positive cells lie: next to the labelled mover or away from it.

    python benchmarks/false_positives.py davis
    python benchmarks/false_positives.py davis,ucsd --ring 3

Per sequence with mask ground truth, the cell tallies of ``motiondetect
evaluate`` (10x10-pixel cells, frames 0-1 unscored) with the false positives
split in three: "uncovered" cells are at least 30 % mover in the previous
frame's truth moved by this frame's fitted plane (background the mover has
just uncovered, where the flow has nothing to match); "near" cells lie
within ``--ring`` cells of a cell the truth touches (the outline
overshooting the mover); "far" cells beyond (other movers, parallax,
clutter). Cell F1 is ``2 tp / (2 tp + uncovered + near + far + fn)``, so the
split says what a better outline, or one that knew what was uncovered,
could win back.
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


def uncovered(last: np.ndarray | None, result) -> np.ndarray | None:
    """The last frame's mover, (h, w) bool input pixels, moved by this frame's
    fitted plane (None without either, or where only a picture inside black
    bars was measured)."""
    camera, work = result.camera, result.mask
    if last is None or camera is None or camera.homography is None or work is None:
        return None
    if result.field is None or getattr(result.field, "picture", None) is not None:
        return None
    (h, w), (wh, ww) = last.shape, work.shape
    small = cv2.resize(last.view(np.uint8), (ww, wh), interpolation=cv2.INTER_NEAREST)
    flags = cv2.INTER_NEAREST | cv2.WARP_INVERSE_MAP  # the homography maps current to last
    moved = cv2.warpPerspective(small, camera.homography, (ww, wh), flags=flags)
    return cv2.resize(moved, (w, h), interpolation=cv2.INTER_NEAREST) > 0


def tally(job: tuple) -> tuple[str, np.ndarray]:
    """(name, [tp, uncovered fp, near fp, far fp, fn]) of one sequence."""
    name, source, gt, ring = job
    cv2.setNumThreads(1)
    detector = MotionDetector("both")
    kernel = np.ones((2 * ring + 1, 2 * ring + 1), np.uint8)
    counts, last = np.zeros(5, np.int64), None
    with open_source(source) as frames:
        masks = compare.gt_masks(gt, frames)
        for frame in frames:
            result = detector.process(frame.grey, frame.index, frame.time_s)
            if frame.index not in masks:
                last = None
                continue
            mover, unknown = truth_masks(read_mask(masks[frame.index]))
            was, last = uncovered(last, result), mover
            if frame.index < compare.WARMUP:
                continue
            h, w = mover.shape
            flagged = result.input_mask(w, h) > 0
            positive, negative, flagged = cell_classes(flagged, mover, mover | unknown)
            touched = (cell_shares(mover) > 0).astype(np.uint8)
            near = cv2.dilate(touched, kernel) > 0
            behind = np.zeros_like(near) if was is None else cell_shares(was) >= 0.3
            false = flagged & negative
            counts += [
                (flagged & positive).sum(),
                (false & behind).sum(),
                (false & near & ~behind).sum(),
                (false & ~near & ~behind).sum(),
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
    heads = ("tp", "fp uncov", "fp near", "fp far", "fn")
    print(f"{'sequence':28s} " + " ".join(f"{h:>8s}" for h in heads) + "  cell F1")
    for group in groups:
        pooled = np.zeros(5, np.int64)
        for name, counts in results:
            if name.startswith(group):
                pooled += counts
                print(f"  {name:26s} " + " ".join(f"{c:8d}" for c in counts))
        tp = pooled[0]
        f1 = 2 * tp / max(2 * tp + pooled[1:].sum(), 1)
        print(f"{group:28s} " + " ".join(f"{c:8d}" for c in pooled) + f"  {f1:.3f}")


if __name__ == "__main__":
    main()
