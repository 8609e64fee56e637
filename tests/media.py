"""Video files the PyAV tests write themselves, through FFmpeg's encoders."""

from __future__ import annotations

import struct
from fractions import Fraction
from pathlib import Path

import av
import numpy as np


def encode(
    path: Path,
    frames,
    codec: str = "libx264",
    *,
    fmt: str | None = None,
    rate: int | Fraction = 30,
    options: dict | None = None,
    time_base: Fraction | None = None,
    pts_step: int | None = None,
    stream=None,
    container_options: dict | None = None,
    pix_fmt: str = "yuv420p",
) -> Path:
    """Encode BGR ``frames``; ``pts_step`` sets each frame's pts explicitly
    (in ``time_base``), as a camera or muxer with its own clock would."""
    h, w = frames[0].shape[:2]
    target = stream if stream is not None else str(path)
    with av.open(target, "w", format=fmt, options=container_options or {}) as out:
        s = out.add_stream(codec, rate=rate, options=options or {})
        s.width, s.height, s.pix_fmt = w, h, pix_fmt
        if time_base is not None:
            s.time_base = time_base
        for i, image in enumerate(frames):
            frame = av.VideoFrame.from_ndarray(np.ascontiguousarray(image), format="bgr24")
            if pts_step is not None:
                frame.pts, frame.time_base = i * pts_step, s.time_base
            out.mux(s.encode(frame))
        out.mux(s.encode(None))
    return path


def has_encoder(name: str) -> bool:
    return name in av.codecs_available


def corrupt(path: Path, start_fraction: float, end_fraction: float, keep: int = 48) -> Path:
    """Overwrite bytes from ``start_fraction`` to ``end_fraction`` of the file
    (never its first ``keep`` bytes) with seeded noise."""
    data = bytearray(path.read_bytes())
    start, end = max(keep, int(len(data) * start_fraction)), int(len(data) * end_fraction)
    data[start:end] = np.random.default_rng(0).integers(0, 256, end - start, np.uint8).tobytes()
    path.write_bytes(bytes(data))
    return path


def stream_info(path: Path) -> dict:
    """Codec, pixel format and decoded frame count of a file's video stream."""
    with av.open(str(path)) as container:
        stream = container.streams.video[0]
        count = sum(1 for _ in container.decode(stream))
        return {
            "codec": stream.codec_context.name,
            "pix_fmt": stream.codec_context.pix_fmt,
            "frames": count,
            "duration_s": float(container.duration or 0) / av.time_base,
        }


def pts_times(path: Path) -> list[float]:
    """Each frame's presentation time in seconds, from the stream's start."""
    with av.open(str(path)) as container:
        stream = container.streams.video[0]
        start = float((stream.start_time or 0) * stream.time_base)
        return [frame.time - start for frame in container.decode(stream)]


def turned_quarter(path: Path, out: Path) -> Path:
    """A copy of the MP4 at ``path`` whose track header asks players to turn
    it a quarter turn (a 90-degree display matrix, as phones write it)."""
    data = bytearray(path.read_bytes())
    box = data.find(b"tkhd") - 4
    version = data[box + 8]
    matrix = box + 8 + 4 + (20 if version == 0 else 32) + 8 + 8
    assert struct.unpack(">9i", data[matrix : matrix + 36])[0] == 0x00010000  # identity
    data[matrix : matrix + 36] = struct.pack(
        ">9i", 0, 0x00010000, 0, -0x00010000, 0, 0, 0, 0, 0x40000000
    )
    out.write_bytes(bytes(data))
    return out
