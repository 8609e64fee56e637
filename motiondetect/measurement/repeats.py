"""Frames that repeat the one before: frame-rate conversion, dropped capture.

A 24 fps film converted to 30 fps shows every 4th frame twice; a screen
recording, a webcam or a phone in low light repeats a frame whenever capture
falls behind. A repeated frame holds no motion at all, so measured as a frame
of its own it flags nothing (the movers seem to stop) and the animate test
then sees every mover start again. It carries no new information: the
detector holds the last frame's result for it and measures the next frame
against the last one that differed (:class:`RepeatedFrames`).

A frame repeats the last when its mean absolute difference from it, in grey
levels at working size, is at most ``level`` *and* at most a quarter of the
usual difference between frames (the 75th percentile of the last 9). H.264
re-encodes a repeated frame with a little noise: 0.0-0.6 grey levels at CRF
18-32 on DAVIS clips, against 4-20 between the frames of a moving camera and
1-6 of sensor noise between the frames of a still one. The second condition
keeps a clean, still view (whose frames all differ by less than ``level``)
from being taken for repeats.
"""

from __future__ import annotations

import collections

import cv2
import numpy as np

#: The usual difference between frames is taken over this many frames.
HISTORY = 9
#: A repeat differs by at most this share of the usual difference.
DROP_SHARE = 0.25


class Repeat:
    """What a measurement gives for a frame that repeats the last one."""

    def __repr__(self) -> str:
        return "REPEAT"


#: The one :class:`Repeat`.
REPEAT = Repeat()


def mean_difference(grey: np.ndarray, previous: np.ndarray) -> float:
    """Mean absolute difference of two (h, w) uint8 images, grey levels."""
    return cv2.norm(grey, previous, cv2.NORM_L1) / grey.size


class RepeatedFrames:
    """Tells a frame that repeats the last one (:meth:`repeats`).

    Parameters
    ----------
    level : float
        Mean absolute difference, grey levels at working size, at or below
        which a frame may repeat the last (0: no frame does).
    """

    def __init__(self, level: float) -> None:
        self.level = level
        self._differences: collections.deque = collections.deque(maxlen=HISTORY)

    def reset(self) -> None:
        self._differences.clear()

    def repeats(self, grey: np.ndarray, previous: np.ndarray) -> bool:
        """Whether ``grey`` repeats ``previous`` (both (h, w) uint8)."""
        if self.level <= 0:
            return False
        difference = mean_difference(grey, previous)
        usual = np.percentile(self._differences, 75) if len(self._differences) >= 2 else None
        self._differences.append(difference)
        return usual is not None and difference <= min(self.level, DROP_SHARE * usual)
