"""Detector 1 on the full velocity: the constraint ray in velocity space.

Section 3 of the paper states the test for the 2-D velocity: a rigid
point's velocity lies on the segment ``V_w + s V_XY``, ``s`` in ``[0, a]``
(Figure 2), so a velocity off that segment is independent motion. The
normal-flow filter (:mod:`.normal_filter`) tests only the projection of
that segment on the gradient; here the velocity itself is tested.

* **Fitted observer motion** (default): after the dominant plane's
  velocity is removed, the ray runs through the point toward or away from
  the epipole (:mod:`.camera_fit`); the distance *across* it is the test.
  Without usable parallax the ray shrinks to a point and the whole
  residual is tested.
* **Known ego-motion** (``--egomotion``): the exact segment per point,
  shortened by the depth bound, as in the normal-flow path.

A point is flagged when it lies off the ray by more than a tolerance set
by the frame's measured noise (``noise_sigmas`` robust sigmas of the
plane's inliers, ``spread_sigmas`` robust sigmas of the whole frame's
off-ray distance, and at least ``floor_px``). Under the fit that distance
carries the rigid parallax the plane leaves; under known ego-motion, the
pose's and the lens's errors. Either way a seed must also lie off the ray
in the part of its velocity the image determines (the aperture test), and
where the image changed once the plane's motion is undone.
Flagged points are grown by hysteresis over their neighbours that lie off
the ray by half as much, so a mover is found whole rather than at its
strongest edges. Movers that travel *along* their ray are invisible to
this test (the blind spot, section 3.3).

Movers slower than one frame's tolerance are found on the residual summed
over frames along the motion (``carry``, ``slow_px``; not in the paper,
docs/detectors.md): a steady motion adds up, independent noise much less.
The floor of that test stands for DIS's error repeating under a moving
image, so it shrinks with the image's speed (``slow_still_px``,
``slow_full_speed_px``): a still camera's slow movers are found.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import cv2
import numpy as np

from motiondetect.config_checks import check_fields
from motiondetect.constraint_ray.camera_fit import CameraFit, fit_camera
from motiondetect.constraint_ray.egomotion import known_motion
from motiondetect.constraint_ray.epipole import off_ray
from motiondetect.constraint_ray.fit_config import FitConfig
from motiondetect.constraint_ray.observer_motion import ObserverMotion
from motiondetect.constraint_ray.plane import residual_spread
from motiondetect.detection.base import DetectorOutput
from motiondetect.detection.regions import (
    components,
    discounted_near_edge,
    hysteresis,
    true_pixels,
    without_frame_edge,
)
from motiondetect.measurement.dense_flow import VelocityField, vector_length

NAME = "velocity-ray"
_SPREAD_STEP = 8  # px between the samples the summed field's spread is measured on


@dataclass(frozen=True)
class VelocityRayConfig:
    """Settings of the velocity-space constraint ray filter.

    Attributes
    ----------
    noise_sigmas : float
        Tolerance in robust noise sigmas of the frame's residual.
    floor_px : float
        Smallest tolerance under the fitted motion, work px/frame: five
        times DIS's error on textured sub-pixel motion (about 0.1 px), the
        same five sigmas as ``spread_sigmas``. DIS's larger errors (low
        texture, content entering the frame) are left to the aperture test
        (``FitConfig.aperture_noise``) and the frame-edge band.
    spread_sigmas : float
        The tolerance is also at least this many robust sigmas of the whole
        frame's off-ray distance. Under the fitted motion that is the plane
        residual (``CameraFit.spread_px``): the rigid parallax the plane
        leaves is measured per frame, not assumed. Under known ego-motion it
        is the distance off the known segments: what the given poses and the
        unmodelled lens distortion leave.
    known_floor_px : float
        Smallest tolerance under known ego-motion, which leaves no parallax
        unmodelled (the normal-flow filter's floor).
    grow_ratio : float
        Hysteresis: flagged regions grow over points off the ray by at
        least this share of the tolerance.
    close_px : int
        Morphological closing that joins the fragments of one mover, work px.
    evidence_sigmas : float
        A seed must also show a grey-level change after the plane warp: its
        local mean above this many robust sigmas of the frame's changes (0: off).
        Flow alone can be wrong (blank sky, smeared boundaries); a mover
        changes the image where it is.
    evidence_box : int
        Side of the box the change is averaged over, work px (about DIS's patch).
    carry : float
        Slow movers: each frame's residual is added to this share of the
        previous sum, carried along the motion (0: off), so a motion too
        slow for one frame's tolerance adds up over about ``1 / (1 - carry)``
        frames while independent noise does not.
    slow_px : float
        The slowest steady residual motion the summed test flags, work
        px/frame: its tolerance is ``slow_px / (1 - carry)`` (or the summed
        field's own spread, as for one frame). It stands for DIS's error
        under a moving image, which repeats from frame to frame (a steady
        sub-pixel motion is measured with the same bias each time) and so
        adds up in the sum as a mover does.
    slow_still_px : float
        ``slow_px`` on a still image, work px/frame. What DIS gets wrong
        there repeats too, but less: a codec's ringing along strong edges
        under a camera that trembles by a fraction of a pixel. Set as the
        smallest floor at which still renders with rotational jitter of
        0.01-0.04 deg/frame flag at most one region in 50 frames
        (docs/detectors.md, "A still camera's slow movers").
    slow_full_speed_px : float
        The image's speed (the fitted plane's own median speed,
        ``CameraFit.plane_speed_px``, work px/frame; not the measured
        velocities' median, which DIS's noise raises on a still camera) from
        which the repeating error under motion has its full size: DIS's
        median error on known translations is none still, 0.023 px at 0.1
        px/frame and 0.04-0.06 px from 0.3 px/frame on. Below it the floor runs in
        proportion from ``slow_still_px`` to ``slow_px``; 0: ``slow_px`` at
        every speed.
    edge_error_ratio : float
        Within one DIS patch of the frame edge (``VelocityField.patch_px``)
        the off-ray distance, one frame's and the summed, counts divided by
        this: DIS's error there is about twice the inside's, measured on
        motions with known answers (``benchmarks/velocity_accuracy.py
        --border``). 1: off.
    """

    noise_sigmas: float = 3.0
    floor_px: float = 0.5
    spread_sigmas: float = 5.0
    known_floor_px: float = 0.3
    grow_ratio: float = 0.5
    close_px: int = 5
    evidence_sigmas: float = 3.0
    evidence_box: int = 5
    carry: float = 0.75
    slow_px: float = 0.6
    slow_still_px: float = 0.2
    slow_full_speed_px: float = 0.3
    edge_error_ratio: float = 2.0

    def __post_init__(self) -> None:
        check_fields(
            self,
            positive=(
                "noise_sigmas",
                "floor_px",
                "known_floor_px",
                "grow_ratio",
                "edge_error_ratio",
            ),
            non_negative=(
                "close_px",
                "spread_sigmas",
                "carry",
                "slow_px",
                "slow_still_px",
                "slow_full_speed_px",
            ),
        )
        if self.carry >= 1:
            raise ValueError(f"carry must be below 1, but got {self.carry}")
        if self.grow_ratio > 1:
            raise ValueError(f"grow_ratio must be at most 1, but got {self.grow_ratio}")
        if self.edge_error_ratio < 1:
            raise ValueError(f"edge_error_ratio must be at least 1, got {self.edge_error_ratio}")

    def tolerance(self, noise_px: float, spread_px: float, floor_px: float | None = None) -> float:
        """Largest distance of a rigid point off its ray, px/frame, from the
        plane's noise and the frame's spread (``CameraFit.noise_px``,
        ``spread_px``) and the floor (default ``floor_px``)."""
        floor = self.floor_px if floor_px is None else floor_px
        return max(floor, self.noise_sigmas * noise_px, self.spread_sigmas * spread_px)


def gap_to_segment(velocity: np.ndarray, start: np.ndarray, step: np.ndarray, bound: float):
    """Each velocity minus the nearest point of the segment ``start + s * step``,
    ``s`` in [0, bound].

    Parameters
    ----------
    velocity, start, step : (..., 2) ndarray, px/frame
    bound : float

    Returns
    -------
    (..., 2) ndarray of float32, px/frame
    """
    d = velocity - start
    length2 = (step * step).sum(axis=-1)
    s = np.where(length2 > 1e-12, (d * step).sum(axis=-1) / np.maximum(length2, 1e-12), 0.0)
    s = np.clip(s, 0.0, bound)[..., None]
    return (d - s * step).astype(np.float32)


def known_ray_gap(field: VelocityField, model: ObserverMotion) -> np.ndarray:
    """Under known ego-motion, each velocity's offset from its point's
    segment ``V_w + s V_XY``, (h, w, 2) float32 work px/frame."""
    h, w = field.shape
    start = cv2.resize(model.rotation_px, (w, h), interpolation=cv2.INTER_LINEAR)
    step = cv2.resize(model.translation_px, (w, h), interpolation=cv2.INTER_LINEAR)
    return gap_to_segment(field.velocity_px, start, step, model.depth_bound)


class VelocityRayDetector:
    """Flags velocities no rigid world under the fitted (or known) motion allows.

    State: the previous epipole, tried first in the next frame's fit, and the
    residual summed over the recent frames (for slow movers).

    The observer motion is the field's ``camera`` (fitted once per frame by
    :class:`~motiondetect.detection.detector.MotionDetector` with its
    ``FitConfig``); a field without one is fitted here with the defaults.
    """

    name = NAME
    measurement = "velocity"
    config_type = VelocityRayConfig

    def __init__(self, config: VelocityRayConfig | None = None, egomotion=None) -> None:
        self.config = config or VelocityRayConfig()
        self.egomotion = egomotion
        self._epipole: np.ndarray | None = None
        self._carried: np.ndarray | None = None

    def reset(self) -> None:
        self._epipole = None
        self._carried = None

    def _summed(self, field: VelocityField, fit: CameraFit) -> tuple[np.ndarray, float] | None:
        """The residual summed along the motion (``carry``), as an off-ray
        distance with its tolerance; None until there is a previous sum.

        A pixel continues the sum carried from where it was only where its
        residual continues the sum's mean: the trail a mover leaves starts
        afresh, so the sum does not smear it backwards.
        """
        cfg = self.config
        residual, carried = fit.residual_px, self._carried
        if carried is None or carried.shape != residual.shape:
            self._carried = residual
            return None
        moved = cv2.remap(
            carried, field.source_px, None, cv2.INTER_LINEAR,
            borderMode=cv2.BORDER_CONSTANT, borderValue=0,
        )  # fmt: skip
        gap = cv2.scaleAdd(moved, cfg.carry - 1.0, residual)  # residual - (1 - carry) moved
        continues = (vector_length(gap) < cfg.floor_px).astype(np.float32)
        # Both components at once (4x faster than NumPy's broadcast here).
        kept = cv2.multiply(moved, cv2.merge([continues, continues]))
        total = cv2.scaleAdd(kept, cfg.carry, residual)
        self._carried = total
        distance = off_ray(total, field.pixel_grid, fit.epipole)
        step = _SPREAD_STEP
        spread = residual_spread(distance[step:-step:step, step:-step:step])
        memory = 1.0 / (1.0 - cfg.carry)  # frames a steady sum reaches back
        tolerance = max(self._slow_floor(fit) * memory, cfg.spread_sigmas * spread)
        # What entered the frame during that memory carries flow extrapolated
        # at the edge, so the band reaches as far as the view moved meanwhile.
        band = fit.edge_band_px + fit.median_speed_px * (memory - 1.0)
        distance = discounted_near_edge(distance, field.patch_px, cfg.edge_error_ratio)
        return without_frame_edge(distance, band), tolerance

    def _slow_floor(self, fit: CameraFit) -> float:
        """The summed test's floor for this frame's image speed (the plane's),
        px/frame: from ``slow_still_px`` still to ``slow_px`` at
        ``slow_full_speed_px``."""
        cfg = self.config
        if cfg.slow_full_speed_px <= 0:
            return cfg.slow_px
        share = min(1.0, fit.plane_speed_px / cfg.slow_full_speed_px)
        return cfg.slow_still_px + (cfg.slow_px - cfg.slow_still_px) * share

    def _slow_movers(
        self, field: VelocityField, fit: CameraFit, found: np.ndarray, changed: np.ndarray | None
    ) -> np.ndarray:
        """Movers only the summed residual shows, apart from those ``found``
        in this frame (the sum would only widen them), (h, w) bool."""
        summed = self._summed(field, fit)
        if summed is None:
            return np.zeros_like(found)
        distance, tolerance = summed
        seeds = distance > tolerance
        if changed is not None:
            seeds &= changed
        # A seed's own velocity must be confirmed the other way, as in one
        # frame's test: flow filled in where the view uncovers background
        # behind a near edge is wrong for frames, and adds up in the sum.
        ys, xs = true_pixels(seeds)
        seeds[ys, xs] = field.confirmed_at(ys, xs)
        slow = hysteresis(distance, tolerance, self.config.grow_ratio, seeds)
        if not slow.any():
            return slow
        count, labels = components(slow)
        keep = np.ones(count, bool)
        keep[0] = False
        keep[labels[found]] = False
        return keep.take(labels)

    def _off_ray(
        self, field: VelocityField, fit: CameraFit, known: ObserverMotion | None
    ) -> tuple[np.ndarray, float, np.ndarray | None]:
        """Each pixel's distance off its ray, (h, w) float32; the tolerance;
        and, under known ego-motion, the offsets the distance measures
        (None: the fit's residual, tested across the fitted ray)."""
        cfg = self.config
        if known is None:
            distance = off_ray(
                fit.residual_px, field.pixel_grid, fit.epipole, fit.residual_length()
            )
            return distance, cfg.tolerance(fit.noise_px, fit.spread_px), None
        gap = known_ray_gap(field, known)
        distance = vector_length(gap)
        # What the known motion leaves: DIS's error, the pose's error and
        # the lens's distortion, measured over the frame like the fit's.
        step = _SPREAD_STEP
        spread = residual_spread(distance[step:-step:step, step:-step:step])
        return distance, cfg.tolerance(fit.noise_px, spread, cfg.known_floor_px), gap

    def process(self, field: VelocityField, frame_index: int = 0) -> DetectorOutput:
        """Detect independent motion in one frame's velocity field."""
        cfg = self.config
        fit = field.camera
        if fit is None:
            fit = fit_camera(field, FitConfig(), self._epipole)
            self._epipole = fit.epipole
        known = known_motion(self.egomotion, field, frame_index) if self.egomotion else None
        if not fit.reliable and known is None:
            self._carried = None
            return DetectorOutput.empty(field.shape, camera=fit)
        distance, tolerance, residual = self._off_ray(field, fit, known)
        distance = discounted_near_edge(distance, field.patch_px, cfg.edge_error_ratio)
        distance = without_frame_edge(distance, fit.edge_band_px)
        seeds = distance > tolerance
        changed = None
        if cfg.evidence_sigmas > 0 and fit.plane_difference is not None:
            changed = fit.image_changed(cfg.evidence_sigmas, cfg.evidence_box)
            seeds &= changed
        # The cheap gates first: this one is per pixel.
        epipole = fit.epipole if known is None else None
        seeds = fit.determined_beyond(field, seeds, tolerance, epipole, residual)
        if field.tracked is not None:  # a track's pixels seed from the growth threshold
            held = field.tracked & (distance > cfg.grow_ratio * tolerance)
            seeds |= held if changed is None else held & changed
        mask = hysteresis(distance, tolerance, cfg.grow_ratio, seeds)
        if cfg.carry > 0 and known is None:
            mask |= self._slow_movers(field, fit, mask, changed)
        if cfg.close_px > 1:
            kernel = np.ones((cfg.close_px, cfg.close_px), np.uint8)
            mask = cv2.morphologyEx(mask.astype(np.uint8), cv2.MORPH_CLOSE, kernel) > 0
        strength = np.where(mask, distance / (distance + tolerance), 0.0).astype(np.float32)
        return DetectorOutput.from_mask(
            mask, strength, camera=_with_known(fit, known), observer=known
        )


def _with_known(fit: CameraFit, known: ObserverMotion | None) -> CameraFit:
    """A fit that known ego-motion made reliable keeps its numbers but no reason."""
    if known is None or fit.reliable:
        return fit
    return dataclasses.replace(
        fit, inlier_share=1.0, epipole=None, reason="", median_speed_px=0.0, plane_speed_px=0.0
    )
