"""Motion events: contiguous runs of frames with detections.

A run of active frames becomes an event when, after bridging gaps of at most
``merge_gap`` frames, it holds at least ``min_frames`` active frames; it is then padded
by ``pad`` frames on each side (clipped to the video) and events that
overlap after padding are merged.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def timecode(seconds: float) -> str:
    """``HH:MM:SS.mmm``."""
    ms = int(round(max(seconds, 0.0) * 1000))
    h, rest = divmod(ms, 3_600_000)
    m, rest = divmod(rest, 60_000)
    s, ms = divmod(rest, 1000)
    return f"{h:02d}:{m:02d}:{s:02d}.{ms:03d}"


@dataclass(frozen=True)
class EventRules:
    min_frames: int = 3
    merge_gap: int = 5
    pad: int = 5


def find_runs(active: np.ndarray, rules: EventRules) -> list[tuple[int, int]]:
    """(start, end) frame ranges, inclusive, of the events in ``active``."""
    idx = np.flatnonzero(active)
    if idx.size == 0:
        return []
    runs = []
    start = prev = int(idx[0])
    for i in idx[1:]:
        i = int(i)
        if i - prev - 1 > rules.merge_gap:
            runs.append((start, prev))
            start = i
        prev = i
    runs.append((start, prev))
    # The minimum length counts frames with motion, not the bridged span.
    runs = [(a, b) for a, b in runs if int(active[a : b + 1].sum()) >= rules.min_frames]
    last = len(active) - 1
    padded: list[tuple[int, int]] = []
    for a, b in runs:
        a, b = max(0, a - rules.pad), min(last, b + rules.pad)
        if padded and a <= padded[-1][1] + 1:
            padded[-1] = (padded[-1][0], max(b, padded[-1][1]))
        else:
            padded.append((a, b))
    return padded


class EventTimeline:
    """Per-frame activity, kept small (a few numbers per frame)."""

    def __init__(self) -> None:
        self.times: list[float] = []
        self.scores: list[float] = []
        self.fractions: list[float] = []
        self.classes: list[int] = []
        self.detectors: list[frozenset] = []
        self.boxes: list[tuple[int, int, int, int] | None] = []
        self.indices: list[int] = []  # source frame index of each entry

    def add(
        self, time_s: float, score: float, fraction: float, class_id: int, detections: list[dict],
        index: int | None = None,
    ) -> None:  # fmt: skip
        """One frame; ``index`` is its source frame index (default: its position)."""
        self.indices.append(len(self.indices) if index is None else index)
        self.times.append(time_s)
        self.scores.append(score)
        self.fractions.append(fraction)
        self.classes.append(class_id)
        self.detectors.append(frozenset(d for det in detections for d in det["detectors"]))
        if detections:
            x0 = min(d["bbox"][0] for d in detections)
            y0 = min(d["bbox"][1] for d in detections)
            x1 = max(d["bbox"][0] + d["bbox"][2] for d in detections)
            y1 = max(d["bbox"][1] + d["bbox"][3] for d in detections)
            self.boxes.append((x0, y0, x1, y1))
        else:
            self.boxes.append(None)

    def __len__(self) -> int:
        return len(self.times)

    def events(self, rules: EventRules, fps: float) -> list[dict]:
        active = np.array([b is not None for b in self.boxes], bool)
        out = []
        for k, (a, b) in enumerate(find_runs(active, rules), start=1):
            boxes = [self.boxes[i] for i in range(a, b + 1) if self.boxes[i] is not None]
            x0, y0 = min(bx[0] for bx in boxes), min(bx[1] for bx in boxes)
            x1, y1 = max(bx[2] for bx in boxes), max(bx[3] for bx in boxes)
            start_s = self.times[a]
            end_s = self.times[b] + 1.0 / fps
            found = sorted(set().union(*self.detectors[a : b + 1]))
            peak = a + int(np.argmax(self.scores[a : b + 1]))
            out.append(
                {
                    "event": k,
                    "start_frame": self.indices[a],
                    "end_frame": self.indices[b],
                    "peak_frame": self.indices[peak],
                    "start_s": round(start_s, 4),
                    "end_s": round(end_s, 4),
                    "start_timecode": timecode(start_s),
                    "end_timecode": timecode(end_s),
                    "duration_s": round(end_s - start_s, 4),
                    "peak_score": round(self.scores[peak], 4),
                    "detectors": found,
                    "bbox": [x0, y0, x1 - x0, y1 - y0],
                }
            )
        return out
