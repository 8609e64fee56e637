"""Synthetic scenes with exact ground truth, rendered once per test session."""

from __future__ import annotations

from functools import lru_cache

import cv2
import numpy as np

from motiondetect.detection.detector import MotionDetector
from motiondetect.tools.evaluate import Counts, score_frame
from motiondetect.tools.synth import CAMERA_CLASS, SynthConfig, render_frames


@lru_cache(maxsize=16)
def scene(
    camera: str, movers: tuple[str, ...] = (), frames: int = 24, supersample: int = 1, **kw
) -> tuple:
    """Rendered frames (small; no supersampling by default, to keep the suite
    fast). ``supersample=2`` renders edges anti-aliased, as a camera's pixels
    integrate light: without it, sharp edges move in whole-pixel jumps that
    the animate detector rightly sees as non-smooth motion."""
    config = SynthConfig(camera=camera, movers=movers, frames=frames, supersample=supersample, **kw)
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
    configs = [kw.pop(k) for k in ("stages", "constraint_ray", "animate") if k in kw]
    kw.setdefault("measure", "normal")
    md = MotionDetector(detector, *configs, persistence=persistence, **kw)
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


def object_hits(results, frames, mover: int = 1):
    """Per frame with the mover wholly in view: (frame index, region hit,
    pixel hit). A region hit is a reported region with at least 3 flagged
    cells on the mover; a pixel hit is >= 10 % of its pixels flagged (the
    ``evaluate`` object criterion)."""
    out = []
    for res, fr in zip(results, frames):
        obj = fr.movers == mover
        edge = obj[0].any() or obj[-1].any() or obj[:, 0].any() or obj[:, -1].any()
        if res.field is None or fr.index < 2 or obj.sum() < 50 or edge:
            continue
        cells = cv2.resize(obj.astype(np.float32), (64, 64), interpolation=cv2.INTER_AREA) > 0.5
        region_hit = any(cells[r.cells[:, 0], r.cells[:, 1]].sum() >= 3 for r in res.regions)
        flag = cv2.resize(
            res.flagged.astype(np.uint8), obj.shape[::-1], interpolation=cv2.INTER_NEAREST
        ).astype(bool)
        out.append((fr.index, region_hit, flag[obj].mean() >= 0.1))
    return out


def found_and_stray(md: MotionDetector, frames) -> tuple[int, int]:
    """Run ``md`` over rendered frames: (frames with a reported region on a
    mover, regions touching no mover pixel)."""
    found = stray = 0
    for fr in frames:
        res = md.process(fr.image, fr.index, fr.index / 30)
        mover = fr.mask == 255
        hits = [mover[y : y + h, x : x + w].any() for x, y, w, h in (r.bbox for r in res.regions)]
        found += any(hits)
        stray += hits.count(False)
    return found, stray


def near_reversal(index: int, period: int) -> bool:
    """Within 1.5 frames of an extreme of x = sin(2 pi t / period), where an
    ``animate`` mover reverses and its acceleration peaks."""
    return abs(index % (period / 2) - period / 4) <= 1.5
