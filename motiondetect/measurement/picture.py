"""The picture inside black bars: letterboxed and pillarboxed video.

A film in a 16:9 frame, or a 4:3 or upright phone clip posted at 16:9,
arrives with black bars. The bars are not the scene: content enters the
view at the *picture's* edge, where the flow is undetermined, and the bars
take working pixels from the picture. So the velocity path measures only
the picture (:class:`PictureArea`), and the detector places its results
back in the whole frame (:mod:`motiondetect.detection.framing`).

A bar is a band along a frame edge in which no pixel has ever been brighter
than ``limit`` grey levels (FFmpeg's ``cropdetect`` uses the same limit,
24 of 255), beyond the codec's bleed next to the picture; bars come in
pairs of one thickness, the picture centred between them. The picture only
grows: once content shows in a bar, the picture takes in this frame's
content (bars that are no longer a centred pair go), and after two such
openings the whole frame is the picture.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from motiondetect.measurement.stages import MIN_FRAME_SIDE

#: Darkest grey level that counts as picture, of 255 (FFmpeg cropdetect's default).
BAR_LIMIT = 24
#: A dark band thinner than this share of its side is not a bar.
MIN_BAR_SHARE = 0.01
#: Times the picture may grow into lit bars before the whole frame is taken
#: (each starts the measurement afresh).
MAX_OPENINGS = 2
#: Input px of a bar next to the picture where brighter pixels do not count:
#: a codec's blocks (8-16 px) ring, and its half-resolution colour bleeds,
#: across the picture's edge into the bar.
BLEED_PX = 16


@dataclass(frozen=True)
class Picture:
    """Where the picture lies in a frame.

    Attributes
    ----------
    box : (x, y, width, height)
        Input pixels.
    frame_size : (width, height)
        The whole frame, input pixels.
    """

    box: tuple[int, int, int, int]
    frame_size: tuple[int, int]

    def crop(self, frame: np.ndarray) -> np.ndarray:
        """The picture's pixels of ``frame`` (a view, not a copy)."""
        x, y, w, h = self.box
        return frame[y : y + h, x : x + w]


def content_bounds(frame: np.ndarray, limit: int = BAR_LIMIT) -> tuple[int, int, int, int] | None:
    """The smallest box holding every pixel brighter than ``limit``.

    Parameters
    ----------
    frame : (H, W) or (H, W, C) ndarray of uint8 or uint16
    limit : int
        Grey levels of 255 (scaled by 257 for uint16 frames).

    Returns
    -------
    (x0, y0, x1, y1) or None
        Input pixels, end exclusive; None when the frame is dark throughout.
    """
    level = _level(frame, limit)
    h, w = frame.shape[:2]
    flat = np.ascontiguousarray(frame).reshape(h, -1)  # channels side by side in each row
    rows = np.flatnonzero(flat.max(axis=1) > level)
    if rows.size == 0:
        return None
    cols = np.flatnonzero(flat.max(axis=0).reshape(w, -1).max(axis=1) > level)
    return int(cols[0]), int(rows[0]), int(cols[-1]) + 1, int(rows[-1]) + 1


def _level(frame: np.ndarray, limit: int) -> int:
    return limit * 257 if frame.dtype == np.uint16 else limit


class PictureArea:
    """The picture inside a video's black bars, frame after frame.

    ``update`` returns None while every frame so far is dark or has no bar
    (the whole frame is measured), else the :class:`Picture`. Once a frame
    without bars is seen no frame is inspected again; with bars, only the
    bars are (a thin slice of the frame).
    """

    def __init__(self, limit: int = BAR_LIMIT) -> None:
        self.limit = limit
        self.reset()

    def reset(self) -> None:
        self._bounds: tuple[int, int, int, int] | None = None  # x0, y0, x1, y1
        self._whole = False
        self._size: tuple[int, int] | None = None
        self._openings = 0

    def update(self, frame: np.ndarray) -> Picture | None:
        h, w = frame.shape[:2]
        if self._size != (w, h):  # another input
            self.reset()
            self._size = (w, h)
        if self._whole:
            return None
        if self._bounds is None:
            found = content_bounds(frame, self.limit)
            if found is None:
                return None
            self._bounds = _bars_kept(found, w, h)
        else:
            self._bounds = self._lit_bars_opened(frame)
        x0, y0, x1, y1 = self._bounds
        if (x0, y0, x1, y1) == (0, 0, w, h) or min(x1 - x0, y1 - y0) < MIN_FRAME_SIDE:
            self._whole = True
            return None
        return Picture((x0, y0, x1 - x0, y1 - y0), (w, h))

    def _lit_bars_opened(self, frame: np.ndarray) -> tuple[int, int, int, int]:
        """The bounds, grown to this frame's content when content shows in a
        bar (beyond the bleed next to the picture): a title on black gives
        way to a letterboxed film. After :data:`MAX_OPENINGS` the whole
        frame is the picture."""
        h, w = frame.shape[:2]
        x0, y0, x1, y1 = self._bounds
        level, m = _level(frame, self.limit), BLEED_PX
        bars = (
            frame[: max(y0 - m, 0)],
            frame[y1 + m :],
            frame[:, : max(x0 - m, 0)],
            frame[:, x1 + m :],
        )
        if not any(bar.size and bar.max() > level for bar in bars):
            return self._bounds
        self._openings += 1
        if self._openings > MAX_OPENINGS:
            return 0, 0, w, h
        fx0, fy0, fx1, fy1 = content_bounds(frame, self.limit)  # a bar is lit: not None
        return _bars_kept((min(x0, fx0), min(y0, fy0), max(x1, fx1), max(y1, fy1)), w, h)


def _bars_kept(bounds, width: int, height: int) -> tuple[int, int, int, int]:
    """``bounds`` with the dark bands that are no bars given to the picture.

    Bars come in pairs of one thickness, the picture centred between them
    (top and bottom, or left and right, within :data:`BLEED_PX`), each at
    least ``MIN_BAR_SHARE`` of its side: a night sky above a lit road, or an
    encoder's dark edge column, is no bar.
    """
    x0, y0, x1, y1 = bounds
    x0, x1 = _pair(x0, width - x1, width)
    y0, y1 = _pair(y0, height - y1, height)
    return x0, y0, width - x1, height - y1


def _pair(before: int, after: int, side: int) -> tuple[int, int]:
    """Two dark bands' thicknesses kept as bars, or both 0."""
    if min(before, after) < MIN_BAR_SHARE * side or abs(before - after) > BLEED_PX:
        return 0, 0
    return before, after
