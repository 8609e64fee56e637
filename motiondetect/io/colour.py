"""Colour conversion between PyAV's frames and OpenCV's BGR arrays.

Nearly all video is 4:2:0 YUV (``yuv420p``, or ``yuvj420p``: the same at
full range, as webcams write it; HEVC decodes full range as ``yuv420p``
flagged by its colour range, and phones recording HDR write 10-bit
``yuv420p10le``). FFmpeg's swscale, which
PyAV's ``to_ndarray(format="bgr24")`` calls, took about 2 ms per 512x512
frame here; OpenCV's planar conversion takes about 0.1 ms (the decode
rows of ``benchmarks/throughput.py``). Both use the BT.601 matrix, so the
pictures agree to a few grey levels (chroma is interpolated differently).
10-bit levels are rounded to 8 bits first: at 3840x2160 swscale took about
15 ms a frame, this path about 9. Other formats, and frames of odd size, go
through swscale.
"""

from __future__ import annotations

import av
import cv2
import numpy as np

#: Planar 4:2:0 formats OpenCV converts itself (full range is rescaled first).
_FOUR_TWO_ZERO = ("yuv420p", "yuvj420p", "yuv420p10le")
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


def frame_to_bgr(frame: av.VideoFrame) -> np.ndarray:
    """A decoded frame as a (h, w, 3) uint8 BGR array."""
    name = frame.format.name
    if name not in _FOUR_TWO_ZERO or frame.width % 2 or frame.height % 2:
        return frame.to_ndarray(format="bgr24")
    planes = frame.to_ndarray()  # (3h/2, w), a new array: Y, then U and V a quarter each
    if planes.dtype != np.uint8:  # 10-bit levels, 0-1023: to 8 bits, rounded
        planes = cv2.convertScaleAbs(planes, alpha=0.25)
    if name == "yuvj420p" or frame.color_range == FULL_RANGE:  # rescaled in place
        luma, chroma = planes[: frame.height], planes[frame.height :]
        cv2.LUT(luma, _LUMA_TO_VIDEO, dst=luma)
        cv2.LUT(chroma, _CHROMA_TO_VIDEO, dst=chroma)
    return cv2.cvtColor(planes, cv2.COLOR_YUV2BGR_I420)


def bgr_to_frame(image: np.ndarray) -> av.VideoFrame:
    """An even-sized (h, w, 3) uint8 BGR array as a ``yuv420p`` frame for an encoder."""
    planes = cv2.cvtColor(image, cv2.COLOR_BGR2YUV_I420)
    return av.VideoFrame.from_ndarray(planes, format="yuv420p")
