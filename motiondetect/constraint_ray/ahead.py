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

import numpy as np

from motiondetect.constraint_ray.fit_config import FitConfig
from motiondetect.constraint_ray.plane import (
    explained_share,
    fit_homography,
    plane_residual,
    samples,
)
from motiondetect.measurement.dense_flow import VelocityField
from motiondetect.measurement.image_change import difference_noise, plane_difference, sharpness


@dataclass(frozen=True)
class PlaneMaps:
    """What one plane leaves of a frame's field.

    Attributes
    ----------
    difference : (h, w) ndarray of uint8 or None
        :func:`~motiondetect.measurement.image_change.plane_difference`.
    change_noise : float or None
        Its :func:`~motiondetect.measurement.image_change.difference_noise`.
    residual : (h, w, 2) ndarray of float32 or None
        :func:`~.plane.plane_residual`, work px/frame.
    sampled : (N, 2) ndarray of float32 or None
        The residual at the samples (:func:`~.plane.samples`).
    energy : float
        The aperture energy the share is measured with, grey levels^2/px^2.
    share : float
        :func:`~.plane.explained_share`: the fit's confidence.
    cut : float
        The mean difference inside an 8-px border (a cut's test), grey levels.

    All None (share: the inliers' share) without a plane.
    """

    difference: np.ndarray | None
    change_noise: float | None
    residual: np.ndarray | None
    sampled: np.ndarray | None
    energy: float
    share: float
    cut: float


def plane_maps(
    field: VelocityField, homography: np.ndarray | None, inliers: np.ndarray, config: FitConfig
) -> PlaneMaps:
    """:class:`PlaneMaps` of ``homography`` on ``field``, its RANSAC ``inliers``
    among the samples given."""
    if homography is None:
        share = float(inliers.mean()) if len(inliers) else 0.0
        return PlaneMaps(None, None, None, None, 0.0, share, 0.0)
    difference = plane_difference(field, homography)
    change_noise = difference_noise(difference)
    residual = plane_residual(field, homography)
    step = config.sample_step_px
    sampled = residual[step:-step:step, step:-step:step].reshape(-1, 2)
    energy = (config.aperture_noise * change_noise) ** 2
    share = explained_share(field, sampled, inliers, energy, step, config.ransac_px)
    cut = float(difference[8:-8, 8:-8].mean())
    return PlaneMaps(difference, change_noise, residual, sampled, energy, share, cut)


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
