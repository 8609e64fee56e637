"""Frames to judge, with the frames skipped before them, measured in order
or one ahead on a second thread (:meth:`.detector.MotionDetector.stream`)."""

from __future__ import annotations

import math
import threading
from collections.abc import Iterable, Iterator
from concurrent.futures import ThreadPoolExecutor
from typing import TypeVar

F = TypeVar("F")

#: ``frame_skip`` that judges one frame about every 1/30 s (:func:`auto_frame_skip`).
AUTO = "auto"
#: Frame rate the detectors' tolerances were measured at: the shared clips run
#: at 20-30 frames/s (docs/detectors.md, "Judged at about 30 frames a second").
REFERENCE_FPS = 30.0
#: Most frames ``auto`` skips: one judged frame in 8, as at 240 frames/s (a
#: phone's slow motion). Timestamps that claim more are likelier wrong than
#: the camera that fast, and a file timed wrongly then still gets judged.
MAX_AUTO_SKIP = 7


def auto_frame_skip(fps: float | None) -> int:
    """Frames to skip after each judged one so that judged frames come about
    :data:`REFERENCE_FPS` apart: 0 below 45 frames/s, 1 from 45 to 75 (50, 60), 3 at 120.

    A camera at 60 frames/s moves half as far between frames as at 30, and a
    slow mover's motion then sinks into the measurement's noise; judging
    every 2nd frame gives the detectors the motion they were measured on,
    for half the work. ``fps`` unknown or not positive: 0; at most
    :data:`MAX_AUTO_SKIP`.
    """
    if fps is None or not math.isfinite(fps) or fps <= 0:
        return 0
    return min(MAX_AUTO_SKIP, max(0, int(fps / REFERENCE_FPS + 0.5) - 1))


def frames_to_skip(frame_skip: int | str, fps: float | None) -> int:
    """``frame_skip`` as a number of frames: :data:`AUTO` resolved at ``fps``
    (:func:`auto_frame_skip`), a number as it is."""
    return auto_frame_skip(fps) if frame_skip == AUTO else int(frame_skip)


def judged_groups(frames: Iterable[F], every: int) -> Iterator[tuple[list[F], F | None]]:
    """(the skipped frames before a frame to judge, that frame): every
    ``every``-th frame is judged, from the first; the last group's frame is
    None when the input ends on skipped frames."""
    held: list[F] = []
    for n, frame in enumerate(frames):
        if n % every:
            held.append(frame)
        else:
            yield held, frame
            held = []
    if held:
        yield held, None


def measured(group: tuple, measure) -> tuple:
    """``(held, frame, measure(picture))`` for one of :func:`judged_groups`,
    the picture :func:`measured_picture`."""
    held, frame = group
    return held, frame, (None if frame is None else measure(measured_picture(frame)))


def measured_picture(frame) -> object:
    """What the measurement reads of a frame: its ``grey``, else its ``image``."""
    grey = getattr(frame, "grey", None)
    return frame.image if grey is None else grey


def measured_ahead(groups: Iterable[tuple], measure, prepare=None) -> Iterator[tuple]:
    """:func:`measured` per group, each group read and measured on a second
    thread while the one before is used.

    ``prepare(measurement, stop)``, returning the measurement with more
    computed (work its user would otherwise do), runs on that thread too,
    but only while the user is still busy with the group before: when the
    user already waits, the measurement goes to it at once and the second
    thread goes on to the next group; ``stop()`` tells ``prepare`` that the
    user has begun to wait, so that it can stop between steps. So the work
    falls to whichever thread has time for it, the measuring one or the one
    using it.
    """
    items = iter(groups)
    waiting = threading.Event()  # the user waits for the next group

    def read_and_measure():
        got = next(items, None)
        if got is None:
            return None
        held, frame, flow = measured(got, measure)
        if prepare is not None and not waiting.is_set():
            flow = prepare(flow, waiting.is_set)
        return held, frame, flow

    with ThreadPoolExecutor(1, thread_name_prefix="measure") as ahead:
        pending = ahead.submit(read_and_measure)
        while True:
            waiting.set()
            got = pending.result()
            waiting.clear()
            if got is None:
                break
            pending = ahead.submit(read_and_measure)
            yield got
