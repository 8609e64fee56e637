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


#: Smallest inlier sigma of the likelihood, work px/frame: a numerical guard
#: for a noiseless (synthetic) field; real frames measure 0.03-0.4 px.
_MIN_SIGMA_PX = 0.01
_EM_ROUNDS = 10


def ransac_homography(
    points: np.ndarray,
    velocity: np.ndarray,
    threshold_px: float,
    draws: int = 500,
    confidence: float = 0.99,
) -> np.ndarray | None:
    """OpenCV's RANSAC homography from current ``points`` to where they were
    (``points - velocity``), at most ``draws`` draws; None when none is found."""
    homography, _ = cv2.findHomography(
        points, points - velocity, cv2.RANSAC, threshold_px, maxIters=draws, confidence=confidence
    )
    return homography


def point_residual(points: np.ndarray, velocity: np.ndarray, homography: np.ndarray) -> np.ndarray:
    """velocity - the plane's velocity at each point, (N, 2) px/frame."""
    previous = cv2.perspectiveTransform(points.reshape(-1, 1, 2).astype(np.float64), homography)
    return previous.reshape(-1, 2) - (points - velocity)


def plane_error(points: np.ndarray, velocity: np.ndarray, homography: np.ndarray) -> np.ndarray:
    """|velocity - the plane's velocity| at each point, (N,) px/frame."""
    return np.hypot(*point_residual(points, velocity, homography).T)


def mixture_log_likelihood(error: np.ndarray, outlier_px: float) -> np.ndarray | float:
    """Log-likelihood of a plane's errors, (N,) px/frame, under a mixture:
    inliers a 2-D Gaussian of their own sigma, outliers spread evenly over
    the disc of radius ``outlier_px`` (the measurable velocities).

    The share and sigma are fitted by a few rounds of EM from the robust
    estimates (MLESAC's score, Torr and Zisserman 2000). Errors of several
    planes at the same points, (K, N), are scored together: (K,) scores.
    """
    one = np.ndim(error) == 1
    error = np.atleast_2d(error).astype(np.float64)
    e2 = error**2
    floor = _MIN_SIGMA_PX**2
    spread = np.median(error, axis=1, keepdims=True) * MEDIAN_TO_SIGMA
    var = np.maximum(spread**2, floor)
    share = np.mean(e2 < 9.0 * var, axis=1, keepdims=True)
    outlier = 1.0 / (np.pi * outlier_px**2)
    for _ in range(_EM_ROUNDS):
        share = np.clip(share, 1e-3, 1.0 - 1e-3)
        inlier = share / (2.0 * np.pi * var) * np.exp(-e2 / (2.0 * var))
        density = inlier + (1.0 - share) * outlier
        weight = inlier / density
        share = weight.mean(axis=1, keepdims=True)
        total = weight.sum(axis=1, keepdims=True)
        var = np.maximum(
            (weight * e2).sum(axis=1, keepdims=True) / (2.0 * np.maximum(total, 1e-9)), floor
        )
    scores = np.log(density).sum(axis=1)
    return float(scores[0]) if one else scores


def fit_homography(
    points: np.ndarray,
    velocity: np.ndarray,
    threshold_px: float,
    *,
    outlier_px: float,
    tight_px: float = 0.0,
    seed: int = 0,
) -> tuple[np.ndarray | None, np.ndarray]:
    """RANSAC homography from current points to where they were.

    With ``tight_px``, RANSAC also runs at that threshold, and the plane
    kept is the one under which the velocities are likelier
    (:func:`mixture_log_likelihood`). RANSAC's final least-squares step runs
    over every point within its threshold: at 1 px, ten times DIS's error, a
    slow mover or a near surface inside that band pulls the plane toward
    itself (a compromise that keeps part of the mover's residual hidden).
    Where one surface dominates, the tight plane fits its points far better
    and wins; where none does (parallax over many depths), the compromise
    explains more of the frame and is kept.

    OpenCV draws the same samples from the same points on every call; a
    non-zero ``seed`` shuffles the points first, so RANSAC draws others.

    Returns
    -------
    homography : (3, 3) ndarray or None
    inliers : (N,) ndarray of bool
        Within ``threshold_px`` of the plane kept (the choice changes which
        plane, not what counts as explained), in the order given.
    """
    if len(points) < 8:
        return None, np.zeros(len(points), bool)
    if seed:
        order = np.random.default_rng(seed).permutation(len(points))
        homography, shuffled = fit_homography(
            points[order], velocity[order], threshold_px, outlier_px=outlier_px, tight_px=tight_px
        )
        inliers = np.empty_like(shuffled)
        inliers[order] = shuffled
        return homography, inliers
    homography = ransac_homography(points, velocity, threshold_px)
    if homography is None:
        return None, np.zeros(len(points), bool)
    error = plane_error(points, velocity, homography)
    tight = ransac_homography(points, velocity, tight_px) if 0 < tight_px < threshold_px else None
    if tight is not None:
        tight_error = plane_error(points, velocity, tight)
        loose_score, tight_score = mixture_log_likelihood(
            np.stack([error, tight_error]), outlier_px
        )
        if tight_score > loose_score:
            homography, error = tight, tight_error
    return homography, error < threshold_px


def fit_homography_without(
    points: np.ndarray,
    velocity: np.ndarray,
    movers: np.ndarray,
    threshold_px: float,
    *,
    outlier_px: float,
    min_rest: float,
    tight_px: float = 0.0,
    seed: int = 0,
    voted: tuple[np.ndarray | None, np.ndarray] | None = None,
) -> tuple[np.ndarray | None, np.ndarray]:
    """:func:`fit_homography`, with the samples on known movers not voting.

    Independent motion says nothing about the observer's: a mover the
    camera follows, once it covers about as much of the view as the
    background, takes the fit (the background is then flagged and the mover
    missed); a slower one pulls the plane toward itself. Where the plane
    fitted to all the samples explains those on ``movers`` at least as well
    as the rest (a larger share of them are its inliers: it is their plane
    as much as the scene's), the plane is fitted again without them, and
    kept when the rest of the samples are likelier under it
    (:func:`mixture_log_likelihood`, the rest's errors under both planes).
    Movers the plane already leaves out, and flagged water or
    parallax (worse explained than the scene), keep their vote: leaving
    them out would only let the plane leave them more.

    Parameters
    ----------
    points, velocity : (N, 2) ndarray
        As :func:`fit_homography`.
    movers : (N,) ndarray of bool
        Samples on known movers (the confirmed tracks' predicted boxes).
    min_rest : float
        The share of the samples that must remain (``FitConfig.min_inlier_share``);
        below it the plane is fitted to all of them, as without ``movers``.
    voted : (homography, inliers), optional
        :func:`fit_homography` of all the samples, when already computed.

    Returns
    -------
    homography : (3, 3) ndarray or None
    inliers : (N,) ndarray of bool
        Every sample within ``threshold_px`` of the plane kept, movers too.
    """
    kwargs = {"outlier_px": outlier_px, "tight_px": tight_px, "seed": seed}
    homography, inliers = voted or fit_homography(points, velocity, threshold_px, **kwargs)
    rest = ~movers
    if homography is None or not movers.any() or rest.mean() < min_rest:
        return homography, inliers
    if inliers[movers].mean() < inliers[rest].mean():
        return homography, inliers  # the movers do not carry the plane
    alone, _ = fit_homography(points[rest], velocity[rest], threshold_px, **kwargs)
    if alone is None:
        return homography, inliers
    errors = [plane_error(points[rest], velocity[rest], h) for h in (homography, alone)]
    with_movers, without = mixture_log_likelihood(np.stack(errors), outlier_px)
    if without <= with_movers:
        return homography, inliers
    return alone, plane_error(points, velocity, alone) < threshold_px


def residual_spread(magnitude: np.ndarray) -> float:
    """Robust sigma of residual vectors from their lengths (any shape): the
    median of a 2-D Gaussian's length over sqrt(2 ln 2). 0 when empty."""
    return float(np.median(magnitude) * MEDIAN_TO_SIGMA) if magnitude.size else 0.0


def frame_spread(
    magnitude: np.ndarray,
    voters: np.ndarray,
    on_movers: np.ndarray | None,
    quantile: float,
    ratio: float,
    min_rest: float,
) -> float:
    """The spread of the plane residual over the frame, work px/frame.

    :func:`residual_spread` of the samples the plane was fitted to
    (``voters``): the noise plus the rigid parallax the plane leaves. The
    median breaks down once movers hold half the samples; a mover the
    camera follows close up then sets the spread, and a tolerance of
    several spreads hides it. So where the samples outside the known movers
    (``~on_movers``, at least ``min_rest`` of all) give a spread under
    ``ratio`` of that one, theirs is kept: the ``quantile`` of their
    lengths over a 2-D Gaussian's (``sqrt(-2 ln(1 - q))`` sigmas; the
    median is the quantile 0.5), a high quantile so that rigid parallax's
    heavy tail is kept, which a median would cut.

    Parameters
    ----------
    magnitude : (N,) ndarray
        Residual lengths at the samples, work px/frame.
    voters : (N,) ndarray of bool
    on_movers : (N,) ndarray of bool or None
        Samples inside the confirmed tracks' predicted boxes; None: none known.
    quantile : float
        In [0, 1); 0: the spread over ``voters`` alone.
    ratio : float
        The rest's spread is kept only below this share of the spread over
        ``voters`` (0.5: the movers have doubled the median).
    min_rest : float
        Share of all the samples that must lie outside the movers.
    """
    spread = residual_spread(magnitude[voters])
    if quantile <= 0 or on_movers is None or not on_movers.any():
        return spread
    rest = voters & ~on_movers
    if rest.sum() < min_rest * len(magnitude):
        return spread
    tail = float(np.quantile(magnitude[rest], quantile) / np.sqrt(-2.0 * np.log(1.0 - quantile)))
    return tail if tail < ratio * spread else spread


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
