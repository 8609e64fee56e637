"""Colour conversion between PyAV's frames and OpenCV's BGR and grey arrays.

Nearly all video is 4:2:0 YUV (``yuv420p``, or ``yuvj420p``: the same at
full range, as webcams write it; HEVC decodes full range as ``yuv420p``
flagged by its colour range, and phones recording HDR write 10-bit
``yuv420p10le``). FFmpeg's swscale, which PyAV's
``to_ndarray(format="bgr24")`` calls, took about 2 ms per 512x512 frame
here; OpenCV's planar conversion takes about 0.1 ms (the decode rows of
``benchmarks/throughput.py``). Both use the BT.601 matrix, so the pictures
agree to a few grey levels (chroma is interpolated differently). 10-bit
levels are rounded to 8 bits first: at 3840x2160 swscale took about 15 ms
a frame, this path about 9. Other formats, and frames of odd size, go
through swscale.

Each frame is converted only as far as it is used: the measurement reads
the luma plane alone (:func:`frame_to_grey`, no colour conversion), and
the annotated video converts the planes resized to its own size
(:func:`frame_to_bgr_at`).
"""

from __future__ import annotations

import av
import cv2
import numpy as np

from motiondetect.io.source import fitted

#: Planar 4:2:0 formats OpenCV converts itself (full range is rescaled first).
_FOUR_TWO_ZERO = ("yuv420p", "yuvj420p", "yuv420p10le")
#: Formats whose first plane is the luma, with its bits per sample.
_LUMA_FIRST = {
    "yuv420p": 8, "yuvj420p": 8, "yuv422p": 8, "yuvj422p": 8, "yuv444p": 8, "yuvj444p": 8,
    "nv12": 8, "yuv420p10le": 10, "yuv422p10le": 10, "yuv444p10le": 10,
}  # fmt: skip
#: ``VideoFrame.color_range`` of full-range (JPEG) levels (FFmpeg's ``AVCOL_RANGE_JPEG``).
FULL_RANGE = 2


def _levels(scale: float, zero_in: float, zero_out: float) -> np.ndarray:
    """A 256-entry table: ``zero_out + (level - zero_in) * scale``, rounded."""
    levels = np.arange(256, dtype=np.float64)
    return np.clip(np.rint(zero_out + (levels - zero_in) * scale), 0, 255).astype(np.uint8)


#: Full-range (JPEG) levels to video range: luma 0-255 to 16-235, chroma
#: 0-255 around 128 to 16-240.
_LUMA_TO_VIDEO = _levels(219 / 255, 0, 16)
_CHROMA_TO_VIDEO = _levels(224 / 255, 128, 128)
#: Video-range luma, 16-235, to grey levels 0-255: ``(luma - 16) * GREY_SCALE``.
GREY_SCALE = 255 / 219


def _full_range(frame: av.VideoFrame) -> bool:
    return frame.format.name.startswith("yuvj") or frame.color_range == FULL_RANGE


def _eight_bits(planes: np.ndarray) -> np.ndarray:
    """10-bit levels, 0-1023, to 8 bits, rounded (a new array); 8-bit ones as they are."""
    return planes if planes.dtype == np.uint8 else cv2.convertScaleAbs(planes, alpha=0.25)


def _i420_to_bgr(planes: np.ndarray, height: int, full: bool) -> np.ndarray:
    """(3h/2, w) uint8 I420 planes as (h, w, 3) BGR; full range rescaled in place first."""
    if full:
        luma, chroma = planes[:height], planes[height:]
        cv2.LUT(luma, _LUMA_TO_VIDEO, dst=luma)
        cv2.LUT(chroma, _CHROMA_TO_VIDEO, dst=chroma)
    return cv2.cvtColor(planes, cv2.COLOR_YUV2BGR_I420)


def _plane(frame: av.VideoFrame, index: int) -> np.ndarray:
    """Plane ``index`` of ``frame``, (rows, samples), a view of the decoder's buffer
    (its rows are padded to the plane's line size)."""
    plane = frame.planes[index]
    dtype = np.uint8 if _LUMA_FIRST.get(frame.format.name, 8) == 8 else np.dtype("<u2")
    return np.frombuffer(plane, dtype).reshape(plane.height, -1)[:, : plane.width]


def _converted_here(frame: av.VideoFrame) -> bool:
    """Whether OpenCV converts ``frame`` (even-sized 4:2:0), not swscale."""
    return frame.format.name in _FOUR_TWO_ZERO and not (frame.width % 2 or frame.height % 2)


def frame_to_bgr(frame: av.VideoFrame) -> np.ndarray:
    """A decoded frame as a (h, w, 3) uint8 BGR array."""
    if not _converted_here(frame):
        return frame.to_ndarray(format="bgr24")
    planes = _eight_bits(frame.to_ndarray())  # (3h/2, w), new: Y, then U and V a quarter each
    return _i420_to_bgr(planes, frame.height, _full_range(frame))


def frame_to_bgr_at(frame: av.VideoFrame, size: tuple[int, int]) -> np.ndarray:
    """A decoded frame as (h, w, 3) uint8 BGR at ``size`` (width, height),
    for drawing: 4:2:0 planes are resized first (:func:`fitted`), so only
    the pixels drawn are converted; other formats, and odd sizes, are
    converted whole and then resized."""
    w, h = size
    if not _converted_here(frame) or w % 2 or h % 2:
        return fitted(frame_to_bgr(frame), size)
    resized = [fitted(_plane(frame, i), (w >> (i > 0), h >> (i > 0))) for i in range(3)]
    planes = np.concatenate([plane.ravel() for plane in resized]).reshape(-1, w)
    return _i420_to_bgr(_eight_bits(planes), h, _full_range(frame))


def frame_to_grey(frame: av.VideoFrame) -> np.ndarray:
    """A decoded frame as (h, w) uint8 grey: its luma plane at full range,
    where its format has one (no colour conversion); else its BGR made grey.

    The BT.601 grey of the BGR picture, 0.299 R + 0.587 G + 0.114 B, is the
    luma itself (the chroma terms cancel), bar colours clipped in BGR.
    """
    if frame.format.name not in _LUMA_FIRST:
        return cv2.cvtColor(frame_to_bgr(frame), cv2.COLOR_BGR2GRAY)
    luma = _plane(frame, 0)
    eight = _eight_bits(luma)
    if _full_range(frame):
        # a copy: the decoder may still read its buffer as a reference picture,
        # and the measurement may keep or crop what it is given
        return eight.copy() if eight is luma else eight
    # rounded and clipped as a table would, in a third of cv2.LUT's time at 4K
    return cv2.addWeighted(eight, GREY_SCALE, eight, 0.0, -16 * GREY_SCALE)


def bgr_to_frame(image: np.ndarray) -> av.VideoFrame:
    """An even-sized (h, w, 3) uint8 BGR array as a ``yuv420p`` frame for an encoder."""
    planes = cv2.cvtColor(image, cv2.COLOR_BGR2YUV_I420)
    return av.VideoFrame.from_ndarray(planes, format="yuv420p")
