"""Content fixed to the screen while the camera moves: captions, logos, the vehicle's parts.

A dashcam's date and clock, a drone's telemetry, a broadcaster's logo or a
stock-footage watermark stay on the same pixels while the view behind them
moves. Where the fitted camera motion moves the scene, such content has a
velocity of zero, so it lies off every constraint ray and is flagged on
every frame, and one event then spans the whole video.
So does whatever the camera is mounted on and sees: a car's bonnet, a
bicycle's handlebars, a drone's landing gear, a train's window frame.

No point of a rigid world seen by a moving camera keeps its image where the
camera's motion changes the image; an overlay does, on every frame. Each
work pixel keeps the grey level it showed when it last changed (its
reference) and a score:

* **+1** on a frame where the pixel still shows its reference (within
  :data:`STILL_SIGMAS`) while the fitted plane would have changed it: either
  the plane difference, ``|I_t - H(I_{t-1})|``, is beyond
  :data:`EVIDENCE_SIGMAS` of the frame's difference noise (high-contrast
  content: a caption's white strokes outlined in black), or the measured
  velocity is zero within :data:`STILL_PX` where the plane moves the scene
  by more than the constraint ray's tolerance (textured content of any
  contrast: a dashboard, a bonnet; on a textured scene in motion the
  difference noise is 7-14 grey levels, more than a dim texture shifted by
  a few pixels changes by); on velocity evidence, **+1 more** for each
  tolerance by which the plane's motion there changed since the last frame
  (up to :data:`CHANGE_PENALTY` more): a jolt of a handheld or vehicle
  camera moves every world point, and a mover the camera follows with it,
  while what is fixed to the camera stays;
* **-**:data:`CHANGE_PENALTY` on a frame where it does not show its
  reference, which then becomes the grey level it shows;
* unchanged otherwise (a still camera, or plain texture that no motion
  would change, is no evidence either way; nor is the band along the frame
  edge where content enters, which the detectors do not test).

The score is kept within ``[0, 2 * frames]``. Pixels whose score has reached
``frames`` are fixed to the screen; their connected groups of at least
:data:`MIN_PIXELS` (text strokes, a logo, not a speck of noise) make the
overlay. The reference is not moved along with small changes, so a mover
that the camera follows drifts or deforms away from it and keeps a low
score; a clock's digit changes once a second and costs only
:data:`CHANGE_PENALTY` of a score that grows by one a frame.

Blind spot: a mover the camera keeps on the same pixels (its velocity
within :data:`STILL_PX` of zero), unchanged in look, for ``frames``
frames of a smoothly moving view is screen-fixed by any measure, and is
taken out as an overlay would be (``tests/test_screen_fixed.py``). The
default, 30 frames (1 s at 30 fps), is long for a camera to follow a mover
to the pixel; docs/detectors.md measures it.
"""

from __future__ import annotations

import cv2
import numpy as np

from motiondetect.constraint_ray.camera_fit import CameraFit
from motiondetect.detection.regions import components, true_pixels, without_frame_edge
from motiondetect.measurement.dense_flow import VelocityField, vector_length

#: Plane difference, in difference-noise sigmas, beyond which the camera's
#: motion predicts a change at a pixel (the same 5 sigmas as the ray's tolerance).
EVIDENCE_SIGMAS = 5.0
#: Distance from the reference, in difference-noise sigmas, within which a
#: pixel still shows it (an overlay's pixels change by sensor noise only).
STILL_SIGMAS = 2.0
#: Speed within which a measured velocity is zero, work px/frame: DIS's
#: error on textured sub-pixel motion (docs/detectors.md). A mover that the
#: camera follows drifts by more on most frames (DAVIS car-roundabout's car:
#: a median of 0.3-1.5 px/frame).
STILL_PX = 0.1
#: Score lost on a frame where a pixel changes.
CHANGE_PENALTY = 5
#: Smallest group of fixed pixels that counts as an overlay, work px.
MIN_PIXELS = 10


class ScreenFixed:
    """Finds content fixed to the screen over the frames (:meth:`update`).

    State: each work pixel's reference grey level and score, kept across
    unreliable frames (an overlay outlasts a cut) and cleared by a change
    of size.

    Parameters
    ----------
    frames : int
        Frames of evidence that make a pixel fixed (0: off).
    """

    def __init__(self, frames: int) -> None:
        self.frames = frames
        self.reset()

    def reset(self) -> None:
        self._last_residual: np.ndarray | None = None  # (h, w, 2): the last judged frame's
        self._reference: np.ndarray | None = None  # (h, w) uint8
        self._score: np.ndarray | None = None  # (h, w) int32: any ``frames`` fits
        self._fixed: np.ndarray | None = None  # (h, w) bool: what _overlay was made of
        self._overlay: np.ndarray | None = None  # remade only when _fixed changes

    def update(
        self, field: VelocityField, fit: CameraFit, tolerance_px: float
    ) -> np.ndarray | None:
        """Score this frame and return the overlay, (h, w) bool work pixels;
        None while nothing is fixed (or when off). ``tolerance_px``: the
        constraint ray's tolerance on this frame, work px/frame."""
        if self.frames <= 0:
            return None
        grey = field.grey
        if self._reference is None or self._reference.shape != grey.shape:
            self._reference = field.previous_grey.copy()
            self._score = np.zeros(grey.shape, np.int32)
            self._fixed = self._overlay = self._last_residual = None
        residual = fit.residual_px
        if not fit.reliable or fit.plane_difference is None or residual is None:
            self._last_residual = None  # the next plane is compared with none
            return self._overlay
        sigma = fit.difference_sigma()
        changed = cv2.absdiff(grey, self._reference) > STILL_SIGMAS * sigma
        # Where |v| <= STILL_PX the plane's velocity, v - r, is within
        # STILL_PX of -r, so the shared residual length bounds its speed.
        still = vector_length(field.velocity_px) <= STILL_PX
        still &= fit.residual_length() > tolerance_px + STILL_PX
        evidence = (fit.plane_difference > EVIDENCE_SIGMAS * sigma) | still
        evidence &= ~changed
        # Where content enters, the plane difference compares with nothing
        # seen; the detectors do not test there either.
        evidence = without_frame_edge(evidence, fit.edge_band_px)
        score = self._score  # whole-array arithmetic: masks would cost 20x more
        score += evidence.view(np.uint8)
        if self._last_residual is not None:
            # At a still pixel the change of -r is the change of the plane's
            # velocity. Such pixels are few but where something is fixed.
            ys, xs = true_pixels(evidence & still)
            change = residual[ys, xs] - self._last_residual[ys, xs]
            jolt = vector_length(change) / tolerance_px
            score[ys, xs] += np.minimum(jolt, CHANGE_PENALTY).astype(np.int32)
        self._last_residual = residual
        score -= changed.view(np.uint8) * np.uint8(CHANGE_PENALTY)
        np.clip(score, 0, 2 * self.frames, out=score)
        np.copyto(self._reference, grey, where=changed)
        fixed = score >= self.frames
        if self._fixed is None or not np.array_equal(fixed, self._fixed):
            self._fixed, self._overlay = fixed, _groups(fixed)  # else unchanged: kept
        return self._overlay


def _groups(fixed: np.ndarray) -> np.ndarray | None:
    """The connected groups of ``fixed`` pixels of at least :data:`MIN_PIXELS`,
    (h, w) bool; None when there are none."""
    if not fixed.any():
        return None
    count, labels = components(fixed)
    sizes = np.bincount(labels.ravel(), minlength=count)
    keep = sizes >= MIN_PIXELS
    keep[0] = False
    return keep.take(labels) if keep.any() else None


def without_overlay(flagged: np.ndarray, overlay: np.ndarray, radius_px: int) -> np.ndarray:
    """``flagged`` with the overlay's flags taken out, (h, w) bool, a new array.

    The flow within ``radius_px`` of an overlay mixes its zero velocity
    with the scene's (DIS's patches straddle it), so that band is cleared;
    and a flagged group whose part outside the band is no larger than its
    flagged part of the band within ``radius_px`` of that part is the
    overlay's too (its fringe, grown up to about ``radius_px`` beyond the
    band where the mixed flow spread further), so it goes whole. The test
    is local: a large overlay (a bonnet) flags a band far longer than a
    mover touching it, and a group mostly in the band as a whole would take
    the mover with it. A mover crossing the band keeps what lies outside it.
    """
    size = 2 * radius_px + 1
    band = cv2.dilate(overlay.view(np.uint8), np.ones((size, size), np.uint8)) > 0
    # The overlay's own pixels belong to no group (label 0): through a large
    # one (a bonnet) every mover touching it would be one group.
    count, labels = components(flagged & ~overlay)
    outside = flagged & ~band
    near = cv2.dilate(outside.view(np.uint8), np.ones((size, size), np.uint8)) > 0
    inside = np.bincount(labels[band & near], minlength=count)
    drop = inside >= np.bincount(labels[outside], minlength=count)
    drop[0] = True  # the background stays unflagged
    return ~drop.take(labels) & ~band
