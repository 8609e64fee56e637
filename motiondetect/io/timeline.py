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


def draw_timeline(
    timeline: EventTimeline, events: list[dict], width: int = 1000, height: int = 260
) -> np.ndarray:
    """The timeline image (height, width, 3) uint8 BGR."""
    img = np.full((height, width, 3), 255, np.uint8)
    n = max(len(timeline), 1)
    left, right, top, plot_bottom, band_top = 50, width - 10, 20, height - 70, height - 55
    band_bottom = height - 40

    def x_of(i: float) -> int:
        return int(left + (right - left) * i / max(n - 1, 1))

    def y_of(v: float) -> int:
        return int(plot_bottom - (plot_bottom - top) * min(max(v, 0.0), 1.0))

    for ev in events:
        cv2.rectangle(
            img,
            (x_of(ev["start_frame"]), top),
            (x_of(ev["end_frame"]), plot_bottom),
            (200, 225, 255),
            -1,
        )
    cv2.rectangle(img, (left, top), (right, plot_bottom), (0, 0, 0), 1)
    for v in (0.25, 0.5, 0.75):
        cv2.line(img, (left, y_of(v)), (right, y_of(v)), (225, 225, 225), 1)
    for series, colour in ((timeline.scores, (30, 30, 200)), (timeline.fractions, (160, 90, 0))):
        if len(series) > 1:
            pts = np.array([(x_of(i), y_of(v)) for i, v in enumerate(series)], np.int32)
            cv2.polylines(img, [pts], False, colour, 1, cv2.LINE_AA)
    for i, c in enumerate(timeline.classes):
        x0, x1 = x_of(i - 0.5), x_of(i + 0.5)
        cv2.rectangle(
            img,
            (max(x0, left), band_top),
            (min(x1, right), band_bottom),
            CLASS_COLOURS.get(c, (0, 0, 0)),
            -1,
        )
    font = cv2.FONT_HERSHEY_SIMPLEX
    cv2.putText(img, "1", (30, top + 5), font, 0.4, (0, 0, 0), 1)
    cv2.putText(img, "0", (30, plot_bottom), font, 0.4, (0, 0, 0), 1)
    duration = timeline.times[-1] if timeline.times else 0.0
    cv2.putText(img, "0 s", (left, plot_bottom + 12), font, 0.4, (0, 0, 0), 1)
    cv2.putText(img, f"{duration:.1f} s", (right - 50, plot_bottom + 12), font, 0.4, (0, 0, 0), 1)
    cv2.putText(img, "score", (left + 5, top - 6), font, 0.45, (30, 30, 200), 1)
    cv2.putText(img, "moving fraction", (left + 60, top - 6), font, 0.45, (160, 90, 0), 1)
    cv2.putText(img, "events", (left + 200, top - 6), font, 0.45, (90, 150, 230), 1)
    x = left
    for cid in sorted(set(timeline.classes)):
        cv2.rectangle(img, (x, height - 25), (x + 12, height - 13), CLASS_COLOURS.get(cid), -1)
        label = CLASS_NAMES.get(cid, str(cid))
        cv2.putText(img, label, (x + 16, height - 14), font, 0.4, (0, 0, 0), 1)
        x += 24 + 8 * len(label)
    cv2.putText(img, "observer", (2, band_bottom - 3), font, 0.33, (0, 0, 0), 1)
    return img
