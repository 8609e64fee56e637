"""What the detector reports for one frame (:class:`FrameResult`)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import cv2
import numpy as np

from motiondetect.constraint_ray.camera_fit import CameraFit
from motiondetect.constraint_ray.hough import CoarseField
from motiondetect.constraint_ray.observer_motion import ObserverMotion
from motiondetect.detection.base import DetectorOutput
from motiondetect.detection.regions import Region


@dataclass(frozen=True)
class FrameResult:
    """Everything reported for one frame.

    ``mask`` (work pixels) is set on the velocity path, and ``overlay``
    (work pixels) where content fixed to the screen, a burnt-in caption or
    logo, was found and not flagged (:mod:`.screen_fixed`); ``reason`` says why
    a frame could not be judged (then nothing is flagged on it);
    ``held_from`` is set on a frame skipped by ``frame_skip``
    (:meth:`MotionDetector.stream`) or, with ``repeat``, on a frame that
    repeats the one before (:mod:`~motiondetect.measurement.repeats`): the
    index of the judged frame whose result it carries.
    """

    index: int
    time_s: float
    regions: list[Region]
    flagged: np.ndarray  # (64, 64) bool, union of the detectors
    observer: ObserverMotion | None
    coarse: CoarseField | None
    field: object | None
    outputs: dict[str, DetectorOutput] = field(default_factory=dict)
    mask: np.ndarray | None = None
    camera: CameraFit | None = None
    reason: str = ""
    held_from: int | None = None
    overlay: np.ndarray | None = None
    repeat: bool = False

    def held(self, index: int, time_s: float) -> FrameResult:
        """This result carried to a later, skipped frame."""
        return dataclasses.replace(self, index=index, time_s=time_s, held_from=self.index)

    @property
    def moving_fraction(self) -> float:
        return float(self.flagged_pixels.mean())

    @property
    def flagged_pixels(self) -> np.ndarray:
        """What is flagged, (h, w) bool: ``mask`` in work pixels on the
        velocity path, else the (64, 64) ``flagged`` grid."""
        return self.mask if self.mask is not None else self.flagged

    @property
    def score(self) -> float:
        return max((r.score for r in self.regions), default=0.0)

    @property
    def warm_up(self) -> bool:
        return self.field is None

    @property
    def reliable(self) -> bool:
        return not self.reason

    @property
    def view_velocity_px_s(self) -> tuple[float, float] | None:
        """How fast the view moves: the fitted camera motion's image velocity
        (the dominant plane's) at the centre of the picture measured, input
        px per second (x right, y down); None on a frame that could not be
        judged, where no motion was fitted or where the time between the
        frames is not known (the first two frames; velocity path only)."""
        field = self.field
        fit = self.camera
        interval = getattr(field, "interval_s", None)
        if not self.reliable or fit is None or fit.homography is None or not interval:
            return None
        (iw, ih), (ww, wh) = field.geometry.input_size, field.geometry.work_size
        centre = np.array([[[ww / 2, wh / 2]]], np.float64)
        before = cv2.perspectiveTransform(centre, fit.homography)[0, 0]
        dx, dy = (centre[0, 0] - before) / interval
        return float(dx * iw / ww), float(dy * ih / wh)

    def input_mask(self, width: int, height: int) -> np.ndarray:
        """Flagged pixels at input size, (height, width) uint8 0/255."""
        flagged = self.flagged_pixels.astype(np.uint8) * 255
        return cv2.resize(flagged, (width, height), interpolation=cv2.INTER_NEAREST_EXACT)
