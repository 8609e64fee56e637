"""The velocity a smooth world predicts: last frame's, carried on by the camera's change.

Detector 2's prediction for a point is the velocity it had in the
previous frame (section 4). A camera's own motion changes between frames
(a hand's rotational jitter, a pan that speeds up), and that changes every
point's velocity at once; the paper compensates it. The change is fitted
here to the velocities themselves: each sampled point, moved on by its
previous velocity, lands near where it is now up to one homography, ``G``
(a change of rotation moves every point by a homography whatever its
depth; a steady translation changes little from one frame to the next).
RANSAC keeps the points that broke their motion out of the fit.

Removing each frame's fitted plane instead (the residuals' difference)
compensates the same change only while both frames' planes are the same
surface. Where parallax spreads over many depths no surface dominates,
the 1-px RANSAC plane is a compromise that changes from frame to frame,
and the difference of two such planes moves every rigid point by up to a
few px (docs/detectors.md, "The camera's change fitted to the velocities").

Pure functions of two frames' fields.
"""

from __future__ import annotations

import cv2
import numpy as np

from motiondetect.constraint_ray.fit_config import FitConfig
from motiondetect.constraint_ray.plane import ransac_homography

#: Step of the grid the change is fitted on, work px: the plane's default.
SAMPLE_STEP_PX = FitConfig.sample_step_px
#: Fewest samples a change is fitted to.
MIN_SAMPLES = 16
_ROW = 1024  # points per row of a sampling block (remap takes at most 32767 columns)


def sample_at(image: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Bilinear samples of ``image`` at ``points``; NaN outside the frame.

    Parameters
    ----------
    image : (h, w, 2) ndarray of float32
    points : (N, 2) ndarray of float32, (x, y) work px

    Returns
    -------
    (N, 2) ndarray of float32
    """
    n = len(points)
    rows = -(-n // _ROW)
    block = np.full((rows * _ROW, 2), -1.0, np.float32)
    block[:n] = points
    block = block.reshape(rows, _ROW, 2)
    out = cv2.remap(
        image, block[..., 0], block[..., 1], cv2.INTER_LINEAR,
        borderMode=cv2.BORDER_CONSTANT, borderValue=(np.nan, np.nan),
    )  # fmt: skip
    return out.reshape(-1, 2)[:n]


def continued_velocity(
    previous: np.ndarray,
    pixel_grid: np.ndarray,
    source: np.ndarray,
    ratio: float,
    threshold_px: float,
) -> np.ndarray:
    """The velocity each previous-frame point would have now if it moved on smoothly.

    Parameters
    ----------
    previous : (h, w, 2) ndarray of float32
        The previous frame's velocity, work px/frame.
    pixel_grid : (h, w, 2) ndarray of float32
        (x, y) of every work pixel.
    source : (h, w, 2) ndarray of float32
        Where each current pixel was in the previous frame.
    ratio : float
        This frame's interval over the last one's (1: equal).
    threshold_px : float
        RANSAC's threshold for the camera's change, work px.

    Returns
    -------
    (h, w, 2) ndarray of float32
        At each previous-frame pixel ``x``, ``G(x + ratio v(x)) - x``: where
        it would be now, less where it was. ``G`` is the identity when too
        few samples fit one.
    """
    step = SAMPLE_STEP_PX
    was = source[step::step, step::step].reshape(-1, 2)
    now = pixel_grid[step::step, step::step].reshape(-1, 2)
    before = sample_at(previous, was)
    known = np.isfinite(before).all(axis=1)
    moved_on = was[known] + np.float32(ratio) * before[known]
    change = None
    if known.sum() >= MIN_SAMPLES:
        change = ransac_homography(moved_on, moved_on - now[known], threshold_px)
    h, w = previous.shape[:2]
    ahead = pixel_grid + np.float32(ratio) * previous
    if change is not None:
        ahead = cv2.perspectiveTransform(ahead.reshape(-1, 1, 2), change).reshape(h, w, 2)
    return (ahead - pixel_grid).astype(np.float32)
