"""The dominant plane: a RANSAC homography on the sampled velocity field.

Step 1 of :mod:`.camera_fit`. The homography takes each current pixel to
where the plane's point was in the previous frame; it absorbs the camera's
rotation and the motion of the dominant surface (or of the plane at
infinity). What it leaves, the plane residual, is parallax and independent
motion. Pure functions of one frame's field.
"""

from __future__ import annotations

import cv2
import numpy as np

from motiondetect.measurement.aperture import determined
from motiondetect.measurement.dense_flow import VelocityField, vector_length

#: Gaussian 2-D noise: median |r| = sigma * sqrt(2 ln 2).
MEDIAN_TO_SIGMA = 1.0 / np.sqrt(2.0 * np.log(2.0))


def samples(field: VelocityField, step: int) -> tuple[np.ndarray, np.ndarray]:
    """Grid samples away from the border: points and their velocities, (N, 2) each."""
    h, w = field.shape
    b = step
    pts = field.pixel_grid[b : h - b : step, b : w - b : step].reshape(-1, 2)
    vel = field.velocity_px[b : h - b : step, b : w - b : step].reshape(-1, 2)
    return pts, vel


def plane_residual(field: VelocityField, homography: np.ndarray) -> np.ndarray:
    """Velocity left after the dominant plane's, at every work pixel.

    Returns
    -------
    (h, w, 2) ndarray of float32, work px/frame
    """
    grid = field.pixel_grid
    h, w = field.shape
    previous = cv2.perspectiveTransform(grid.reshape(-1, 1, 2), homography).reshape(h, w, 2)
    plane_velocity = grid - previous
    return (field.velocity_px - plane_velocity).astype(np.float32)


#: DIS's error on textured motion, work px/frame: the refit never takes the
#: noise below it (it binds only on a noiseless, synthetic field).
_DIS_ERROR_PX = 0.1


def _ransac(points: np.ndarray, velocity: np.ndarray, threshold_px: float) -> np.ndarray | None:
    homography, _ = cv2.findHomography(
        points, points - velocity, cv2.RANSAC, threshold_px, maxIters=500, confidence=0.99
    )
    return homography


def plane_error(points: np.ndarray, velocity: np.ndarray, homography: np.ndarray) -> np.ndarray:
    """|velocity - the plane's velocity| at each point, (N,) px/frame."""
    previous = cv2.perspectiveTransform(points.reshape(-1, 1, 2).astype(np.float64), homography)
    return np.hypot(*(previous.reshape(-1, 2) - (points - velocity)).T)


def fit_homography(
    points: np.ndarray, velocity: np.ndarray, threshold_px: float, refit_sigmas: float = 0.0
) -> tuple[np.ndarray | None, np.ndarray]:
    """RANSAC homography from current points to where they were.

    With ``refit_sigmas``, the plane found at ``threshold_px`` measures the
    noise (robust sigma of its inliers' errors) and RANSAC runs again at
    ``refit_sigmas`` of it. RANSAC's final least-squares step runs over
    every point within its threshold: at a threshold far above the flow's
    noise those include a slow mover or a near surface, which pull the
    plane toward themselves (a compromise that halves their residual). At
    the measured noise scale only the dominant plane's points remain.

    Returns
    -------
    homography : (3, 3) ndarray or None
    inliers : (N,) ndarray of bool
        Within ``threshold_px`` of the returned plane (the refit changes
        which plane, not what counts as explained).
    """
    if len(points) < 8:
        return None, np.zeros(len(points), bool)
    homography = _ransac(points, velocity, threshold_px)
    if homography is None:
        return None, np.zeros(len(points), bool)
    error = plane_error(points, velocity, homography)
    inliers = error < threshold_px
    if refit_sigmas > 0 and inliers.any():
        sigma = float(np.median(error[inliers])) * MEDIAN_TO_SIGMA
        tight = refit_sigmas * max(sigma, _DIS_ERROR_PX)
        refit = _ransac(points, velocity, tight) if tight < threshold_px else None
        if refit is not None:
            homography = refit
            inliers = plane_error(points, velocity, homography) < threshold_px
    return homography, inliers


def residual_spread(magnitude: np.ndarray) -> float:
    """Robust sigma of residual vectors from their lengths (any shape): the
    median of a 2-D Gaussian's length over sqrt(2 ln 2). 0 when empty."""
    return float(np.median(magnitude) * MEDIAN_TO_SIGMA) if magnitude.size else 0.0


def explained_share(
    field: VelocityField,
    sampled: np.ndarray,
    inliers: np.ndarray,
    energy: float,
    step: int,
    threshold_px: float,
) -> float:
    """Share of the samples the plane explains as far as the image determines.

    A sample counts when it is a RANSAC inlier or when the part of its
    residual the image determines (:func:`~motiondetect.measurement.aperture.determined`
    with the aperture energy the detectors' seeds are tested with) is within
    ``threshold_px``: a residual along motion-blurred grass or a straight
    edge is DIS's fill-in, not evidence against the plane, and could not
    flag anything either.

    Parameters
    ----------
    field : VelocityField
    sampled : (N, 2) ndarray of float32
        The plane residual at the RANSAC samples, work px/frame.
    inliers : (N,) ndarray of bool
        RANSAC's.
    energy : float
        Aperture energy, grey levels^2/px^2 (0: the RANSAC share alone).
    step : int
        The samples' grid step, work px (:func:`samples`).
    threshold_px : float
        RANSAC's inlier threshold, work px/frame.
    """
    if not len(inliers):
        return 0.0
    if energy <= 0:
        return float(inliers.mean())
    tensor = tuple(t[step:-step:step, step:-step:step].reshape(-1) for t in field.structure)
    length = vector_length(determined(sampled, tensor, energy))
    return float((inliers | (length < threshold_px)).mean())
