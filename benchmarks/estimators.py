r"""What the plane's robust estimator costs, and what others would find, on real clips.

    python benchmarks/estimators.py                     # woman.mp4, DAVIS dog, motocross-bumps
    python benchmarks/estimators.py ../shared/data/davis/goat/JPEGImages

Every call of ``plane.ransac_homography`` a default ``detect`` makes on each
input (the plane and its tight refit ahead of judging, the refit without the
tracked movers, the layer order's second plane, the animate detector's
change of camera motion) is recorded with its points, velocities and
settings. The recorded calls are then run again, one OpenCV thread, by
OpenCV's RANSAC (what the tool uses) and by USAC variants: time per judged
frame, and how far each moves the share of the points its homography
explains within the call's threshold (mean change, and the share of calls
where it gains or loses more than 5 points). A gain in that share is not a
gain in detection: a plane that explains more of the points may have
absorbed a slow mover (docs/detectors.md, "The plane's estimator on hard
clips").
"""

from __future__ import annotations

import inspect
import sys
import time
from collections.abc import Callable
from pathlib import Path

import cv2
import numpy as np
from common import SHARED_DATA

from motiondetect.animate import continuation
from motiondetect.constraint_ray import layer_order, plane
from motiondetect.detection.detector import MotionDetector
from motiondetect.io.video import open_source

Call = tuple[np.ndarray, np.ndarray, float, int, float]  # points, velocity, px, draws, confidence
Estimator = Callable[[np.ndarray, np.ndarray, float, int, float], np.ndarray | None]


def recorded_calls(path: Path) -> tuple[list[Call], int]:
    """Every ``ransac_homography`` call of the default detector over ``path``, and its frames."""
    calls: list[Call] = []
    original = plane.ransac_homography
    signature = inspect.signature(original)  # its defaults, not restated here

    def recording(*args, **kwargs):
        bound = signature.bind(*args, **kwargs)
        bound.apply_defaults()
        points, velocity, threshold_px, draws, confidence = bound.args
        calls.append((points.copy(), velocity.copy(), threshold_px, draws, confidence))
        return original(*args, **kwargs)

    modules = (plane, layer_order, continuation)
    for module in modules:
        module.ransac_homography = recording
    try:
        detector, frames = MotionDetector(), 0
        with open_source(path) as source:
            for frame in source:
                detector.process(frame.image, frame.index, frame.time_s)
                frames += 1
    finally:
        for module in modules:
            module.ransac_homography = original
    return calls, frames


def usac(score: int, local: int) -> Estimator:
    """USAC with uniform samples, ``score``, local optimisation ``local``, least-squares polish."""

    def fit(points, velocity, threshold_px, draws, confidence):
        params = cv2.UsacParams()
        params.threshold, params.maxIterations, params.confidence = threshold_px, draws, confidence
        params.sampler, params.score = cv2.SAMPLING_UNIFORM, score
        params.loMethod, params.final_polisher = local, cv2.LSQ_POLISHER
        return cv2.findHomography(points, points - velocity, params)[0]

    return fit


def by_method(method: int) -> Estimator:
    """``cv2.findHomography`` by ``method`` (``cv2.RANSAC``, ``cv2.USAC_FAST``...)."""

    def fit(points, velocity, threshold_px, draws, confidence):
        return cv2.findHomography(
            points, points - velocity, method, threshold_px, maxIters=draws, confidence=confidence
        )[0]

    return fit


ESTIMATORS: dict[str, Estimator] = {
    "RANSAC (the tool)": by_method(cv2.RANSAC),
    "USAC_FAST": by_method(cv2.USAC_FAST),
    "MSAC, no local opt.": usac(cv2.SCORE_METHOD_MSAC, cv2.LOCAL_OPTIM_NULL),
    "MSAC, inner local opt.": usac(cv2.SCORE_METHOD_MSAC, cv2.LOCAL_OPTIM_INNER_LO),
}


def explained(call: Call, homography: np.ndarray | None) -> float:
    """Share of the call's points within its threshold of ``homography``."""
    points, velocity, threshold_px = call[:3]
    if homography is None:
        return 0.0
    return float((plane.plane_error(points, velocity, homography) < threshold_px).mean())


def compare(name: str, calls: list[Call], frames: int) -> None:
    print(f"{name}: {len(calls)} calls, {len(calls) / max(frames, 1):.1f} a judged frame")
    base = None
    for label, estimate in ESTIMATORS.items():
        start = time.perf_counter()
        found = [estimate(*call) for call in calls]
        ms = 1000 * (time.perf_counter() - start) / max(frames, 1)
        share = np.array([explained(c, h) for c, h in zip(calls, found, strict=True)])
        base = share if base is None else base
        change = share - base
        print(
            f"  {label:24s} {ms:6.2f} ms/frame  explained {share.mean():.3f}"
            f" (change {change.mean():+.4f}; >+0.05 on {np.mean(change > 0.05):.2f},"
            f" <-0.05 on {np.mean(change < -0.05):.2f} of calls)"
        )


def main() -> None:
    cv2.setNumThreads(1)
    inputs = [Path(p) for p in sys.argv[1:]] or [
        SHARED_DATA / "woman" / "woman.mp4",
        SHARED_DATA / "davis" / "dog" / "JPEGImages",
        SHARED_DATA / "davis" / "motocross-bumps" / "JPEGImages",
    ]
    for path in inputs:
        if not path.exists():
            print(f"{path}: not found, skipped")
            continue
        calls, frames = recorded_calls(path)
        compare(path.parent.name if path.name == "JPEGImages" else path.name, calls, frames)


if __name__ == "__main__":
    main()
