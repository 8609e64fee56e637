"""Video in through PyAV, FFmpeg's own bindings: files, URLs, devices and pipes.

Every video input goes through :class:`AvSource`:

* frames carry their **presentation timestamps** (0 at the stream's start),
  so variable frame rates are exact; timestamps that go back (concatenated
  MPEG-TS, broken muxers) are warned about once and the times continue
  monotonically from there;
* decoding is **threaded** (``thread_type="AUTO"``);
* **damaged packets are skipped**, counted in ``decode_errors``; the input
  is then ``partial``, and frames decoded after the damage are processed;
* **interlaced** streams are deinterlaced with FFmpeg's ``bwdif`` filter;
* the container's **display rotation** is applied;
* **paths** may be ``str``, ``bytes`` or :class:`~pathlib.Path` (any bytes
  a file system allows); **URLs** (``rtsp://``, ``http://``, ``udp://`` ...),
  **capture devices** (``/dev/video0``) and ``-`` (standard input) are
  read once, as they arrive.

FFmpeg's own log lines are never printed here; on a failure to open, the
last one becomes part of the one-line error.
"""

from __future__ import annotations

import contextlib
import logging
import os
import re
import stat
import sys
from collections.abc import Iterator
from functools import cached_property
from pathlib import Path

import av
import numpy as np

from motiondetect.io.colour import frame_to_bgr, frame_to_bgr_at, frame_to_grey
from motiondetect.io.source import (
    DEFAULT_FRAMES_FPS,
    FrameSource,
    SourceFrame,
    VideoError,
    VideoInfo,
    check_size,
)

log = logging.getLogger("motiondetect")

STDIN = "-"
URL = re.compile(r"^[a-zA-Z][a-zA-Z0-9+.-]*://")
NETWORK_TIMEOUT_S = 15.0  # a URL that sends nothing for this long has ended
PIPE_BUFFER_BYTES = 1 << 16
# A stream is probed for at most this long before its first frame is decoded
# (FFmpeg's default, 5 s, would hold a live input back by as much).
STREAM_PROBE = {"analyzeduration": "1000000", "probesize": "1000000"}
DEINTERLACE = ("bwdif", "mode=send_frame:parity=auto:deint=interlaced")

# FFmpeg's words for common failures, and what they mean to a user.
_EXPLAINED = {
    "moov atom not found": "the MP4 index (moov atom) is missing: the file was cut short "
    "before its index was written, and no frame can be located without it",
    "Connection refused": "the server refused the connection",
    "Invalid data found when processing input": "not a video FFmpeg can read",
}


def is_stream_location(text: str) -> bool:
    """``-`` (standard input) or a URL: read once, as it arrives."""
    return text == STDIN or bool(URL.match(text))


def is_device(path: Path) -> bool:
    try:
        return stat.S_ISCHR(path.stat().st_mode)
    except OSError:
        return False


@contextlib.contextmanager
def _ffmpeg_lines():
    """FFmpeg's error lines while opening, kept to explain a failure, not printed."""
    previous = av.logging.get_level()
    av.logging.set_level(av.logging.ERROR)
    try:
        with av.logging.Capture() as lines:
            yield lines
    finally:
        av.logging.set_level(previous)


#: The box types an MP4/MOV file (ISO base media) can start with.
_MP4_BOXES = (b"ftyp", b"moov", b"mdat", b"free", b"skip", b"wide", b"pnot", b"uuid")


def _starts_like_mp4(path: str) -> bool:
    try:
        with open(path, "rb") as file:
            return file.read(8)[4:8] in _MP4_BOXES
    except OSError:
        return False


def _explain(name: str, exc: Exception, lines: list, path: str | None = None) -> str:
    """One line for a file FFmpeg could not open. FFmpeg's last error line
    is read from the capture and from PyAV's exception (FFmpeg does not
    repeat a line it just logged, so the next input that fails the same way
    leaves none to capture)."""
    last = " ".join(str(line[2]).strip() for line in lines[-1:])
    said = last or getattr(exc, "strerror", None) or str(exc)
    heard = f"{last} {exc}"
    for words, meaning in _EXPLAINED.items():
        if words in heard:
            if words == "moov atom not found" and path is not None and not _starts_like_mp4(path):
                meaning = _EXPLAINED["Invalid data found when processing input"]
            return f"{name}: {meaning}"
    return f"{name}: cannot open: {said}"


def _open_container(location: str | bytes | Path, name: str):
    """The opened container, whether it can seek, and its display name."""
    options: dict = {}
    if isinstance(location, str) and location == STDIN:
        target, fmt, seekable = sys.stdin.buffer, None, False
        options = {"buffer_size": PIPE_BUFFER_BYTES, "container_options": STREAM_PROBE}
    elif isinstance(location, str) and URL.match(location):
        target, fmt, seekable = location, None, False
        options = {"timeout": NETWORK_TIMEOUT_S, "container_options": STREAM_PROBE}
    else:
        path = Path(os.fsdecode(location))
        if not path.exists():
            raise VideoError(f"{name}: no such file or directory")
        device = is_device(path)
        if not device and path.stat().st_size == 0:
            raise VideoError(f"{name}: file is empty")
        target = str(path)
        fmt = "v4l2" if device and sys.platform.startswith("linux") else None
        seekable = not device
    with _ffmpeg_lines() as lines:
        try:
            container = av.open(target, format=fmt, metadata_errors="replace", **options)
        except av.error.FFmpegError as exc:
            path_text = target if isinstance(target, str) and seekable else None
            raise VideoError(_explain(name, exc, lines, path_text)) from None
        except OSError as exc:
            raise VideoError(f"{name}: cannot read: {exc.strerror or exc}") from None
        except Exception as exc:  # PyAV's own parsing of a damaged header
            raise VideoError(f"{name}: not a video FFmpeg can open ({exc!r})") from None
    return container, seekable


def _frame_rate(stream) -> tuple[float, str]:
    for rate in (stream.average_rate, stream.guessed_rate):
        if rate is not None and rate > 0 and np.isfinite(float(rate)):
            return float(rate), "container"
    return DEFAULT_FRAMES_FPS, "assumed"


#: Dispositions of a video stream that is a picture, not the video: cover art
#: (an MP4's or MKV's attached picture), thumbnails, a still image.
_PICTURES = (
    av.stream.Disposition.attached_pic
    | av.stream.Disposition.timed_thumbnails
    | av.stream.Disposition.still_image
)


def main_video_stream(container: av.container.InputContainer) -> av.VideoStream | None:
    """The video stream to read: FFmpeg's best (``av_find_best_stream``: the
    default one, then the one with frames, then the highest bit rate), never
    a cover picture or a thumbnail track (the first video stream was a
    thumbnail in files that store one before the video); None when the
    file's video streams are only such pictures (an audio file's cover)."""
    moving = [s for s in container.streams.video if not s.disposition & _PICTURES]
    best = container.streams.best("video")
    return best if best in moving else (moving[0] if moving else None)


class AvSource(FrameSource):
    """The frames of one video file, URL, device or pipe, decoded by FFmpeg."""

    def __init__(self, location: str | bytes | Path, name: str | None = None) -> None:
        name = name or (os.fsdecode(location) if not isinstance(location, str) else location)
        self.name = name
        self._container, self.seekable = _open_container(location, name)
        try:
            self._setup(name)
        except BaseException:
            self._container.close()
            raise

    def _setup(self, name: str) -> None:
        if not self._container.streams.video:
            raise VideoError(f"{name}: no video stream (a damaged header, or audio or data only)")
        stream = self._stream = main_video_stream(self._container)
        if stream is None:
            raise VideoError(f"{name}: no video stream, only a cover picture (an audio file?)")
        if stream.codec_context is None:
            raise VideoError(f"{name}: no decoder for this stream's codec in this FFmpeg build")
        stream.thread_type = "AUTO"
        self.decode_errors, self.partial = 0, False
        self._graph = None
        self._decoded = self._frames()
        first = next(self._decoded, None)
        if first is None:
            raise VideoError(self._nothing_decoded(name))
        self._turns = round((first.rotation or 0) / 90) % 4  # counter-clockwise quarter turns
        width, height = (first.width, first.height)[:: -1 if self._turns % 2 else 1]
        check_size(width, height, name)
        fps, fps_source = _frame_rate(stream)
        self.info = VideoInfo(
            name, "video" if self.seekable else "stream", width, height,
            fps, max(0, stream.frames or 0), stream.codec_context.name,
            (-90 * self._turns) % 360, fps_source, self._graph is not None,
        )  # fmt: skip
        start = stream.start_time
        self._origin = float(start * stream.time_base) if start is not None else first.time or 0
        self._first = first

    def _nothing_decoded(self, name: str) -> str:
        if not self.seekable and "mp4" in self._container.format.name.split(","):
            # The index of an MP4 written without faststart follows its
            # frames, and a pipe cannot seek back to the frames after it.
            return (
                f"{name}: an MP4 or MOV whose index (moov atom) follows its frames cannot be "
                "read from a pipe: give the file's path, or remux it first with "
                "'ffmpeg -i IN -c copy -movflags +faststart OUT.mp4'"
            )
        damaged = f" ({self.decode_errors} damaged packets)" if self.decode_errors else ""
        return f"{name}: no decodable video frames{damaged}"

    def _damaged(self, what: str) -> None:
        self.decode_errors += 1
        log.debug("%s: skipping a damaged packet: %s", self.name, what)

    def _frames(self) -> Iterator[av.VideoFrame]:
        """Decoded (and, if interlaced, deinterlaced) frames; damage is skipped."""
        try:
            for packet in self._container.demux(self._stream):
                try:
                    frames = packet.decode()
                except av.error.FFmpegError as exc:
                    self._damaged(str(exc))
                    continue
                for frame in frames:
                    if frame.is_corrupt:
                        self._damaged("a frame decoded with errors")
                    yield from self._filtered(frame)
        except av.error.FFmpegError as exc:  # the container itself gives out
            self.partial = True
            log.warning("%s: reading stopped: %s", self.name, exc.strerror or exc)
        yield from self._filtered(None)

    def _filtered(self, frame: av.VideoFrame | None) -> Iterator[av.VideoFrame]:
        if self._graph is None and frame is not None and frame.interlaced_frame:
            self._graph = av.filter.Graph()
            chain = [self._graph.add_buffer(template=self._stream)]
            chain.append(self._graph.add(*DEINTERLACE))
            chain.append(self._graph.add("buffersink"))
            self._graph.link_nodes(*chain).configure()
        if self._graph is None:
            if frame is not None:
                yield frame
            return
        self._graph.push(frame)
        while True:
            try:
                yield self._graph.pull()
            except (BlockingIOError, av.error.EOFError):
                return

    def __iter__(self) -> Iterator[SourceFrame]:
        clock = _Clock(self.name, self._origin, self.info.fps)
        yield DecodedFrame(0, clock.time(self._first), self._first, self._turns)
        index = 1
        for frame in self._decoded:
            yield DecodedFrame(index, clock.time(frame), frame, self._turns)
            index += 1
        self._finish(index)

    def _finish(self, decoded: int) -> None:
        stated = self.info.frame_count
        if self.decode_errors:
            self.partial = True
            log.warning("%s: skipped %d damaged packets", self.name, self.decode_errors)
        if stated and decoded < stated - 1:
            self.partial = True
            log.warning("%s: decoding stopped at frame %d of %d stated", self.name, decoded, stated)

    def close(self) -> None:
        self._container.close()


class DecodedFrame(SourceFrame):
    """A frame of :class:`AvSource` (or a colour JPEG of a frames folder,
    with its ``number``): its BGR ``image`` and its ``grey`` are
    made from FFmpeg's frame when first read, each once, and turned as the
    container asks. The measurement reads only ``grey``, the luma plane
    (:func:`~.colour.frame_to_grey`), and the annotated video its
    :meth:`picture`, converted at the video's size on the drawing thread, so
    no frame is converted to colour whole.
    """

    def __init__(
        self, index: int, time_s: float, frame: av.VideoFrame, turns: int, number: int | None = None
    ) -> None:
        for name, value in (("index", index), ("time_s", time_s), ("number", number)):
            object.__setattr__(self, name, value)
        object.__setattr__(self, "_decoded", (frame, turns))

    @cached_property
    def image(self) -> np.ndarray:  # type: ignore[override]
        frame, turns = self._decoded
        return _turned(frame_to_bgr(frame), turns)

    @cached_property
    def grey(self) -> np.ndarray:  # type: ignore[override]
        frame, turns = self._decoded
        return _turned(frame_to_grey(frame), turns)

    def picture(self, size: tuple[int, int]) -> np.ndarray:
        frame, turns = self._decoded
        return _turned(frame_to_bgr_at(frame, size[:: -1 if turns % 2 else 1]), turns)


def _turned(image: np.ndarray, turns: int) -> np.ndarray:
    """``image`` turned ``turns`` quarter turns counter-clockwise."""
    return np.ascontiguousarray(np.rot90(image, turns)) if turns else image


class _Clock:
    """Frame times from timestamps, kept increasing.

    A timestamp that goes back or repeats is warned about once; from there
    on, times continue one frame period after the last good one, keeping the
    stream's own spacing.
    """

    def __init__(self, name: str, origin: float, fps: float) -> None:
        self.name, self.origin, self.period = name, origin, 1.0 / fps
        self.offset, self.last, self.jumps = 0.0, None, 0

    def time(self, frame: av.VideoFrame) -> float:
        raw = frame.time
        if raw is None:  # no timestamp: one period after the last frame
            t = 0.0 if self.last is None else self.last + self.period
        else:
            t = raw - self.origin + self.offset
            if self.last is None and t < 0:  # an edit list starting before zero
                self.offset, t = -t + self.offset, 0.0
            elif self.last is not None and t <= self.last:
                if self.jumps == 0:
                    log.warning(
                        "%s: timestamps go back at %.3f s; times continue from there",
                        self.name, self.last,
                    )  # fmt: skip
                self.jumps += 1
                self.offset += self.last + self.period - t
                t = self.last + self.period
        self.last = t
        return round(t, 6)
