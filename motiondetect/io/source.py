"""What every input looks like to the pipeline: its description and its frames.

A source is read frame by frame (memory stays flat in video length). Its
kinds live beside this module: :mod:`motiondetect.io.decode` (anything
FFmpeg opens, through PyAV) and :mod:`motiondetect.io.frames_folder`.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import asdict, dataclass

import cv2
import numpy as np

#: Frame files OpenCV decodes to 8 or 16 bits: also WebP (frames saved from
#: the web) and the Netpbm formats (PGM/PPM dumps of robot and lab cameras).
IMAGE_EXTENSIONS = {
    ".jpg", ".jpeg", ".png", ".bmp", ".tif", ".tiff", ".webp", ".pgm", ".ppm", ".pnm",
}  # fmt: skip
#: Video files a batch finds: containers, the names cameras give them
#: (camcorders' DV and MPEG-2 .mod/.tod, GoPro's .lrv proxies, Insta360's
#: .insv, both MP4), and the raw streams cameras and encoders leave
#: (H.264/H.265 elementary streams, IVF, MJPEG).
VIDEO_EXTENSIONS = {
    ".mp4", ".avi", ".mov", ".qt", ".mkv", ".webm", ".m4v", ".mpg", ".mpeg", ".wmv", ".flv",
    ".ts", ".mts", ".m2ts", ".3gp", ".3g2", ".ogv", ".y4m", ".mxf", ".vob", ".m2v", ".f4v",
    ".asf", ".divx", ".nut", ".rm", ".rmvb", ".dv", ".dif", ".mod", ".tod", ".lrv", ".insv",
    ".h264", ".264", ".h265", ".265", ".hevc", ".ivf", ".mjpeg", ".mjpg",
}  # fmt: skip
DEFAULT_FRAMES_FPS = 30.0
MIN_FRAME_SIDE = 64
MAX_FRAME_PIXELS = 16384 * 16384


class VideoError(Exception):
    """An input cannot be read as video; the message is one line for the user."""


@dataclass(frozen=True)
class VideoInfo:
    """What the tool sees in an input.

    ``rotation_deg`` is the clockwise turn the container asks for (applied
    to the frames); ``fps_source`` says where ``fps`` came from:
    ``"container"``, ``"given"`` (``--frames-fps``), ``"timestamps"``
    (measured from the first frames' timestamps) or ``"assumed"``.
    """

    path: str
    kind: str  # "video", "stream" or "frames"
    width: int
    height: int
    fps: float
    frame_count: int  # as the container states it; 0 when unknown
    codec: str
    rotation_deg: int = 0
    fps_source: str = "container"
    interlaced: bool = False
    span_frames: int = 0  # frame steps the times span (a folder timed by number); 0: frames

    @property
    def duration_s(self) -> float:
        frames = self.span_frames or self.frame_count
        return frames / self.fps if self.fps > 0 else 0.0

    def to_json(self) -> dict:
        out = asdict(self)
        del out["span_frames"]  # what it changes is the duration
        out["duration_s"] = round(self.duration_s, 4)
        return out


@dataclass(frozen=True)
class SourceFrame:
    index: int  # 0-based, in presentation order
    time_s: float  # from the stream's timestamps, 0 at the stream's start
    image: np.ndarray
    number: int | None = None  # the number in a frame file's name

    @property
    def grey(self) -> np.ndarray:
        """What the measurement reads: here the image itself, which the
        pipeline makes grey (a decoded video's frames give their luma)."""
        return self.image

    def picture(self, size: tuple[int, int]) -> np.ndarray:
        """The image as 8-bit BGR at ``size`` (width, height), for drawing
        (:func:`fitted`; a decoded video's frames convert only that many pixels)."""
        return fitted(to_display(self.image), size)


def to_display(image: np.ndarray) -> np.ndarray:
    """Any input frame as 8-bit BGR for drawing and encoding."""
    if image.dtype == np.uint16:
        image = (image >> 8).astype(np.uint8)
    if image.ndim == 2 or image.shape[2] == 1:
        return cv2.cvtColor(image.reshape(image.shape[:2]), cv2.COLOR_GRAY2BGR)
    if image.shape[2] == 4:
        return cv2.cvtColor(image, cv2.COLOR_BGRA2BGR)
    return image


def fitted(image: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """``image`` at ``size`` (width, height): area-averaged when reduced,
    interpolated when enlarged; itself when already that size."""
    h, w = image.shape[:2]
    if (w, h) == size:
        return image
    smaller = size[0] < w
    return cv2.resize(image, size, interpolation=cv2.INTER_AREA if smaller else cv2.INTER_LINEAR)


class FrameSource:
    """Iterate the frames of one input. Use :func:`motiondetect.io.video.open_source`.

    After iteration, ``partial`` says decoding stopped early or skipped
    damage, and ``decode_errors`` counts the damaged packets skipped.
    """

    info: VideoInfo
    partial: bool = False
    decode_errors: int = 0
    seekable: bool = True  # False for pipes, URLs and devices: read once, as it arrives

    def __iter__(self) -> Iterator[SourceFrame]:  # pragma: no cover - interface
        raise NotImplementedError

    def close(self) -> None:
        pass

    def __enter__(self) -> FrameSource:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def check_size(width: int, height: int, name: str) -> None:
    """Refuse frames too small to measure motion on, or too large to hold."""
    if width < MIN_FRAME_SIDE or height < MIN_FRAME_SIDE:
        raise VideoError(
            f"{name}: frames are {width}x{height}; at least "
            f"{MIN_FRAME_SIDE}x{MIN_FRAME_SIDE} pixels are needed"
        )
    if width * height > MAX_FRAME_PIXELS:
        raise VideoError(f"{name}: frames of {width}x{height} are too large to process")
