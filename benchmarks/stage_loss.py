r"""Which stage loses a mover: the detectors' flags, or the objects made of them.

    python benchmarks/stage_loss.py davis
    MOTIONDETECT_DATA=/tmp/close50 python benchmarks/stage_loss.py davis

For each sequence with mask ground truth, pooled over its scored frames (at
the working size, unknown pixels left out):

- *flagged*: the share of the labelled mover's pixels that either
  detector flags (the union of their masks, before objects);
- *kept*: the share the objects keep (the support gate, outline, interior
  and tracks: the final mask);
- *outside*: pixels per frame flagged off the mover, by the detectors and
  in the objects;
- the medians over frames of the constraint ray's tolerance and of the
  plane residual's length on the mover and off it, and the share of frames
  on which the tolerance exceeds the mover's median residual (the ray
  cannot seed most of it there).

A mover lost at *flagged* is the measurement's or the fit's (the plane
taken by the mover, a tolerance raised by it); one lost between *flagged*
and *kept* is the object stage's. ``benchmarks/close_movers.py`` makes the
crops in which a mover fills a third or half of the view. Scores come from
the default detector or from the config sections given as JSON
(``sweep.configs``); frames 0-1 are not scored.
"""

from __future__ import annotations

import cv2
import numpy as np
import sweep

from motiondetect.detection.detector import MotionDetector
from motiondetect.tools.evaluate import truth_masks


def frame_row(result, truth: np.ndarray, tolerance: float) -> list[float] | None:
    """One frame's pixel counts and residual medians (None: nothing to score)."""
    h, w = result.mask.shape
    positive, unknown = (
        cv2.resize(m.view(np.uint8), (w, h), interpolation=cv2.INTER_NEAREST) > 0
        for m in truth_masks(truth)
    )
    if not positive.any() or result.camera is None or result.camera.residual_px is None:
        return None
    flagged = np.zeros((h, w), bool)
    for output in (result.outputs or {}).values():
        flagged |= output.mask
    background = ~positive & ~unknown
    length = result.camera.residual_length()
    return [
        positive.sum(), (flagged & positive).sum(), (result.mask & positive).sum(),
        (flagged & background).sum(), (result.mask & background).sum(), tolerance,
        float(np.median(length[positive])),
        float(np.median(length[background])) if background.any() else 0.0,
    ]  # fmt: skip


def _run(job: tuple) -> tuple[str, np.ndarray]:
    detector = MotionDetector("both", *job[3])  # its ray's tolerance, too
    rows = []
    for result, truth in sweep.scored_frames(job, detector):
        camera = result.camera
        if camera is None or not camera.reliable:
            continue
        tolerance = detector.ray_config.tolerance(camera.noise_px, camera.spread_px)
        row = frame_row(result, truth, tolerance)
        if row is not None:
            rows.append(row)
    return job[0], np.array(rows, float).reshape(-1, 8)


def _line(name: str, rows: np.ndarray) -> str:
    if not len(rows):
        return f"{name:30s} no frame scored"
    area, flagged, kept, off_flagged, off_kept = rows[:, :5].sum(axis=0)
    tolerance, mover, background = np.median(rows[:, 5:], axis=0)
    above = np.mean(rows[:, 5] > rows[:, 6])
    return (
        f"{name:30s} flagged {flagged / area:.2f}  kept {kept / area:.2f}  outside "
        f"{off_flagged / len(rows):6.0f} / {off_kept / len(rows):6.0f} px  tolerance "
        f"{tolerance:5.2f}  residual mover {mover:5.2f} rest {background:5.2f}  "
        f"tolerance above the mover's on {above:.2f}"
    )


def main() -> None:
    groups, results = sweep.on_masked_sequences(__doc__, _run)
    sweep.print_by_group(groups, results, _line, np.concatenate)


if __name__ == "__main__":
    main()
