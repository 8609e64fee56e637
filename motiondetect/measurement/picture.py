"""The picture inside black bars: letterboxed and pillarboxed video.

A film in a 16:9 frame, or a 4:3 or upright phone clip posted at 16:9,
arrives with black bars. The bars are not the scene: content enters the
view at the *picture's* edge, where the flow is undetermined, and the bars
take working pixels from the picture. So the velocity path measures only
the picture (:class:`PictureArea`), and the detector places its results
back in the whole frame (:mod:`motiondetect.detection.framing`).

A bar is a band along a frame edge in which no pixel has ever been brighter
than ``limit`` grey levels (FFmpeg's ``cropdetect`` uses the same limit,
24 of 255), or which shows no detail (the blurred, enlarged copy of the
video that social media put beside an upright phone clip), beyond the
codec's bleed next to the picture; bars come in pairs of one thickness, the
picture centred between them. The picture only grows: once detail shows in
a bar, the picture takes in this frame's content (bars that are no longer a
centred pair go), and after two such openings the whole frame is the
picture.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from motiondetect.measurement.stages import MIN_FRAME_SIDE

#: Darkest grey level that counts as picture, of 255 (FFmpeg cropdetect's default).
BAR_LIMIT = 24
#: A dark band thinner than this share of its side is not a bar.
MIN_BAR_SHARE = 0.01
#: Times the picture may grow into lit bars before the whole frame is taken
#: (each starts the measurement afresh).
MAX_OPENINGS = 2
#: Input px of a bar next to the picture where content does not count:
#: a codec's blocks (8-16 px) ring, and its half-resolution colour bleeds,
#: across the picture's edge into the bar.
BLEED_PX = 16
#: Detail is measured on the frame reduced to this long side, px.
DETAIL_SIDE = 480
#: A column or row shows no detail when its mean absolute difference between
#: neighbouring pixels is below this share of the frame's 90th-percentile
#: column. Measured on the shared clips: the most detailed column or row of
#: each 5 % band along a frame edge reaches 0.22-1.1 of it; social media's
#: blurred panels (``benchmarks/degrade.py --blurred-sides``), 0.01-0.09.
FLAT_SHARE = 0.1
#: A bar lights up (it shows content) when a column or row of it reaches this
#: share of the picture's detail: twice the bar's own limit, so that a
#: blurred panel near that limit stays a bar.
LIT_SHARE = 2 * FLAT_SHARE
#: A frame whose picture has less detail than this (its 90th-percentile
#: column, grey levels) says nothing of its bars: a fade, a cut to black.
MIN_DETAIL = 1.0


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


def detail_profiles(frame: np.ndarray, scale: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Each column's and row's detail: the mean absolute difference between
    neighbouring pixels (across and along), grey levels, on the frame
    reduced to :data:`DETAIL_SIDE` (or by ``scale``, for part of a frame).

    Returns
    -------
    cols : (W,) ndarray of float32
    rows : (H,) ndarray of float32
        Per input column and row.
    """
    h, w = frame.shape[:2]
    scale = min(1.0, DETAIL_SIDE / max(h, w))
    size = (max(2, round(w * scale)), max(2, round(h * scale)))
    small = cv2.resize(frame, size, interpolation=cv2.INTER_LINEAR)  # sampled: 0.3 ms at 1080p
    if small.ndim == 3:
        small = cv2.cvtColor(small, cv2.COLOR_BGR2GRAY)
    small = small.astype(np.float32)
    detail = np.zeros_like(small)
    detail[:, 1:] += np.abs(np.diff(small, axis=1))
    detail[1:, :] += np.abs(np.diff(small, axis=0))
    return _to_input(detail.mean(axis=0), w), _to_input(detail.mean(axis=1), h)


def _to_input(profile: np.ndarray, length: int) -> np.ndarray:
    """A profile of the reduced frame, one value per input column (or row)."""
    index = np.minimum(np.arange(length) * len(profile) // length, len(profile) - 1)
    return profile[index].astype(np.float32)


def _level(frame: np.ndarray, limit: int) -> int:
    return limit * 257 if frame.dtype == np.uint16 else limit


class PictureArea:
    """The picture inside a video's black bars, frame after frame.

    ``update`` returns None while every frame so far is dark or has no bar
    (the whole frame is measured), else the :class:`Picture`. Once a frame
    without bars is seen no frame is inspected again; with bars, each frame
    is, sampled to :data:`DETAIL_SIDE`.
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
            found = self._content(frame)
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

    def _content(self, frame: np.ndarray) -> tuple[int, int, int, int] | None:
        """The box of what is bright and shows detail; None: nothing yet."""
        bright = content_bounds(frame, self.limit)
        if bright is None:
            return None
        cols, rows = detail_profiles(frame)
        flat = FLAT_SHARE * float(np.percentile(cols, 90))
        xs, ys = np.flatnonzero(cols > flat), np.flatnonzero(rows > flat)
        if xs.size == 0 or ys.size == 0:
            return None
        h, w = frame.shape[:2]
        pad = math.ceil(max(h, w) / DETAIL_SIDE)  # input px a reduced column spans
        detailed = (int(xs[0]), int(ys[0]), int(xs[-1]) + 1, int(ys[-1]) + 1)
        return _inner(bright, detailed, pad)

    def _lit_bars_opened(self, frame: np.ndarray) -> tuple[int, int, int, int]:
        """The bounds, grown to this frame's content when a bar shows detail
        beyond the bleed next to the picture (above :data:`LIT_SHARE` of the
        picture's own): a title on black gives way to a letterboxed film.
        After :data:`MAX_OPENINGS` the whole frame is the picture."""
        h, w = frame.shape[:2]
        x0, y0, x1, y1 = self._bounds
        cols, rows = detail_profiles(frame)
        detail = float(np.percentile(cols[x0:x1], 90))
        if detail < MIN_DETAIL:
            return self._bounds
        lit, m = LIT_SHARE * detail, BLEED_PX
        bands = (cols[: max(x0 - m, 0)], cols[x1 + m :], rows[: max(y0 - m, 0)], rows[y1 + m :])
        if not any(band.size and band.max() > lit for band in bands):
            return self._bounds
        self._openings += 1
        found = self._content(frame)
        if self._openings > MAX_OPENINGS or found is None:
            return 0, 0, w, h
        fx0, fy0, fx1, fy1 = found
        return _bars_kept((min(x0, fx0), min(y0, fy0), max(x1, fx1), max(y1, fy1)), w, h)


def _inner(bright, detailed, pad: int) -> tuple[int, int, int, int]:
    """The picture's box from the bright box and the detailed one: each side
    from the bright box (exact, where bars are dark) unless the detailed one
    lies further in by more than the ``pad`` its reduced columns can miss by
    (a blurred panel is bright throughout)."""
    x0, y0 = (d if d > b + pad else b for b, d in zip(bright[:2], detailed[:2], strict=True))
    x1, y1 = (d if d < b - pad else b for b, d in zip(bright[2:], detailed[2:], strict=True))
    return x0, y0, x1, y1


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
    """Two bands' thicknesses kept as bars, or both 0."""
    if min(before, after) < MIN_BAR_SHARE * side or abs(before - after) > BLEED_PX:
        return 0, 0
    return before, after
