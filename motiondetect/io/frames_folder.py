"""A frames folder: a directory whose files include at least two images
(JPEG, PNG, BMP, TIFF) and no video.

Frames are sorted by the last number in their names (``frame_2`` before
``frame_10``); other files are skipped with a warning, and so are images
without a number among numbered ones (a preview, a cover); 16-bit and grey
images are kept as they are. A colour JPEG is decoded by FFmpeg's JPEG
decoder, as a video's frames are (:class:`~.decode.DecodedFrame`): the
measurement reads its luma plane as the file stores it, and only what is
drawn is converted to colour. Any other image, or a JPEG FFmpeg cannot
decode (arithmetic coding, a PNG misnamed), is read whole by OpenCV. Times
step by the given (or assumed) fps; where the numbering has gaps (frames
left out of a sequence), a frame numbered ``n`` is at ``(n - first) /
fps``, so the gaps are gaps in time too. A file that cannot be read (or
differs in size from the frames, the size most of the first three readable
files share) is skipped with a warning and
marks the input partial; the frames keep the index and time of their
places among the files, so it leaves a gap as well.
"""

from __future__ import annotations

import logging
from collections.abc import Iterator
from pathlib import Path

import av
import cv2
import numpy as np

from motiondetect.io.decode import DecodedFrame
from motiondetect.io.files import last_number
from motiondetect.io.source import (
    DEFAULT_FRAMES_FPS,
    IMAGE_EXTENSIONS,
    VIDEO_EXTENSIONS,
    FrameSource,
    SourceFrame,
    VideoError,
    VideoInfo,
    check_size,
)

log = logging.getLogger("motiondetect")

#: What FFmpeg decodes a colour JPEG to (4:2:0, 4:2:2 and 4:4:4 at full
#: range), read as a video's frames are; other layouts (grey, 4:4:0, CMYK)
#: are left to OpenCV.
JPEG_LAYOUTS = ("yuvj420p", "yuvj422p", "yuvj444p")


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


def frame_files(path: Path) -> list[Path]:
    """The frames folder's frame files, in order; other entries skipped with a
    warning: files that are not images, and images without a number in
    their names among numbered ones (a preview, a cover, a thumbnail), which
    are no place in the sequence."""
    files, stray = [], []
    for entry in path.iterdir():
        if entry.is_file() and entry.suffix.lower() in IMAGE_EXTENSIONS:
            files.append(entry)
        elif not entry.name.startswith("."):
            stray.append(entry.name)
    if stray:
        log.warning("%s: skipping %d non-image entries (e.g. %s)", path, len(stray), stray[0])
    numbered = [f for f in files if last_number(f) is not None]
    if numbered and len(numbered) < len(files):
        odd = sorted(f.name for f in files if last_number(f) is None)
        log.warning(
            "%s: skipping images without a frame number among numbered frames: %d (e.g. %s)",
            path, len(odd), odd[0],
        )  # fmt: skip
        files = numbered
    return sorted(files, key=numeric_key)


#: Readable files, from the first, whose most common size is the frames'.
SIZE_VOTES = 3


class FramesFolderSource(FrameSource):
    def __init__(self, path: Path, fps: float | None) -> None:
        fps_source = "assumed" if fps is None else "given"
        fps = DEFAULT_FRAMES_FPS if fps is None else fps
        files = frame_files(path)
        numbers = [numeric_key(f)[0] for f in files]
        steps = [b - a for a, b in zip(numbers, numbers[1:])]
        gaps = sum(step > 1 for step in steps)
        rising = bool(numbers) and numbers[0] >= 0 and all(step > 0 for step in steps)
        self._timed_by_number = bool(gaps) and rising
        #: The files' numbering, first, last and gaps (the frames are timed by
        #: it, and ground truth matched by it); None where files lack numbers.
        self.numbering = (
            {"first": numbers[0], "last": numbers[-1], "gaps": gaps}
            if numbers and min(numbers) >= 0
            else None
        )
        if gaps:
            timed = "timed by their numbers" if rising else "taken in order"
            log.warning("%s: frame numbering has %d gaps; frames are %s", path, gaps, timed)
        repeated = [
            f.name for f, n, step in zip(files[1:], numbers[1:], steps) if n >= 0 and step == 0
        ]
        if repeated:  # two cameras' frames in one folder, say: interleaved by number
            log.warning(
                "%s: %d frame numbers repeat (e.g. %s); frames are taken by number, then name",
                path, len(repeated), repeated[0],
            )  # fmt: skip
        self._jpeg = av.CodecContext.create("mjpeg", "r")
        self._jpeg.thread_count = 1  # one picture a packet, returned at once
        first, first_at = self._first_readable(files)  # it sets the size
        if first is None:
            raise VideoError(f"{path}: no readable image frames")
        w, h = _size(first)
        check_size(w, h, str(path))
        self._files, self._numbers, self._first, self._first_at = files, numbers, first, first_at
        span = numbers[-1] - numbers[0] + 1 if self._timed_by_number else 0
        self.info = VideoInfo(
            str(path), "frames", w, h, fps, len(files), "image-sequence", 0, fps_source,
            span_frames=span,
        )  # fmt: skip
        self.partial = False

    def _first_readable(self, files: list[Path]) -> tuple[np.ndarray | av.VideoFrame | None, int]:
        """The first of ``files`` that can be read and has the size most of
        the first :data:`SIZE_VOTES` readable ones share (a preview or a
        thumbnail among the frames does not set it), and its place; (None,
        len) when none can be read."""
        seen = []
        for at, file in enumerate(files):
            image = self._read(file)
            if image is not None:
                seen.append((at, image))
                if len(seen) == SIZE_VOTES:
                    break
        if not seen:
            return None, len(files)
        sizes = [_size(image) for _, image in seen]
        common = max(sizes, key=sizes.count)  # a tie: the first file's
        at, image = seen[sizes.index(common)]
        return image, at

    def _read(self, file: Path) -> np.ndarray | av.VideoFrame | None:
        """The image in ``file``: a colour JPEG as FFmpeg's decoded frame,
        anything else as OpenCV's array; None when unreadable."""
        data = file.read_bytes()  # decoded from memory: any name, unlike cv2.imread
        if not data:
            return None
        if file.suffix.lower() in (".jpg", ".jpeg"):
            try:
                decoded = self._jpeg.decode(av.Packet(data))
            except av.error.FFmpegError:  # e.g. arithmetic coding: left to OpenCV
                decoded = []
            if decoded and decoded[0].format.name in JPEG_LAYOUTS:
                return decoded[0]
        return cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_UNCHANGED)

    def __iter__(self) -> Iterator[SourceFrame]:
        """Each readable frame, its index its place among the files and its
        time its place in the sequence: a file skipped (unreadable, or of
        another size) leaves a gap in both, as a frame left out of the
        numbering leaves one in time, so the frames after it keep their
        own times (and ground truth, or poses, numbered as the files)."""
        size, first = _size(self._first), self._first_at
        for i, file in enumerate(self._files):
            image = self._first if i == first else None if i < first else self._read(file)
            if image is None or _size(image) != size:
                log.warning("%s: skipping unreadable or differently sized frame", file)
                self.partial = True
                continue
            step = self._numbers[i] - self._numbers[0] if self._timed_by_number else i
            time_s, number = step / self.info.fps, self._numbers[i]
            if isinstance(image, av.VideoFrame):
                yield DecodedFrame(i, time_s, image, 0, number)
            else:
                yield SourceFrame(i, time_s, image, number)

    @property
    def frame_numbers(self) -> list[int]:
        return list(self._numbers)


def _size(image: np.ndarray | av.VideoFrame) -> tuple[int, int]:
    """(width, height) of a read image."""
    if isinstance(image, av.VideoFrame):
        return image.width, image.height
    return image.shape[1], image.shape[0]
