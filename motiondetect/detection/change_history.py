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
from motiondetect.detection.regions import components
from motiondetect.measurement.dense_flow import VelocityField
from motiondetect.measurement.image_change import (
    chained_difference,
    chained_seen,
    difference_noise,
    matched_exposure,
)


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
        until that many frames are held. Both are taken where the frame
        that far back saw too: what entered the view since compares with
        nothing (its "change" is its grey level)."""
        if self.frames < 1 or len(self._planes) < self.frames:
            return None
        planes = list(self._planes)
        difference = chained_difference(self._greys[0], planes, self._greys[-1])
        seen = chained_seen(planes, difference.shape)
        noise = difference_noise(difference, seen)
        return (cv2.blur(difference, (box, box)) > sigmas * noise) & seen


def slow_parts(flagged: np.ndarray, speed: np.ndarray, frames: int, px: float) -> np.ndarray:
    """The flagged components whose mean residual ``speed`` (work px/frame)
    carries them no farther than ``px`` over ``frames - 1`` frames, (h, w)
    bool: there the change over ``frames`` frames adds a slow mover's plain
    body; a faster mover would add the trail it left."""
    count, labels = components(flagged)
    inside = labels[flagged]
    sums = np.bincount(inside, weights=speed[flagged], minlength=count)
    sizes = np.bincount(inside, minlength=count)
    mean = sums / np.maximum(sizes, 1)
    slow = mean * (frames - 1) <= px
    slow[0] = False
    return slow.take(labels)


class BackgroundMemory:
    """The background last seen at each place, registered by the fitted planes.

    One frame's change map shows a mover twice: where it is, and where it
    was (the *ghost*: background uncovered since the previous frame). Dense
    flow smears the mover's velocity over that ghost, so it is flagged too,
    a trail on the mover's trailing side. A pixel whose image matches the
    background remembered at that place is background, whatever the
    previous frame showed there: the ghost is taken out, the mover stays.

    The memory, warped into each new frame by that frame's plane (like the
    frames of :class:`ChangeHistory`), learns only where the rigid world
    shows itself: pixels neither flagged nor changed since the previous
    frame. At ``rate`` 1 it holds the last such look at each place; below
    1, a running mean of the looks. A place counts as known after
    ``frames`` such looks; a flagged place keeps what was seen there before
    the mover came. Content that entered the view, and places never seen
    unoccluded, are unknown and never match.

    State: the memory and its per-pixel count of looks, cleared by an
    unreliable frame (its plane is unknown) or a change of size.

    Parameters
    ----------
    rate : float
        Share of each new look blended into the memory, in (0, 1].
    frames : int
        Looks before a place's memory is trusted.
    """

    def __init__(self, rate: float, frames: int) -> None:
        self.rate = rate
        self.frames = frames
        self.reset()

    def reset(self) -> None:
        self._memory: np.ndarray | None = None  # (h, w) float32 grey levels
        self._looks: np.ndarray | None = None  # (h, w) uint8
        self._grey: np.ndarray | None = None

    def differs(self, field: VelocityField, fit: CameraFit, sigmas: float, box: int):
        """Where this frame differs from the remembered background, or the
        background is unknown, (h, w) bool; None while under a tenth of the
        frame is known (too little to measure the difference's noise on).

        The memory is first brought to this frame's exposure
        (:func:`~motiondetect.measurement.image_change.matched_exposure`).
        The ``box``-px mean of ``|grey - memory|`` is compared with
        ``sigmas`` robust sigmas of that difference over the known places.
        Call once per frame, before :meth:`learn`.
        """
        if not fit.reliable or fit.homography is None:
            self.reset()
            return None
        h, w = field.shape
        self._grey = field.grey.astype(np.float32)
        if self._memory is None or self._memory.shape != (h, w):
            self._memory = self._grey.copy()
            self._looks = np.zeros((h, w), np.uint8)
            return None
        inverse = cv2.WARP_INVERSE_MAP  # the plane maps this frame's pixels to the last
        self._memory = cv2.warpPerspective(
            self._memory, fit.homography, (w, h), flags=inverse | cv2.INTER_LINEAR
        )
        self._looks = cv2.warpPerspective(
            self._looks, fit.homography, (w, h), flags=inverse | cv2.INTER_NEAREST
        )  # 0 (unknown) where content entered the view
        known = self._looks >= self.frames
        if known.sum() < known.size // 10:
            return None
        self._memory = matched_exposure(self._memory, self._grey)
        difference = np.minimum(cv2.absdiff(self._memory, self._grey), 255).astype(np.uint8)
        noise = difference_noise(difference, known)
        return (cv2.blur(difference, (box, box)) > sigmas * noise) | ~known

    def learn(self, flagged: np.ndarray, changed: np.ndarray | None) -> None:
        """Blend this frame into the memory where the rigid world shows:
        not within 2 px of a ``flagged`` pixel, nor ``changed``."""
        if self._memory is None or self._grey is None:
            return
        hidden = cv2.dilate(flagged.view(np.uint8), np.ones((5, 5), np.uint8))
        if changed is not None:
            hidden |= changed.view(np.uint8)
        shown = (hidden == 0).view(np.uint8)
        if self.rate < 1.0:  # the looks averaged; a place's first look taken as it is
            blended = cv2.addWeighted(self._memory, 1.0 - self.rate, self._grey, self.rate, 0.0)
            np.copyto(blended, self._grey, where=self._looks == 0)
        else:
            blended = self._grey
        cv2.copyTo(blended, shown, self._memory)  # the warped memory is ours to change
        cv2.add(self._looks, 1, self._looks, shown)  # saturates at 255
        self._grey = None
