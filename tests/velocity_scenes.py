"""Scenes with exact answers for the velocity path's tests: a real photograph
moved by exact warps, with a textured square pasted as a mover.
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
from skimage import data

from motiondetect.detection.detector import MotionDetector
from motiondetect.io.video import open_source, read_mask
from motiondetect.measurement.dense_flow import DenseFlow, DenseFlowConfig
from motiondetect.tools.evaluate import Counts, score_frame

W, H = 320, 240
PHOTO = cv2.cvtColor(data.astronaut(), cv2.COLOR_RGB2BGR)
PATCH = cv2.resize(cv2.cvtColor(data.coffee(), cv2.COLOR_RGB2BGR), (48, 48))


def background(dx: float, dy: float = 0.0, zoom: float = 1.0) -> np.ndarray:
    """The photograph seen by a camera moved by (dx, dy) px and zoomed about the centre."""
    c = np.array([256.0, 256.0])
    m = np.array([[zoom, 0, (1 - zoom) * c[0] - dx - 96], [0, zoom, (1 - zoom) * c[1] - dy - 136]])
    return cv2.warpAffine(PHOTO, m, (W, H), flags=cv2.INTER_CUBIC, borderMode=cv2.BORDER_REFLECT)


def paste(frame: np.ndarray, x: float, y: float) -> tuple[np.ndarray, np.ndarray]:
    """The patch at sub-pixel (x, y), and its 0/255 mask."""
    m = np.float32([[1, 0, x], [0, 1, y]])
    patch = cv2.warpAffine(PATCH, m, (W, H), flags=cv2.INTER_CUBIC)
    inside = cv2.warpAffine(np.ones((48, 48), np.float32), m, (W, H)) > 0.5
    out = frame.copy()
    out[inside] = patch[inside]
    return out, inside


def field_between(a: np.ndarray, b: np.ndarray):
    flow = DenseFlow(DenseFlowConfig(work_size=W))
    flow.process(a)
    return flow.process(b)


def pan_with_mover(path, frames=24, pan=2.0):
    """Frames of a panning camera with the patch at ``path(t)``; masks too."""
    out = []
    for t in range(frames):
        image, mask = paste(background(pan * t), *path(t))
        out.append((image, mask))
    return out


def mover_hits(md: MotionDetector, clip, warmup: int = 3) -> list[bool]:
    hits = []
    for t, (image, mask) in enumerate(clip):
        result = md.process(image, t, t / 30)
        if t >= warmup:
            flagged = result.input_mask(W, H) > 0
            hits.append(flagged[mask].mean() >= 0.5)
    return hits


def coverage(md: MotionDetector, clip, judged) -> tuple[list[float], list[int]]:
    """Run ``md`` over ``clip`` ((frame, mask) pairs, ``W`` x ``H``); on each
    frame ``judged(t, mask)`` picks: the share of the mover flagged, and the
    number of background pixels flagged."""
    found, background_px = [], []
    for t, (frame, mask) in enumerate(clip):
        flagged = md.process(frame, t, t / 30).input_mask(W, H) > 0
        if judged(t, mask):
            found.append(float(flagged[mask].mean()))
            background_px.append(int(flagged[~mask].sum()))
    return found, background_px


def animate_on_sample(name: str, *configs, detector: str = "animate") -> tuple[float, float]:
    """(false-alarm regions per frame, object recall) of ``detector`` (the
    animate detector alone unless named) on a sample video."""
    folder = Path(__file__).resolve().parents[1] / "sample_videos" / name
    md, counts = MotionDetector(detector, *configs), Counts()
    with open_source(folder / "video.mp4") as source:
        for frame in source:
            result = md.process(frame.image, frame.index, frame.time_s)
            if frame.index >= 2:
                truth = read_mask(folder / "truth" / f"{frame.index:06d}.png")
                counts.add(score_frame(result.input_mask(*truth.shape[::-1]), truth))
    m = counts.metrics()
    return m["false_alarm_regions_per_frame"], m["object_recall"]
