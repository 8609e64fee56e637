"""Opening inputs, and the small image helpers every writer shares.

:func:`open_source` is the one entry point: a frames folder goes to
:mod:`motiondetect.io.frames_folder`; anything else (a video file, a URL,
a capture device, ``-`` for standard input) to FFmpeg through
:mod:`motiondetect.io.decode`. Still images and masks go through OpenCV.
"""

from __future__ import annotations

import os
from pathlib import Path

import av
import cv2
import numpy as np

from motiondetect.io.decode import AvSource, is_stream_location, main_video_stream
from motiondetect.io.encode import VideoSink
from motiondetect.io.files import atomic_path, display_name
from motiondetect.io.frames_folder import FramesFolderSource, is_frames_folder, numeric_key
from motiondetect.io.source import (
    DEFAULT_FRAMES_FPS,
    IMAGE_EXTENSIONS,
    VIDEO_EXTENSIONS,
    FrameSource,
    SourceFrame,
    VideoError,
    VideoInfo,
    to_display,
)

__all__ = [
    "DEFAULT_FRAMES_FPS", "IMAGE_EXTENSIONS", "VIDEO_EXTENSIONS", "FrameSource", "SourceFrame",
    "VideoError", "VideoInfo", "VideoSink", "count_decodable_frames", "is_animated",
    "is_frames_folder", "is_stream_location", "numeric_key", "open_source", "read_mask",
    "to_display", "write_image",
]  # fmt: skip

_IMAGE_MAGIC = (b"\x89PNG", b"\xff\xd8\xff", b"BM", b"GIF8", b"II*\x00", b"MM\x00*")


def open_source(location: str | bytes | Path, frames_fps: float | None = None) -> FrameSource:
    """Open an input; raise :class:`VideoError` (one line) if it cannot be read.

    Parameters
    ----------
    location : str, bytes or Path
        A video file, a frames folder, a URL (``rtsp://``, ``http://``,
        ``udp://`` ...), a capture device, or ``"-"`` for standard input.
    frames_fps : float, optional
        Frame rate of a frames folder (default 30, reported as assumed).
    """
    if isinstance(location, str) and is_stream_location(location):
        return AvSource(location)
    path = Path(os.fsdecode(location))
    if path.is_dir():
        if not is_frames_folder(path):
            entries = list(path.iterdir())
            images = sum(e.suffix.lower() in IMAGE_EXTENSIONS for e in entries)
            folders = sum(e.is_dir() and not e.name.startswith(".") for e in entries)
            deeper = ""
            if folders:
                which = "its sub-folder is" if folders == 1 else f"its {folders} sub-folders are"
                deeper = f"; {which} searched with --recursive"
            raise VideoError(
                f"{path}: a directory with {images} image{'s' if images != 1 else ''} and no "
                f"video; a frames folder needs at least 2 images{deeper}"
            )
        return FramesFolderSource(path, frames_fps)
    try:
        with open(path, "rb") as fp:
            head = fp.read(8)
    except FileNotFoundError:
        raise VideoError(f"{path}: no such file or directory") from None
    except OSError as exc:
        raise VideoError(f"{path}: cannot read: {exc.strerror or exc}") from None
    # A GIF, or JPEGs one after another (an MJPEG stream), with two frames is a video.
    moving = head.startswith((b"GIF8", b"\xff\xd8\xff")) and is_animated(path)
    if head.startswith(_IMAGE_MAGIC) and not moving:
        raise VideoError(f"{path}: a still image, not a video")
    return AvSource(path, display_name(path))


def is_animated(path: Path) -> bool:
    """Whether an image file holds at least two frames: an animated GIF, or
    an MJPEG stream, is a video; a still image is not."""
    try:
        with av.open(str(path)) as container:
            packets = (p for p in container.demux(video=0) if p.size)
            return sum(1 for _, _ in zip(range(2), packets)) == 2
    except (av.error.FFmpegError, OSError, IndexError, ValueError):
        return False


def write_image(path: Path, image: np.ndarray) -> None:
    """Write a PNG or JPEG (by the path's suffix) atomically (unicode-safe)."""
    ok, buf = cv2.imencode(path.suffix.lower() or ".png", image)
    if not ok:
        raise OSError(f"cannot encode {path}")
    with atomic_path(path) as tmp:
        buf.tofile(str(tmp))


def count_decodable_frames(path: str | Path) -> int:
    """Decode a video to the end and count its frames (container counts can lie)."""
    with av.open(str(path)) as container:
        stream = main_video_stream(container)
        return 0 if stream is None else sum(1 for _ in container.decode(stream))


def read_mask(path: Path) -> np.ndarray | None:
    data = np.fromfile(str(path), np.uint8)
    image = cv2.imdecode(data, cv2.IMREAD_GRAYSCALE) if data.size else None
    return image
