"""Where the image changed over the last few frames once the camera's motion is undone.

One frame's plane difference
(:func:`~motiondetect.measurement.image_change.plane_difference`) shows a
mover only where it moved far enough, against the local texture, to change
the image in one frame. A slow mover (a grazing cow, a pedestrian far away)
moves a fraction of a pixel per frame: its plain body changes the image by
less than the noise, and only its fastest part shows. Over ``k`` frames it
moves ``k`` times as far, while the rigid world, registered by the chain of
the fitted planes' homographies, still does not change. This module keeps
the last ``k`` working frames and homographies (a few small images: memory
stays flat in video length) and gives that longer-baseline change map.
"""

from __future__ import annotations

import collections

import cv2
import numpy as np

from motiondetect.constraint_ray.camera_fit import CameraFit
from motiondetect.measurement.dense_flow import VelocityField
from motiondetect.measurement.image_change import chained_difference, difference_noise


class ChangeHistory:
    """The last ``frames + 1`` working frames and ``frames`` planes, for :meth:`changed`.

    State: the frames and planes, cleared by an unreliable frame (its plane
    is unknown) or a change of size.
    """

    def __init__(self, frames: int) -> None:
        self.frames = frames
        self._greys: collections.deque = collections.deque(maxlen=frames + 1)
        self._planes: collections.deque = collections.deque(maxlen=frames)

    def reset(self) -> None:
        self._greys.clear()
        self._planes.clear()

    def update(self, field: VelocityField, fit: CameraFit) -> None:
        """Add this frame (after its plane is fitted)."""
        if not fit.reliable or (self._greys and self._greys[-1].shape != field.shape):
            self.reset()
            if not fit.reliable:
                return
        if not self._greys:
            self._greys.append(field.previous_grey)
        self._greys.append(field.grey)
        self._planes.append(fit.homography)

    def changed(self, sigmas: float, box: int) -> np.ndarray | None:
        """Where the ``box``-px mean of the change since ``frames`` frames ago
        exceeds ``sigmas`` robust sigmas of that change, (h, w) bool; None
        until that many frames are held."""
        if self.frames < 1 or len(self._planes) < self.frames:
            return None
        difference = chained_difference(self._greys[0], list(self._planes), self._greys[-1])
        return cv2.blur(difference, (box, box)) > sigmas * difference_noise(difference)
