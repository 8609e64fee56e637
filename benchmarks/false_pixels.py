r"""Where the flagged pixels that are not the mover lie.

    python benchmarks/false_pixels.py davis
    python benchmarks/false_pixels.py davis,ucsd '{"track": {"outline_px": 2}}'

Pixel precision on DAVIS was about half: which half? Each flagged pixel
outside the labelled mover falls in one of these classes, given as shares of
all flagged pixels:

- *apart*: in a flagged region that touches no labelled pixel (a false
  alarm, or a mover the labels leave out);
- *band 0-4*, *4-12*, *12-30*, *beyond 30*: in a region that touches the
  mover, at that distance from it (input px, L2).

A mask that is fat all round fills the near bands; a region joined to
unlabelled motion (a second animal, water, smoke) fills *beyond 30*. Scores
come from the default detector or from the config sections given as JSON
(``sweep.configs``); unknown pixels (CDnet's 170) are left out, frames 0-1
are not scored.
"""

from __future__ import annotations

import cv2
import numpy as np
import sweep

from motiondetect.tools.evaluate import truth_masks

#: Distance bands from the labelled mover, input px: (above, at most).
BANDS = ((0, 4), (4, 12), (12, 30), (30, np.inf))
COLUMNS = ("hit", "apart") + tuple(
    f"band {a:g}-{b:g}" if np.isfinite(b) else f"beyond {a:g}" for a, b in BANDS
)


def false_pixels(flagged: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """Pixel counts for one frame, in the order of ``COLUMNS``.

    Parameters
    ----------
    flagged : (h, w) ndarray of bool
    truth : (h, w) ndarray of uint8
        A ground-truth mask (0 static, 255 moving, 170 unknown).
    """
    positive, unknown = truth_masks(truth)
    _, labels = cv2.connectedComponents(flagged.view(np.uint8), connectivity=8)
    touched = np.unique(labels[flagged & positive])
    touching = np.isin(labels, touched[touched > 0])
    false = flagged & ~positive & ~unknown
    distance = cv2.distanceTransform((~positive).view(np.uint8), cv2.DIST_L2, 3)
    near = false & touching
    bands = [np.count_nonzero(near & (distance > a) & (distance <= b)) for a, b in BANDS]
    hits = np.count_nonzero(flagged & positive)  # unknown pixels are not positive
    return np.array([hits, np.count_nonzero(false & ~touching), *bands], np.int64)


def _run(job: tuple) -> tuple[str, np.ndarray]:
    total = np.zeros(len(COLUMNS), np.int64)
    for result, truth in sweep.scored_frames(job):
        h, w = truth.shape
        total += false_pixels(result.input_mask(w, h) > 0, truth)
    return job[0], total


def _line(name: str, counts: np.ndarray) -> str:
    shares = counts / max(int(counts.sum()), 1)
    cells = "  ".join(f"{c} {s:.2f}" for c, s in zip(COLUMNS, shares))
    return f"{name:30s} {cells}"


def main() -> None:
    sweep.print_summed(__doc__, _run, _line)


if __name__ == "__main__":
    main()
