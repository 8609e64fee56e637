r"""Where a mask's edge lies against the mover's: the band it adds and the band it misses.

    python benchmarks/edge_band.py davis
    python benchmarks/edge_band.py davis,ucsd '{"track": {"rim_look": false}}'

For each sequence with mask ground truth, at the working size (the truth
reduced by area, a pixel a mover's when at least half of it is), pooled
over the scored frames: the pixels of the final mask outside the mover
(and its unknown pixels) by their distance to it, 1 to 7 work px and 8 or
more, and the mover's pixels the mask misses by their distance to the
mask; each as a share of the mover's area. An edge that lies on the
mover's has both near bands small; a mask that reaches past it by a band
of smeared flow has a large outside band at 1-3 px and a small missed one.
The far columns (8 px or more) are other things: regions off the mover
(other movers the truth does not label, false alarms) and parts of the
mover never found. Scores come from the default detector or from the
config sections given as JSON (``sweep.configs``); frames 0-1 are not
scored.
"""

from __future__ import annotations

import cv2
import numpy as np
import sweep

from motiondetect.tools.evaluate import truth_masks

#: Distance bands, work px: 1 .. FAR - 1, and FAR or more.
FAR = 8


def _by_distance(pixels: np.ndarray, distance: np.ndarray) -> np.ndarray:
    """(FAR,) counts of ``pixels`` by ``distance`` rounded up, 1 to FAR."""
    bands = np.clip(np.ceil(distance[pixels]).astype(int), 1, FAR) - 1
    return np.bincount(bands, minlength=FAR)


def frame_bands(mask: np.ndarray, truth: np.ndarray) -> np.ndarray | None:
    """(2 FAR + 1,): outside pixels by band, missed pixels by band, the
    mover's area; None when the frame has no mover."""
    h, w = mask.shape
    mover, unknown = (
        cv2.resize(255 * m.astype(np.uint8), (w, h), interpolation=cv2.INTER_AREA) >= 128
        for m in truth_masks(truth)
    )
    if not mover.any():
        return None
    to_mover = cv2.distanceTransform((~(mover | unknown)).astype(np.uint8), cv2.DIST_L2, 3)
    outside = _by_distance(mask & ~mover & ~unknown, to_mover)
    missed = np.zeros(FAR)
    if mask.any():
        to_mask = cv2.distanceTransform((~mask).astype(np.uint8), cv2.DIST_L2, 3)
        missed = _by_distance(mover & ~mask, to_mask)
    else:
        missed[-1] = mover.sum()
    return np.concatenate([outside, missed, [mover.sum()]])


def _run(job: tuple) -> tuple[str, np.ndarray]:
    total = np.zeros(2 * FAR + 1)
    for result, truth in sweep.scored_frames(job):
        row = None if result.mask is None else frame_bands(result.mask, truth)
        if row is not None:
            total += row
    return job[0], total


def _line(name: str, total: np.ndarray) -> str:
    area = max(total[-1], 1.0)
    shares = (total[:-1] / area).reshape(2, FAR)
    outside, missed = (" ".join(f"{x:.3f}" for x in part) for part in shares)
    return f"{name:24s} outside by px 1..{FAR}+: {outside} | missed: {missed}"


def main() -> None:
    sweep.print_summed(__doc__, _run, _line)


if __name__ == "__main__":
    main()
