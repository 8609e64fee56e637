"""timeline.png: score over time, events shaded, observer class as a band.

Drawn with OpenCV, which the tool already needs, so that no plotting
library is required for a PNG of lines and rectangles.
"""

from __future__ import annotations

import cv2
import numpy as np

from motiondetect.constraint_ray.observer_motion import CLASS_NAMES
from motiondetect.detection.events import EventTimeline
from motiondetect.io.colours import CLASS_COLOURS

_STEPS_S = (0.1, 0.2, 0.5, 1, 2, 5, 10, 15, 30, 60, 120, 300, 600, 900, 1800, 3600, 7200)


def tick_step(duration_s: float, most: int = 10) -> float:
    """The smallest round step (s) giving at most ``most`` ticks over ``duration_s``."""
    return next((s for s in _STEPS_S if duration_s / s <= most), _STEPS_S[-1])


def tick_label(t: float, step: float) -> str:
    """``12.5 s`` under a minute; ``m:ss`` or ``h:mm:ss`` beyond."""
    if t < 60 and step < 60:
        return f"{t:g} s" if step < 1 else f"{t:.0f} s"
    h, rem = divmod(int(round(t)), 3600)
    m, s = divmod(rem, 60)
    return f"{h}:{m:02d}:{s:02d}" if h else f"{m}:{s:02d}"


class _Frame:
    """The plot's geometry: time to x, value to y."""

    def __init__(self, width: int, height: int, t0: float, t1: float) -> None:
        self.left, self.right, self.top = 50, width - 10, 20
        self.bottom, self.band = height - 70, (height - 55, height - 40)
        self.t0, self.span = t0, max(t1 - t0, 1e-6)

    def x(self, t: float) -> int:
        return int(self.left + (self.right - self.left) * (t - self.t0) / self.span)

    def y(self, v: float) -> int:
        return int(self.bottom - (self.bottom - self.top) * min(max(v, 0.0), 1.0))


def _draw_axes(img: np.ndarray, f: _Frame, font) -> None:
    cv2.rectangle(img, (f.left, f.top), (f.right, f.bottom), (0, 0, 0), 1)
    for v in (0.25, 0.5, 0.75):
        cv2.line(img, (f.left, f.y(v)), (f.right, f.y(v)), (225, 225, 225), 1)
    cv2.putText(img, "1", (30, f.top + 5), font, 0.4, (0, 0, 0), 1)
    cv2.putText(img, "0", (30, f.bottom), font, 0.4, (0, 0, 0), 1)
    step = tick_step(f.span)
    first = np.ceil(f.t0 / step - 1e-9) * step
    for t in np.arange(first, f.t0 + f.span + 1e-9, step):
        x = f.x(t)
        cv2.line(img, (x, f.bottom), (x, f.bottom + 4), (0, 0, 0), 1)
        label = tick_label(round(float(t), 3), step)
        at = max(x - 4 * len(label), f.left)
        cv2.putText(img, label, (at, f.bottom + 15), font, 0.35, (0, 0, 0), 1)
    cv2.putText(img, "score", (f.left + 5, f.top - 6), font, 0.45, (30, 30, 200), 1)
    cv2.putText(img, "moving fraction", (f.left + 60, f.top - 6), font, 0.45, (160, 90, 0), 1)
    cv2.putText(img, "events", (f.left + 200, f.top - 6), font, 0.45, (90, 150, 230), 1)


def _draw_classes(img: np.ndarray, f: _Frame, timeline: EventTimeline, font) -> None:
    times, height = timeline.times, img.shape[0]
    half = 0.5 * f.span / max(len(times) - 1, 1)
    for t, c in zip(times, timeline.classes):
        x0, x1 = max(f.x(t - half), f.left), min(f.x(t + half), f.right)
        cv2.rectangle(img, (x0, f.band[0]), (x1, f.band[1]), CLASS_COLOURS.get(c, (0, 0, 0)), -1)
    cv2.putText(img, "observer", (2, f.band[1] - 3), font, 0.33, (0, 0, 0), 1)
    x = f.left
    for cid in sorted(set(timeline.classes)):
        cv2.rectangle(img, (x, height - 25), (x + 12, height - 13), CLASS_COLOURS.get(cid), -1)
        label = CLASS_NAMES.get(cid, str(cid))
        cv2.putText(img, label, (x + 16, height - 14), font, 0.4, (0, 0, 0), 1)
        x += 24 + 8 * len(label)


def draw_timeline(
    timeline: EventTimeline, events: list[dict], width: int = 1000, height: int = 260
) -> np.ndarray:
    """The timeline image (height, width, 3) uint8 BGR, with round time ticks."""
    img = np.full((height, width, 3), 255, np.uint8)
    times = timeline.times or [0.0]
    f = _Frame(width, height, times[0], times[-1])
    for ev in events:
        x0, x1 = f.x(ev["start_s"]), min(f.x(ev["end_s"]), f.right)
        cv2.rectangle(img, (x0, f.top), (x1, f.bottom), (200, 225, 255), -1)
    font = cv2.FONT_HERSHEY_SIMPLEX
    _draw_axes(img, f, font)
    for series, colour in ((timeline.scores, (30, 30, 200)), (timeline.fractions, (160, 90, 0))):
        if len(series) > 1:
            pts = np.array([(f.x(t), f.y(v)) for t, v in zip(times, series)], np.int32)
            cv2.polylines(img, [pts], False, colour, 1, cv2.LINE_AA)
    _draw_classes(img, f, timeline, font)
    return img
