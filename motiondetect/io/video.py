"""Video input and output: the only module that decodes or encodes frames.

Sources are read frame by frame (memory stays flat in video length):

* a **video file**, anything OpenCV's FFmpeg backend reads; times come from
  the container's presentation timestamps, so variable frame rates are
  right; rotation metadata is applied by OpenCV and reported;
* a **frames folder**: a directory whose files include at least two images
  (JPEG, PNG, BMP, TIFF) and no video; frames are sorted by the last number
  in their names (``frame_2`` before ``frame_10``); other files are skipped
  with a warning; 16-bit and grey images are kept as they are.
"""

from __future__ import annotations

import contextlib
import logging
import os
from collections.abc import Iterator
from dataclasses import asdict, dataclass
from pathlib import Path

import cv2
import numpy as np

from motiondetect.io.files import atomic_path, last_number, temporary_path

log = logging.getLogger("motiondetect")

IMAGE_EXTENSIONS = {".jpg", ".jpeg", ".png", ".bmp", ".tif", ".tiff"}
VIDEO_EXTENSIONS = {
    ".mp4",
    ".avi",
    ".mov",
    ".mkv",
    ".webm",
    ".m4v",
    ".mpg",
    ".mpeg",
    ".wmv",
    ".flv",
    ".ts",
    ".mts",
    ".3gp",
    ".ogv",
}
DEFAULT_FRAMES_FPS = 30.0
MAX_FRAME_PIXELS = 16384 * 16384

# FFmpeg's own log lines ("moov atom not found") are not this tool's messages:
# OpenCV reads this when it opens its first capture. A value the user set wins;
# the CLI's -v sets warnings (docs/robustness.md).
os.environ.setdefault("OPENCV_FFMPEG_LOGLEVEL", "-8")

try:  # keep FFmpeg's own chatter out of the user's terminal
    cv2.utils.logging.setLogLevel(cv2.utils.logging.LOG_LEVEL_ERROR)
except AttributeError:  # pragma: no cover - older OpenCV
    pass


class VideoError(Exception):
    """An input cannot be read as video; the message is one line for the user."""


@dataclass(frozen=True)
class VideoInfo:
    """What the tool sees in an input."""

    path: str
    kind: str  # "video" or "frames"
    width: int
    height: int
    fps: float
    frame_count: int  # as the container states it; 0 when unknown
    codec: str
    rotation_deg: int = 0
    fps_source: str = "container"  # "container", "given" (--frames-fps) or "assumed"

    @property
    def duration_s(self) -> float:
        return self.frame_count / self.fps if self.fps > 0 else 0.0

    def to_json(self) -> dict:
        out = asdict(self)
        out["duration_s"] = round(self.duration_s, 4)
        return out


@dataclass(frozen=True)
class SourceFrame:
    index: int  # 0-based, in decode order
    time_s: float
    image: np.ndarray
    number: int | None = None  # the number in a frame file's name


def numeric_key(path: Path) -> tuple:
    """Sort key of a frame file: its last number, then its name."""
    number = last_number(path)
    return (-1 if number is None else number, path.name)


def is_frames_folder(path: Path) -> bool:
    """The documented rule: >= 2 image files and no video file directly inside."""
    if not path.is_dir():
        return False
    images = videos = 0
    for entry in path.iterdir():
        suffix = entry.suffix.lower()
        if entry.is_file():
            images += suffix in IMAGE_EXTENSIONS
            videos += suffix in VIDEO_EXTENSIONS
    return images >= 2 and videos == 0


class FrameSource:
    """Iterate the frames of one input. Use :func:`open_source`."""

    info: VideoInfo
    partial: bool = False  # decoding stopped before the stated frame count

    def __iter__(self) -> Iterator[SourceFrame]:  # pragma: no cover - interface
        raise NotImplementedError

    def close(self) -> None:
        pass

    def __enter__(self) -> FrameSource:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _check_size(width: int, height: int, path: Path) -> None:
    if width < 64 or height < 64:
        raise VideoError(f"{path}: frames are {width}x{height}; at least 64x64 pixels are needed")
    if width * height > MAX_FRAME_PIXELS:
        raise VideoError(f"{path}: frames of {width}x{height} are too large to process")


_IMAGE_MAGIC = (b"\x89PNG", b"\xff\xd8\xff", b"BM", b"GIF8", b"II*\x00", b"MM\x00*")


class _VideoFileSource(FrameSource):
    def __init__(self, path: Path) -> None:
        if path.stat().st_size == 0:
            raise VideoError(f"{path}: file is empty")
        with open(path, "rb") as fp:
            head = fp.read(8)
        if head.startswith(_IMAGE_MAGIC):
            raise VideoError(f"{path}: a still image, not a video")
        cap = cv2.VideoCapture(str(path), cv2.CAP_FFMPEG)
        if not cap.isOpened():
            raise VideoError(f"{path}: not a video OpenCV/FFmpeg can open")
        ok, first = cap.read()
        if not ok or first is None:
            cap.release()
            raise VideoError(f"{path}: no decodable video frames")
        h, w = first.shape[:2]
        _check_size(w, h, path)
        fps = float(cap.get(cv2.CAP_PROP_FPS) or 0.0)
        fps_source = "container"
        if not np.isfinite(fps) or fps <= 0 or fps > 1000:
            fps, fps_source = DEFAULT_FRAMES_FPS, "assumed"
        fourcc = int(cap.get(cv2.CAP_PROP_FOURCC) or 0)
        codec = "".join(chr((fourcc >> 8 * i) & 0xFF) for i in range(4)).strip("\x00 ") or "?"
        rotation = int(cap.get(cv2.CAP_PROP_ORIENTATION_META) or 0)
        count = max(0, int(cap.get(cv2.CAP_PROP_FRAME_COUNT) or 0))
        self.info = VideoInfo(str(path), "video", w, h, fps, count, codec, rotation, fps_source)
        self._cap = cap
        self._first = (first, self._time(cap, 0, fps))
        self.partial = False

    @staticmethod
    def _time(cap: cv2.VideoCapture, index: int, fps: float) -> float:
        msec = cap.get(cv2.CAP_PROP_POS_MSEC)
        return msec / 1000.0 if msec and np.isfinite(msec) and msec >= 0 else index / fps

    def __iter__(self) -> Iterator[SourceFrame]:
        first, t0 = self._first
        yield SourceFrame(0, t0, first)
        index = 1
        last_t = t0
        while True:
            ok, image = self._cap.read()
            if not ok or image is None:
                break
            t = self._time(self._cap, index, self.info.fps)
            if t <= last_t:  # containers without timestamps
                t = last_t + 1.0 / self.info.fps
            last_t = t
            yield SourceFrame(index, t, image)
            index += 1
        stated = self.info.frame_count
        if stated and index < stated - 1:
            self.partial = True
            log.warning(
                "%s: decoding stopped at frame %d of %d stated", self.info.path, index, stated
            )

    def close(self) -> None:
        self._cap.release()


class _FramesFolderSource(FrameSource):
    def __init__(self, path: Path, fps: float | None) -> None:
        fps_source = "assumed" if fps is None else "given"
        fps = DEFAULT_FRAMES_FPS if fps is None else fps
        files, stray = [], []
        for entry in path.iterdir():
            if entry.is_file() and entry.suffix.lower() in IMAGE_EXTENSIONS:
                files.append(entry)
            elif not entry.name.startswith("."):
                stray.append(entry.name)
        if stray:
            log.warning("%s: skipping %d non-image entries (e.g. %s)", path, len(stray), stray[0])
        files.sort(key=numeric_key)
        numbers = [numeric_key(f)[0] for f in files]
        gaps = sum(1 for a, b in zip(numbers, numbers[1:]) if b - a > 1)
        if gaps:
            log.warning("%s: frame numbering has %d gaps; frames are taken in order", path, gaps)
        first = self._read(files[0]) if files else None
        if first is None:
            raise VideoError(f"{path}: no readable image frames")
        h, w = first.shape[:2]
        _check_size(w, h, path)
        self._files, self._numbers, self._first = files, numbers, first
        self.info = VideoInfo(
            str(path), "frames", w, h, fps, len(files), "image-sequence", 0, fps_source
        )
        self.partial = False

    @staticmethod
    def _read(file: Path) -> np.ndarray | None:
        data = np.fromfile(str(file), np.uint8)  # unicode-safe, unlike cv2.imread
        if data.size == 0:
            return None
        return cv2.imdecode(data, cv2.IMREAD_UNCHANGED)

    def __iter__(self) -> Iterator[SourceFrame]:
        shape = self._first.shape
        index = 0
        for i, file in enumerate(self._files):
            image = self._first if i == 0 else self._read(file)
            if image is None or image.shape[:2] != shape[:2]:
                log.warning("%s: skipping unreadable or differently sized frame", file)
                self.partial = True
                continue
            yield SourceFrame(index, index / self.info.fps, image, self._numbers[i])
            index += 1

    @property
    def frame_numbers(self) -> list[int]:
        return list(self._numbers)


def open_source(path: str | Path, frames_fps: float | None = None) -> FrameSource:
    """Open a video file or a frames folder; raise :class:`VideoError` if it cannot be read."""
    path = Path(path)
    if not path.exists():
        raise VideoError(f"{path}: no such file or directory")
    if path.is_dir():
        if not is_frames_folder(path):
            images = sum(1 for e in path.iterdir() if e.suffix.lower() in IMAGE_EXTENSIONS)
            raise VideoError(
                f"{path}: a directory with {images} image{'s' if images != 1 else ''} and no "
                "video; a frames folder needs at least 2 images"
            )
        return _FramesFolderSource(path, frames_fps)
    try:
        return _VideoFileSource(path)
    except OSError as exc:
        raise VideoError(f"{path}: cannot read: {exc.strerror or exc}") from exc


@contextlib.contextmanager
def _quiet_native_stderr():
    """Silence C-level stderr: OpenCV's FFmpeg wrapper prints a harmless
    "tag ... is not supported" line with fprintf when opening a WebM writer."""
    try:
        saved = os.dup(2)
    except OSError:  # no real stderr (embedded use)
        yield
        return
    try:
        with open(os.devnull, "wb") as null:
            os.dup2(null.fileno(), 2)
            yield
    finally:
        os.dup2(saved, 2)
        os.close(saved)


class VideoSink:
    """Write frames to a video atomically: a hidden temporary file, renamed on success.

    Parameters
    ----------
    path : Path
        Final name; ``.webm`` gives VP8 (plays in web browsers), ``.mp4``
        gives MPEG-4 Part 2, ``.mkv`` gives lossless FFV1.
    fps : float
    size : (width, height)
    """

    FOURCC = {".webm": "VP80", ".mp4": "mp4v", ".mkv": "FFV1", ".avi": "MJPG"}

    def __init__(self, path: str | Path, fps: float, size: tuple[int, int]) -> None:
        self.path = Path(path)
        self._tmp = temporary_path(self.path)
        fourcc = cv2.VideoWriter_fourcc(*self.FOURCC.get(self.path.suffix.lower(), "mp4v"))
        with _quiet_native_stderr():
            self._writer = cv2.VideoWriter(str(self._tmp), fourcc, float(fps), size)
        if not self._writer.isOpened():
            raise VideoError(f"{self.path}: cannot open a video writer here")
        self.size = size
        self.frames = 0

    def write(self, frame: np.ndarray) -> None:
        if frame.ndim == 2:
            frame = cv2.cvtColor(frame, cv2.COLOR_GRAY2BGR)
        self._writer.write(frame)
        self.frames += 1

    def close(self, keep: bool = True) -> None:
        self._writer.release()
        if keep and self._tmp.exists() and self._tmp.stat().st_size > 0:
            os.replace(self._tmp, self.path)
        else:
            self._tmp.unlink(missing_ok=True)
            if keep:
                raise VideoError(f"{self.path}: the video writer produced no output")

    def __enter__(self) -> VideoSink:
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        self.close(keep=exc_type is None)


def to_display(image: np.ndarray) -> np.ndarray:
    """Any input frame as 8-bit BGR for drawing and encoding."""
    if image.dtype == np.uint16:
        image = (image >> 8).astype(np.uint8)
    if image.ndim == 2 or image.shape[2] == 1:
        return cv2.cvtColor(image.reshape(image.shape[:2]), cv2.COLOR_GRAY2BGR)
    if image.shape[2] == 4:
        return cv2.cvtColor(image, cv2.COLOR_BGRA2BGR)
    return image


def write_image(path: Path, image: np.ndarray) -> None:
    """Write a PNG or JPEG (by the path's suffix) atomically (unicode-safe)."""
    ok, buf = cv2.imencode(path.suffix.lower() or ".png", image)
    if not ok:
        raise OSError(f"cannot encode {path}")
    with atomic_path(path) as tmp:
        buf.tofile(str(tmp))


def count_decodable_frames(path: str | Path) -> int:
    """Decode a video to the end and count its frames (container counts can lie)."""
    cap = cv2.VideoCapture(str(path))
    count = 0
    while cap.grab():
        count += 1
    cap.release()
    return count


def read_mask(path: Path) -> np.ndarray | None:
    data = np.fromfile(str(path), np.uint8)
    image = cv2.imdecode(data, cv2.IMREAD_GRAYSCALE) if data.size else None
    return image
