"""Shared helpers for the benchmark scripts (not part of the package)."""

from __future__ import annotations

import os
import resource
import tempfile
import time
from pathlib import Path

import cv2
import numpy as np
from skimage import data

#: The real clips: $MOTIONDETECT_DATA, else ../shared/data beside the checkout
#: (the same rule as tests/conftest.py).
SHARED_DATA = Path(
    os.environ.get("MOTIONDETECT_DATA") or Path(__file__).resolve().parents[2] / "shared" / "data"
)

#: Fresh synthetic scenes (``synth_set.py``): $MOTIONDETECT_SYNTH, else a
#: folder in the system's temporary directory (never the checkout).
SYNTH_SET = Path(
    os.environ.get("MOTIONDETECT_SYNTH") or Path(tempfile.gettempdir()) / "motiondetect-synth-set"
)


def single_thread() -> None:
    """One core: OpenCV and BLAS both limited to one thread."""
    os.environ["OMP_NUM_THREADS"] = "1"
    os.environ["OPENBLAS_NUM_THREADS"] = "1"
    cv2.setNumThreads(1)


def make_pan_clip(
    path: Path, size: tuple[int, int], frames: int, fps: float = 30.0, speed_px: float = 3.0
) -> Path:
    """A real photograph panned across at ``speed_px`` per frame, written as MPEG-4."""
    w, h = size
    photo = np.concatenate([data.astronaut(), data.astronaut()[:, ::-1]], axis=1)
    travel = min(speed_px * frames, 600.0)  # pans back and forth beyond this
    scale = max((h + 8) / photo.shape[0], (w + travel + 8) / photo.shape[1])
    big = cv2.resize(photo[..., ::-1], None, fx=scale, fy=scale, interpolation=cv2.INTER_CUBIC)
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), fps, (w, h))
    for i in range(frames):
        x = speed_px * i % (2 * travel) if travel > 0 else 0.0
        x = x if x <= travel else 2 * travel - x
        m = np.float32([[1, 0, -x], [0, 1, 0]])
        frame = cv2.warpAffine(big, m, (w, h), flags=cv2.INTER_LINEAR)
        writer.write(frame)
    writer.release()
    return path


def read_all(path: Path) -> list[np.ndarray]:
    cap = cv2.VideoCapture(str(path))
    frames = []
    while True:
        ok, f = cap.read()
        if not ok:
            break
        frames.append(f)
    cap.release()
    return frames


def timed(fn, repeat: int = 1) -> float:
    """Best wall time of ``repeat`` runs, seconds."""
    best = float("inf")
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t)
    return best


def decode_only(path: Path) -> int:
    cap = cv2.VideoCapture(str(path))
    n = 0
    while cap.read()[0]:  # read, not grab: decode-only includes the pixel conversion
        n += 1
    cap.release()
    return n


def on_frames(path: Path, apply) -> int:
    """``apply`` on each BGR frame of ``path`` as OpenCV decodes it; the frame count."""
    cap = cv2.VideoCapture(str(path))
    n = 0
    while True:
        ok, f = cap.read()
        if not ok:
            break
        apply(f)
        n += 1
    cap.release()
    return n


def on_grey(path: Path, process) -> int:
    """``process`` on each frame's grey as the tool reads it (PyAV); the frame count."""
    # Imported here: MOG2's whole-process timing imports this module, and
    # should not pay for loading the package.
    from motiondetect.io.video import open_source

    n = 0
    with open_source(path) as source:
        for frame in source:
            process(frame.grey)
            n += 1
    return n


def mog2_on(path: Path) -> int:
    """OpenCV MOG2 per frame, as DVR-Scan uses it (decode included)."""
    return on_frames(path, cv2.createBackgroundSubtractorMOG2().apply)


def peak_rss_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
