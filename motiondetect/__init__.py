"""motiondetect: independently moving objects seen by a moving observer.

An implementation of R. C. Nelson, "Qualitative Detection of Motion by a
Moving Observer" (CVPR 1991 / IJCV 7(1) 1991): the Maxvideo normal-flow stage
pipeline, the constraint ray filter (section 3) and the animate-motion
detector (section 4), on the paper's normal flow or on the full 2-D velocity.

The public API::

    import motiondetect
    for result in motiondetect.detect("clip.mp4"):
        print(result.index, [r.bbox for r in result.regions])

    detector = motiondetect.MotionDetector()        # numpy frames one at a time
    result = detector.process(frame, index, time_s)
"""

from __future__ import annotations

import logging
from collections.abc import Iterable, Iterator
from pathlib import Path

import numpy as np

__version__ = "0.2.0"

logging.getLogger("motiondetect").addHandler(logging.NullHandler())

from motiondetect.detection.base import Detector, DetectorOutput, registry  # noqa: E402
from motiondetect.detection.detector import FrameResult, MotionDetector  # noqa: E402
from motiondetect.detection.regions import Region  # noqa: E402
from motiondetect.detection.streaming import AUTO, frames_to_skip  # noqa: E402
from motiondetect.io.source import SourceFrame  # noqa: E402
from motiondetect.io.video import FrameSource, VideoError, VideoInfo, open_source  # noqa: E402

__all__ = [
    "Detector",
    "DetectorOutput",
    "FrameResult",
    "FrameSource",
    "MotionDetector",
    "Region",
    "VideoError",
    "VideoInfo",
    "__version__",
    "detect",
    "open_source",
    "registry",
]


def detect(
    source: str | Path | Iterable[np.ndarray],
    detector: str = "both",
    *configs,
    measure: str = "velocity",
    fps: float = 30.0,
    persistence: int | None = None,
    frame_skip: int | str = AUTO,
) -> Iterator[FrameResult]:
    """Detect independent motion in every frame of ``source``, lazily.

    Parameters
    ----------
    source : path or iterable of (H, W) or (H, W, 3) ndarray of uint8
        A video file or frames folder (opened with :func:`open_source`), or
        frames already in memory (BGR or grey).
    detector, configs, measure, persistence
        As for :class:`MotionDetector`.
    fps : float
        Frame rate of in-memory frames, for ``time_s``.
    frame_skip : int or "auto"
        Judge every (n+1)-th frame only; the others carry its result,
        marked ``held_from`` (:meth:`MotionDetector.stream`). "auto": one
        judged frame about every 1/30 s, from the frame rate
        (:func:`~motiondetect.detection.streaming.auto_frame_skip`: 1 at
        60 frames/s, 0 below 45).

    Yields
    ------
    FrameResult
        One per frame, in order; memory stays flat in the video's length.
    """
    md = MotionDetector(detector, *configs, measure=measure, persistence=persistence)
    if isinstance(source, (str, Path)):
        with open_source(source) as frames:
            for _, result in md.stream(frames, frames_to_skip(frame_skip, frames.info.fps)):
                yield result
        return
    in_memory = (SourceFrame(i, i / fps, image) for i, image in enumerate(source))
    for _, result in md.stream(in_memory, frames_to_skip(frame_skip, fps)):
        yield result
