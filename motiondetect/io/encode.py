"""Video out through PyAV: the annotated video and event clips.

The format follows the file's suffix:

========  ==============================  ====================================
suffix    codec                           why
========  ==============================  ====================================
``.mp4``  H.264 (libx264), ``yuv420p``,   plays in every browser and player;
          ``+faststart``                  the default
``.webm`` VP8 (libvpx), realtime          for tools that want WebM
``.mkv``  FFV1, lossless                  for frame-exact review
========  ==============================  ====================================

The x264 preset and quality were chosen by measurement
(``benchmarks/throughput.py --encode``; ``docs/performance.md``). Frames
are written to a hidden temporary file, renamed on success, so a crash
never leaves a half video under the final name. Odd frame sizes are padded
by one edge pixel, since 4:2:0 needs even sizes; frames reach the encoder
already in ``yuv420p`` (:func:`~motiondetect.io.colour.bgr_to_frame`).
"""

from __future__ import annotations

import os
import queue
import threading
from fractions import Fraction
from pathlib import Path

import av
import cv2
import numpy as np

from motiondetect.io.colour import bgr_to_frame
from motiondetect.io.files import temporary_path
from motiondetect.io.source import VideoError

TIME_BASE = Fraction(1, 90000)
FORMATS = {
    ".mp4": ("libx264", "yuv420p", {"preset": "veryfast", "crf": "23"}, {"movflags": "+faststart"}),
    ".webm": (
        "libvpx", "yuv420p",
        {"deadline": "realtime", "cpu-used": "8", "crf": "10", "b": "2M"}, {},
    ),
    ".mkv": ("ffv1", "yuv420p", {}, {}),
}  # fmt: skip


class VideoSink:
    """Write frames to a video atomically.

    Parameters
    ----------
    path : str or Path
        The final name; its suffix picks the format (table above).
    fps : float
        Nominal frame rate, frames/second; used when :meth:`write` is given
        no time.
    size : (width, height)
        Size of the frames that will be written, pixels.
    """

    def __init__(self, path: str | Path, fps: float, size: tuple[int, int]) -> None:
        self.path = Path(path)
        suffix = self.path.suffix.lower()
        if suffix not in FORMATS:
            raise VideoError(f"{self.path}: cannot write video as {suffix or 'no suffix'}")
        codec, pix_fmt, options, muxer = FORMATS[suffix]
        self._tmp = temporary_path(self.path)
        self.size = size
        self._even = (size[0] + size[0] % 2, size[1] + size[1] % 2)
        rate = Fraction(fps).limit_denominator(1001) if fps > 0 else Fraction(30)
        try:
            self._out = av.open(str(self._tmp), "w", format=suffix[1:].replace("mkv", "matroska"),
                                options=muxer)  # fmt: skip
            stream = self._out.add_stream(codec, rate=rate, options=options)
        except (av.error.FFmpegError, ValueError) as exc:
            self._tmp.unlink(missing_ok=True)
            raise VideoError(f"{self.path}: cannot open a {codec} writer: {exc}") from None
        stream.width, stream.height, stream.pix_fmt = *self._even, pix_fmt
        stream.time_base = TIME_BASE
        stream.codec_context.time_base = TIME_BASE
        self._stream, self._period = stream, 1.0 / float(rate)
        self.frames = 0
        self._last_pts = -1

    def write(self, frame: np.ndarray, time_s: float | None = None) -> None:
        """Append one BGR (or grey) uint8 frame shown at ``time_s`` seconds."""
        if frame.ndim == 2:
            frame = cv2.cvtColor(frame, cv2.COLOR_GRAY2BGR)
        if frame.shape[1::-1] != self._even:
            frame = cv2.copyMakeBorder(
                frame, 0, self._even[1] - frame.shape[0], 0, self._even[0] - frame.shape[1],
                cv2.BORDER_REPLICATE,
            )  # fmt: skip
        out = bgr_to_frame(np.ascontiguousarray(frame))
        t = self.frames * self._period if time_s is None else time_s
        pts = max(int(round(t / TIME_BASE)), self._last_pts + 1)  # strictly increasing
        out.pts, out.time_base, self._last_pts = pts, TIME_BASE, pts
        self._out.mux(self._stream.encode(out))
        self.frames += 1

    def close(self, keep: bool = True) -> None:
        """Finish the file and give it its name (``keep``), or remove it."""
        try:
            if keep and self.frames:
                self._out.mux(self._stream.encode(None))
        finally:
            self._out.close()
        if keep and self.frames and self._tmp.exists():
            os.replace(self._tmp, self.path)
            return
        self._tmp.unlink(missing_ok=True)
        if keep:
            raise VideoError(f"{self.path}: no frames were written")

    def __enter__(self) -> VideoSink:
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        self.close(keep=exc_type is None)


class BackgroundSink:
    """Draw and encode on a second thread, while the next frame is detected.

    ``draw(item)`` turns what :meth:`put` is given into a frame; a bounded
    queue keeps memory flat (at most ``depth`` frames wait). An error on
    the thread is raised by the next :meth:`put` or by :meth:`close`.
    """

    def __init__(self, sink: VideoSink, draw, depth: int = 4) -> None:
        self.sink, self.draw = sink, draw
        self._queue: queue.Queue = queue.Queue(maxsize=depth)
        self._error: BaseException | None = None
        self._thread = threading.Thread(target=self._run, name="video-writer", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while (item := self._queue.get()) is not None:
            if self._error is None:
                try:
                    frame, time_s = self.draw(item)
                    self.sink.write(frame, time_s)
                except BaseException as exc:  # handed to the caller's thread
                    self._error = exc

    def put(self, item) -> None:
        if self._error is not None:
            raise self._error
        self._queue.put(item)

    def close(self, keep: bool = True) -> None:
        self._queue.put(None)
        self._thread.join()
        self.sink.close(keep=keep and self._error is None)
        if keep and self._error is not None:
            raise self._error
