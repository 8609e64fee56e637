"""Synthetic scenes with exact ground truth, rendered once per test session."""

from __future__ import annotations

from functools import lru_cache

import cv2
import numpy as np

from motiondetect.detection import MotionDetector
from motiondetect.evaluate import Counts, score_frame
from motiondetect.synth import CAMERA_CLASS, SynthConfig, render_frames


@lru_cache(maxsize=32)
def scene(camera: str, movers: tuple[str, ...] = (), frames: int = 24, **kw) -> tuple:
    """Rendered frames (small, no supersampling, to keep the suite fast)."""
    config = SynthConfig(camera=camera, movers=movers, frames=frames, supersample=1, **kw)
    return tuple(render_frames(config))


def to_input_mask(flagged: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    h, w = shape
    return cv2.resize(flagged.astype(np.uint8) * 255, (w, h), interpolation=cv2.INTER_NEAREST)


def run_detector(
    frames, detector: str = "constraint-ray", warmup: int = 2, persistence: int = 1, **kw
):
    """Score a detector on rendered frames: (counts, classes per frame, results).

    ``persistence=1`` measures the detector itself, without the temporal filter.
    """
    md = MotionDetector(detector, persistence=persistence, **kw)
    counts, classes, results = Counts(), [], []
    for fr in frames:
        res = md.process(fr.image, fr.index, fr.index / 30.0)
        results.append(res)
        if fr.index < warmup:
            continue
        classes.append(res.observer.class_id if res.observer else None)
        counts.add(score_frame(to_input_mask(res.flagged, fr.mask.shape), fr.mask))
    return counts, classes, results


def class_accuracy(camera: str, classes: list) -> float:
    want = CAMERA_CLASS[camera]
    family = {2: (2, 3), 3: (2, 3)}.get(want, (want,))
    return float(np.mean([c in family for c in classes]))
