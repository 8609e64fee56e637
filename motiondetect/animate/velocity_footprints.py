"""Detector 2 on the full velocity: animate motion (section 4).

The paper's footprint of a measurement is where similar motion may appear
next: the point moved by its velocity, widened by the speed change a
smooth (rigid, inertial) world allows (Figure 8). With the 2-D velocity
the footprint need not be drawn: each current pixel ``q`` names where it
came from, ``q - v(q)``, so the *prediction* is the velocity the previous
frame had there, and the test is whether the new velocity is within the
smooth-change allowance of it.

The paper compensates the observer's own change of motion: a camera's
rotational jitter changes every velocity at once. The prediction is the
previous velocity carried on by that change, one homography fitted to how
the sampled points moved on (:mod:`.continuation`); the test compares it
with the velocity now, both less this frame's plane velocity (so that the
allowance grows with the speed off the plane, not with the pan's).

When the frames' times are known and the two intervals differ (frames
dropped, a phone's variable frame rate), the previous velocity is scaled by
their ratio first (:func:`interval_ratio`): a smooth motion covers ground
in proportion to the time.

Only points whose current velocity is itself off the plane are tested.
Background uncovered at a mover's trailing edge "comes from" where the
mover was, so without this it would be flagged at every edge; the price
is that a mover that stops dead is not flagged by this detector on the
frame it stops (the constraint ray filter still sees any motion it has).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import cv2
import numpy as np

from motiondetect.animate.continuation import continued_velocity, sample_at
from motiondetect.config_checks import check_fields
from motiondetect.constraint_ray.camera_fit import fit_camera
from motiondetect.constraint_ray.fit_config import FitConfig
from motiondetect.detection.base import DetectorOutput
from motiondetect.detection.regions import (
    components_with_stats,
    hysteresis,
    true_pixels,
    without_frame_edge,
)
from motiondetect.measurement.dense_flow import VelocityField

NAME = "velocity-animate"
_SQUARE3 = np.ones((3, 3), np.uint8)
#: Largest ratio of two frames' intervals the continuation is scaled by.
MAX_INTERVAL_RATIO = 4.0


@dataclass(frozen=True)
class VelocityAnimateConfig:
    """Settings of the animate-motion detector on the 2-D velocity.

    Attributes
    ----------
    noise_sigmas : float
        Measurement tolerance in robust noise sigmas of the frame's residual.
    floor_px : float
        Smallest measurement tolerance, work px/frame.
    accel_px : float
        Speed change per frame a smooth world allows, work px/frame.
    accel_relative : float
        Further allowance proportional to the previous speed.
    spread_px : float
        The footprint reaches this far around the predicted point, work px
        (the dense flow's patch smooths motion boundaries by about as much).
    open_px : int
        Morphological opening of the violations, work px. Dense flow is
        smoothed over its patch, so a thin band of background beside every
        mover borrows the mover's velocity and "came from" background; the
        opening removes that band, while a reversing mover violates whole.
    memory_frames : int
        An object that broke its motion stays animate this many frames: the
        label is carried with the object, moved by its velocity, so a limb
        reversing every few frames is flagged between reversals too. A
        frame that cannot be judged (a cut, motion beyond the band) clears
        it: the motion that would carry it is unknown there.
    evidence_sigmas : float
        A violation must also show a grey-level change after the plane warp:
        its ``evidence_box`` mean above this many robust sigmas of the
        frame's changes (0: off), the constraint ray's seed rule. A flow
        that jumps where the image did not change (blank surfaces, an
        occluding edge DIS misplaces) is the measurement's error, not an
        animal's.
    evidence_box : int
        Side of the box the change is averaged over, work px.
    coherence : float
        An animate label grows only over the moving pixels connected to it
        whose residual velocity lies within ``max(tolerance, coherence *
        speed)`` of the labelled part's mean residual velocity: over the
        object that broke its motion, not over every off-plane pixel it
        touches. At 1, a pixel moves with the part when its velocity is
        nearer the part's than the part's is to the plane's. With parallax,
        a whole near surface is off the plane; when the camera's translation
        changes, a few of its points violate, and growing over all of it
        flagged most of the frame (the fox clip: 0.42 false alarms a frame
        against 0.31). 0: over every connected moving pixel
        (docs/detectors.md).
    change_px : float
        RANSAC's threshold for the camera's change of motion between two
        frames (:mod:`.continuation`), work px: 1, as the plane's (``[fit]
        ransac_px``); the points that broke their motion lie beyond it.
    """

    noise_sigmas: float = 3.0
    floor_px: float = 1.0
    accel_px: float = 0.75
    accel_relative: float = 0.1
    open_px: int = 5
    spread_px: float = 6.0
    memory_frames: int = 8
    evidence_sigmas: float = 3.0
    evidence_box: int = 5
    coherence: float = 1.0
    change_px: float = 1.0

    def __post_init__(self) -> None:
        check_fields(
            self,
            positive=("noise_sigmas", "floor_px", "evidence_box", "change_px"),
            non_negative=(
                "accel_px", "accel_relative", "open_px", "spread_px", "memory_frames",
                "evidence_sigmas", "coherence",
            ),
        )  # fmt: skip


#: Violations are tested on every other pixel each way and spread to the
#: pixels between: the opening that follows removes anything thinner anyway.
_TEST_STEP = 2
_FOOTPRINT = np.float32([(0, 0), (1, 0), (-1, 0), (0, 1), (0, -1)])


def footprint_excess(
    continued: np.ndarray,
    source: np.ndarray,
    residual: np.ndarray,
    plane: np.ndarray,
    tolerance: float,
    config: VelocityAnimateConfig,
) -> np.ndarray:
    """How far each point's velocity change exceeds what a smooth world allows.

    Parameters
    ----------
    continued : (h, w, 2) ndarray of float32
        The velocity each previous-frame point has now if it moved on
        smoothly (:func:`~.continuation.continued_velocity`).
    source : (N, 2) ndarray of float32
        Where each point was in the previous frame, work px.
    residual : (N, 2) ndarray of float32
        Each point's residual velocity now.
    plane : (N, 2) ndarray of float32
        The plane's velocity at each point now, taken off the prediction.

    Returns
    -------
    (N,) ndarray of float32, px/frame
        The smallest excess over the footprint (the predicted point and its
        four neighbours ``spread_px`` away): positive where the velocity
        continues none of them; 0 for points that came from outside.
    """
    best = None
    for step in _FOOTPRINT:
        predicted = sample_at(continued, source + config.spread_px * step) - plane
        change = np.hypot(*(residual - predicted).T)
        allowance = tolerance + config.accel_px + config.accel_relative * np.hypot(*predicted.T)
        excess = np.nan_to_num(change - allowance, nan=0.0)
        best = excess if best is None else np.minimum(best, excess)
    return best


def coherent_growth(
    seeds: np.ndarray, residual: np.ndarray, speed: np.ndarray, tolerance: float,
    relative: float,
) -> np.ndarray:  # fmt: skip
    """The moving pixels that move with each part of ``seeds``, (h, w) bool.

    Parameters
    ----------
    seeds : (h, w) ndarray of bool
        The animate labels.
    residual : (h, w, 2) ndarray of float32
        Residual velocity, work px/frame.
    speed : (h, w) ndarray of float32
        Its length; pixels faster than ``tolerance`` are moving.
    tolerance : float
        Measurement tolerance, work px/frame.
    relative : float
        Share of a part's speed its pixels' velocities may differ by.

    Returns
    -------
    (h, w) ndarray of bool
        The moving seeds, grown over the connected moving pixels whose
        velocity lies within ``max(tolerance, relative * |v|)`` of the mean
        velocity ``v`` of the 8-connected seed part nearest to them.
    """
    moving = speed > tolerance
    seeds = seeds & moving
    out = np.zeros(seeds.shape, bool)
    if not seeds.any():
        return out
    # Only the moving regions that hold a seed can grow: work in their box.
    _, regions, boxes = components_with_stats(moving)
    held = np.unique(regions[seeds])
    x0, y0 = boxes[held, 0].min(), boxes[held, 1].min()
    x1 = (boxes[held, 0] + boxes[held, 2]).max()
    y1 = (boxes[held, 1] + boxes[held, 3]).max()
    box = np.s_[y0:y1, x0:x1]
    keep = np.zeros(len(boxes), bool)
    keep[held] = True
    out[box] = _grown(seeds[box], residual[box], keep[regions[box]], tolerance, relative)
    return out


def _grown(
    seeds: np.ndarray, residual: np.ndarray, moving: np.ndarray, tolerance: float,
    relative: float,
) -> np.ndarray:  # fmt: skip
    """:func:`coherent_growth` within the box of the moving regions."""
    count, parts = cv2.connectedComponents(seeds.view(np.uint8), connectivity=8)
    ids = parts[seeds]  # the part of each seed pixel, in scan order
    sizes = np.bincount(ids, minlength=count).clip(1)
    at_seeds = residual[seeds]
    v = np.stack([np.bincount(ids, at_seeds[:, k], count) / sizes for k in (0, 1)], 1)
    reach = np.maximum(tolerance, relative * np.hypot(v[:, 0], v[:, 1]))
    part = 1  # one part: every pixel against it
    if count > 2:  # each pixel against the part nearest to it, in one pass
        _, nearest = cv2.distanceTransformWithLabels(
            (~seeds).view(np.uint8), cv2.DIST_L2, 3, labelType=cv2.DIST_LABEL_PIXEL
        )
        part = ids[nearest - 1]
    dx, dy = residual[..., 0] - v[part, 0], residual[..., 1] - v[part, 1]
    grown = (moving & (dx * dx + dy * dy < (reach * reach)[part])) | seeds
    _, pieces = cv2.connectedComponents(grown.view(np.uint8), connectivity=8)
    touched = np.unique(pieces[seeds])
    return np.isin(pieces, touched[touched > 0])


def interval_ratio(now_s: float, before_s: float) -> float:
    """How much longer this frame's interval is than the last one's: a
    velocity that continues smoothly covers that much more ground (frames
    dropped, a phone's variable frame rate). Kept within
    :data:`MAX_INTERVAL_RATIO` either way, against timestamps that jump."""
    return float(np.clip(now_s / before_s, 1 / MAX_INTERVAL_RATIO, MAX_INTERVAL_RATIO))


def violations(
    field: VelocityField, residual: np.ndarray, candidates: np.ndarray, continued: np.ndarray,
    tolerance: float, config: VelocityAnimateConfig,
    moving_at: Callable[[np.ndarray, np.ndarray], np.ndarray] | None = None,
) -> np.ndarray:  # fmt: skip
    """Where the velocity broke its smooth continuation, (h, w) bool.

    Only the moving ``candidates`` are tested: those ``moving_at(ys, xs)``
    accepts (the points whose residual the image determines exceeds
    ``tolerance``, ``CameraFit.determined_beyond_at``; None: all); see the
    module doc. It is asked only where its answer is used: at the tested
    points, and at the candidates beside a violation.
    """
    h, w = candidates.shape
    s = _TEST_STEP
    ys, xs = true_pixels(candidates[::s, ::s])
    coarse = np.zeros(((h + s - 1) // s, (w + s - 1) // s), np.uint8)
    if len(ys):
        ys, xs = ys * s, xs * s
        if moving_at is not None:
            moving = moving_at(ys, xs)
            ys, xs = ys[moving], xs[moving]
    if len(ys):
        source = field.source_px[ys, xs]
        now = residual[ys, xs]
        plane = field.velocity_px[ys, xs] - now
        excess = footprint_excess(continued, source, now, plane, tolerance, config)
        coarse[ys // s, xs // s] = excess > 0
    mask = np.repeat(np.repeat(coarse, s, axis=0), s, axis=1)[:h, :w] & candidates
    if moving_at is not None:
        ys, xs = true_pixels(mask)
        mask[ys, xs] = moving_at(ys, xs)
    kernel = np.ones((config.open_px, config.open_px), np.uint8) if config.open_px > 1 else _SQUARE3
    return cv2.morphologyEx(mask, cv2.MORPH_OPEN, kernel) > 0


class VelocityAnimateDetector:
    """Flags velocities that break the smooth continuation of the previous frame's.

    State: the previous frame's velocity field (None after a frame that
    could not be judged) and the animate memory (frames left, per pixel).

    The observer motion is the field's ``camera`` (fitted once per frame by
    :class:`~motiondetect.detection.detector.MotionDetector` with its
    ``FitConfig``); a field without one is fitted here with the defaults.
    """

    name = NAME
    measurement = "velocity"
    config_type = VelocityAnimateConfig

    def __init__(self, config: VelocityAnimateConfig | None = None, egomotion=None) -> None:
        self.config = config or VelocityAnimateConfig()
        self._previous: np.ndarray | None = None
        self._memory: np.ndarray | None = None
        self._interval: float | None = None

    def reset(self) -> None:
        self._previous, self._memory, self._interval = None, None, None

    def _remember(self, violation: np.ndarray, field: VelocityField) -> np.ndarray:
        """Frames left of each pixel's animate label, carried along the motion."""
        memory = np.where(violation, self.config.memory_frames, 0).astype(np.float32)
        if self._memory is not None and self._memory.shape == violation.shape:
            carried = cv2.remap(
                self._memory, field.source_px, None, cv2.INTER_NEAREST,
                borderMode=cv2.BORDER_CONSTANT, borderValue=0,
            )  # fmt: skip
            memory = np.maximum(memory, carried - 1)
        self._memory = memory
        return memory > 0

    def process(self, field: VelocityField, frame_index: int = 0) -> DetectorOutput:
        cfg = self.config
        fit = field.camera if field.camera is not None else fit_camera(field, FitConfig())
        # An unjudged frame (a cut) predicts nothing, as it has no residual.
        now = field.velocity_px if fit.residual_px is not None else None
        previous, self._previous = self._previous, now
        interval, self._interval = self._interval, field.interval_s
        ratio = 1.0
        if previous is not None and interval and field.interval_s:
            ratio = interval_ratio(field.interval_s, interval)
        if not fit.reliable:
            # The labels are carried along each frame's motion; a frame that
            # cannot be judged breaks that chain (as the ray filter's sum).
            self._memory = None
        if not fit.reliable or previous is None or previous.shape != field.velocity_px.shape:
            return DetectorOutput.empty(field.shape, camera=fit)
        tolerance = max(cfg.floor_px, cfg.noise_sigmas * fit.noise_px)
        speed = fit.residual_length()

        # Only points whose motion off the plane the image determines are tested.
        def moving_at(ys: np.ndarray, xs: np.ndarray) -> np.ndarray:
            return fit.determined_beyond_at(field, ys, xs, tolerance)

        candidates = speed > tolerance
        continued = continued_velocity(
            previous, field.pixel_grid, field.source_px, ratio, cfg.change_px
        )
        violation = violations(
            field, fit.residual_px, candidates, continued, tolerance, cfg, moving_at
        )
        # The test reads two flow fields (this one and, where each point came
        # from, the previous one), each extrapolated along the frame edge.
        violation = without_frame_edge(violation, 2 * fit.edge_band_px)
        if cfg.evidence_sigmas > 0 and fit.plane_difference is not None:
            violation &= fit.image_changed(cfg.evidence_sigmas, cfg.evidence_box)
        animate = self._remember(violation, field)
        # What entered the view has extrapolated flow: nothing to grow over.
        grown = speed if fit.seen is None else np.where(fit.seen, speed, 0)
        if cfg.coherence > 0:
            mask = coherent_growth(animate, fit.residual_px, grown, tolerance, cfg.coherence)
        else:
            mask = hysteresis(grown, tolerance, 1.0, seeds=animate)
        strength = np.where(mask, speed / (speed + tolerance), 0.0).astype(np.float32)
        return DetectorOutput.from_mask(
            mask, strength, camera=fit, extra={"violations": int(violation.sum())}
        )
