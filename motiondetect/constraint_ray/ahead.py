"""The part of the observer-motion fit that depends on one frame alone.

:func:`~.camera_fit.fit_camera` fits the dominant plane to every sample of
the field first (the plane they all vote for), and only then leaves out
the samples of known movers, which the tracks of earlier frames give.
Most frames keep the voted plane. The voted plane, and what it leaves of
the frame (:class:`PlaneMaps`), depend on nothing judged before, so
:func:`fitted_ahead` can compute them before the frame is judged: on the
measuring thread, when it has finished the next frame's measurement while
this one is still being judged
(:meth:`~motiondetect.detection.detector.MotionDetector.prepare`). The fit
is the same either way; only where its time is spent changes.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from motiondetect.constraint_ray.fit_config import FitConfig
from motiondetect.constraint_ray.plane import (
    explained_share,
    fit_homography,
    plane_residual,
    point_residual,
    samples,
)
from motiondetect.constraint_ray.rolling_shutter import LineOffsets, line_offsets
from motiondetect.measurement.dense_flow import VelocityField, vector_length
from motiondetect.measurement.image_change import (
    difference_noise,
    plane_difference,
    seen_before,
    sharpness,
)


@dataclass(frozen=True)
class PlaneMaps:
    """What one plane leaves of a frame's field.

    Attributes
    ----------
    difference : (h, w) ndarray of uint8 or None
        :func:`~motiondetect.measurement.image_change.plane_difference`.
    change_noise : float or None
        Its :func:`~motiondetect.measurement.image_change.difference_noise`
        over the pixels ``seen`` before (the strip a fast pan brings in
        compares with nothing, and would raise it by up to half).
    residual : (h, w, 2) ndarray of float32 or None
        :func:`~.plane.plane_residual`, work px/frame.
    sampled : (N, 2) ndarray of float32 or None
        The residual at the samples (:func:`~.plane.samples`).
    energy : float
        The aperture energy the share is measured with, grey levels^2/px^2.
    share : float
        :func:`~.plane.explained_share`: the fit's confidence.
    cut : float
        The mean difference inside an 8-px border over the pixels the
        previous frame saw too (a cut's test), grey levels.
    seen : (h, w) ndarray of bool or None
        :func:`~motiondetect.measurement.image_change.seen_before`: the
        pixels the plane takes from inside the previous frame; the rest
        entered the view with this frame, and their flow is extrapolated.

    All None (share: the inliers' share) without a plane.
    """

    difference: np.ndarray | None
    change_noise: float | None
    residual: np.ndarray | None
    sampled: np.ndarray | None
    energy: float
    share: float
    cut: float
    seen: np.ndarray | None


def plane_maps(
    field: VelocityField,
    homography: np.ndarray | None,
    inliers: np.ndarray,
    config: FitConfig,
    lines: LineOffsets | None = None,
) -> PlaneMaps:
    """:class:`PlaneMaps` of ``homography`` on ``field``, its RANSAC ``inliers``
    among the samples given; with ``lines``, the plane's velocity plus the
    rolling shutter's offsets."""
    if homography is None:
        share = float(inliers.mean()) if len(inliers) else 0.0
        return PlaneMaps(None, None, None, None, 0.0, share, 0.0, None)
    offsets = None if lines is None else lines.field(field.shape)
    difference = plane_difference(field, homography, offsets)
    seen = seen_before(field, homography, offsets)
    # What just entered compares with nothing: its "difference" is its grey level.
    change_noise = difference_noise(difference, seen)
    residual = plane_residual(field, homography)
    if offsets is not None:
        residual = residual - offsets
    step = config.sample_step_px
    sampled = residual[step:-step:step, step:-step:step].reshape(-1, 2)
    energy = (config.aperture_noise * change_noise) ** 2
    share = explained_share(field, sampled, inliers, energy, step, config.ransac_px)
    cut = _seen_difference(seen, difference)
    return PlaneMaps(difference, change_noise, residual, sampled, energy, share, cut, seen)


def _seen_difference(seen: np.ndarray, difference: np.ndarray) -> float:
    """The mean of ``difference`` inside an 8-px border over the pixels
    ``seen`` in the previous frame too (:func:`seen_before`), grey levels: a
    cut's test. The strip a fast pan brings into view is left out: it is
    new, not changed, and at 60 px a frame it is a fifth of a 320-px frame.
    255 when the plane takes no pixel from the previous frame."""
    inner = seen[8:-8, 8:-8]
    if not inner.any():
        return 255.0
    return float(cv2.mean(difference[8:-8, 8:-8], mask=inner.view(np.uint8))[0])


def wobble_removed(
    field: VelocityField,
    ahead: Ahead,
    homography: np.ndarray,
    inliers: np.ndarray,
    maps: PlaneMaps,
    movers: np.ndarray | None = None,
    previous: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, PlaneMaps]:
    """The plane, its inliers and its maps with a rolling shutter's wobble
    taken out where the plane leaves one (:mod:`.rolling_shutter`): the
    plane fitted again to the velocities without the wobble, whose lines
    are then measured again against it. As given where there is none, and
    with ``[fit] line_gain`` 0 or a plane explaining too little to judge.
    ``movers`` (h, w) bool: the known movers (the tracks' predicted boxes),
    whose samples the wobble is not measured on; ``previous`` (N, 2): the
    last frame's plane residual at the samples (a wobble comes and goes;
    without it, nothing is taken out)."""
    config, points = ahead.config, ahead.points
    if config.line_gain <= 0 or maps.sampled is None or maps.share < config.min_inlier_share:
        return homography, inliers, maps
    step, (h, w) = config.sample_step_px, field.shape
    grid = (np.arange(step, h - step, step), np.arange(step, w - step, step))
    size = (len(grid[0]), len(grid[1]), 2)
    if previous is None or len(previous) != len(points):
        return homography, inliers, maps  # a wobble is told from parallax by its change
    scene = None
    if movers is not None:
        scene = ~movers[points[:, 1].astype(int), points[:, 0].astype(int)].reshape(size[:2])
    last = previous.reshape(size)
    args = (grid, config.line_gain, (h, w), config.ransac_px, scene, last)
    lines = line_offsets(maps.sampled.reshape(size), *args)
    if lines is None:
        return homography, inliers, maps
    kwargs = {"outlier_px": config.max_speed_px, "tight_px": config.tight_px, "seed": config.seed}
    refit, _ = fit_homography(points, ahead.velocity - lines.at(points), config.ransac_px, **kwargs)
    sampled = maps.sampled
    if refit is not None:
        sampled = point_residual(points, ahead.velocity, refit).astype(np.float32)
        again = line_offsets(sampled.reshape(size), *args)
        if again is None:  # measured against the plane refitted, there is none
            return homography, inliers, maps
        homography, lines = refit, again
    inliers = vector_length(sampled - lines.at(points)) < config.ransac_px
    return homography, inliers, plane_maps(field, homography, inliers, config, lines)


@dataclass(frozen=True)
class Ahead:
    """What :func:`~.camera_fit.fit_camera` reads of one field alone.

    Attributes
    ----------
    config : FitConfig
        The settings it was computed with (a fit with others computes its own).
    points, velocity : (N, 2) ndarray
        The samples (:func:`~.plane.samples`).
    speed : float
        Their median speed, work px/frame.
    voted : (homography or None, (N,) ndarray of bool)
        The plane all the samples vote for (:func:`~.plane.fit_homography`)
        and its inliers.
    maps : PlaneMaps or None
        What the voted plane leaves; None: not computed (the fit computes
        it for the plane it keeps).
    sharpness : float
        :func:`~motiondetect.measurement.image_change.sharpness` of the
        frame, 0 while the blur test is off.
    """

    config: FitConfig
    points: np.ndarray
    velocity: np.ndarray
    speed: float
    voted: tuple[np.ndarray | None, np.ndarray]
    maps: PlaneMaps | None
    sharpness: float


def ahead_of(field: VelocityField, config: FitConfig, maps: bool = True) -> Ahead:
    """``field``'s :class:`Ahead` for ``config``: the one computed before
    (:func:`fitted_ahead`), else computed now, with the voted plane's
    :class:`PlaneMaps` only when ``maps``."""
    known = field.ahead
    if isinstance(known, Ahead) and known.config == config:
        return known
    points, velocity = samples(field, config.sample_step_px)
    speed = float(np.median(np.hypot(velocity[:, 0], velocity[:, 1]))) if len(points) else 0.0
    voted = fit_homography(
        points, velocity, config.ransac_px, outlier_px=config.max_speed_px,
        tight_px=config.tight_px, seed=config.seed,
    )  # fmt: skip
    left = plane_maps(field, voted[0], voted[1], config) if maps else None
    sharp = sharpness(field.grey) if config.blur_ratio > 0 else 0.0
    return Ahead(config, points, velocity, speed, voted, left, sharp)


def fitted_ahead(field: VelocityField, config: FitConfig) -> VelocityField:
    """``field`` with its :class:`Ahead` for ``config`` attached (as
    :attr:`~motiondetect.measurement.dense_flow.VelocityField.ahead`)."""
    return field.replaced(ahead=ahead_of(field, config))
