"""Each object's life in one row: when it was seen, where it went, how strongly it moved.

``detections.csv`` lists every box of every frame; a user asking "what moved
in this video, and when?" wants one line per mover. :class:`TrackTable` sums
the per-frame detections by their ``track`` id as they come, one small record
a track (memory grows with the number of movers, not the video's length),
and gives ``tracks.csv``'s rows (:func:`~motiondetect.io.report.write_tracks_csv`).
Detections without a track (the normal-flow path keeps none) are not counted.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from motiondetect.detection.events import timecode


@dataclass
class _Life:
    track: int
    start_frame: int
    start_s: float
    start_box: tuple[int, int, int, int]
    end_frame: int = 0
    end_s: float = 0.0
    end_box: tuple[int, int, int, int] = (0, 0, 0, 0)
    frames: int = 0
    peak_frame: int = 0
    peak_score: float = -1.0
    detectors: set[str] = field(default_factory=set)
    reach: list[int] = field(init=False)  # x0, y0, x1, y1 around all its boxes
    own: list[float] = field(default_factory=lambda: [0.0, 0.0, 0])  # own velocities summed, count

    def __post_init__(self) -> None:
        x, y, w, h = self.start_box
        self.reach = [x, y, x + w, y + h]

    def add(self, frame: int, time_s: float, box: tuple[int, int, int, int], detection: dict):
        x, y, w, h = box
        self.end_frame, self.end_s, self.end_box = frame, time_s, box
        self.frames += 1
        if detection["score"] > self.peak_score:
            self.peak_frame, self.peak_score = frame, float(detection["score"])
        self.detectors.update(detection["detectors"])
        r = self.reach
        r[:] = [min(r[0], x), min(r[1], y), max(r[2], x + w), max(r[3], y + h)]
        own = detection.get("own_velocity_px_s")
        if own is not None and not detection.get("held"):  # a held one repeats its last
            self.own[:] = [self.own[0] + own[0], self.own[1] + own[1], self.own[2] + 1]

    def mean_own(self) -> tuple[float, float] | tuple[str, str]:
        """Its mean own velocity over the frames it was found on, px/s; empty without one."""
        vx, vy, count = self.own
        return (round(vx / count, 1), round(vy / count, 1)) if count else ("", "")


def _centre(box: tuple[int, int, int, int]) -> tuple[float, float]:
    x, y, w, h = box
    return round(x + w / 2, 1), round(y + h / 2, 1)


class TrackTable:
    """Per-track totals of one input, fed frame by frame (:meth:`add`)."""

    def __init__(self) -> None:
        self._lives: dict[int, _Life] = {}

    def add(self, frame: int, time_s: float, detections: list[dict]) -> None:
        """One frame's detections (``frames.jsonl``'s records: ``bbox``,
        ``score``, ``detectors`` and ``track``), in frame order."""
        for detection in detections:
            track = detection.get("track")
            if track is None:
                continue
            box = tuple(int(v) for v in detection["bbox"])
            life = self._lives.get(track)
            if life is None:
                life = self._lives[track] = _Life(track, frame, time_s, box)
            life.add(frame, time_s, box, detection)

    def __len__(self) -> int:
        return len(self._lives)

    def rows(self) -> list[dict]:
        """One dict per track, by first frame then id: its first and last
        frame and time, the frames it was detected on, its peak score and
        frame, the detectors that flagged it, its box centre on the first
        and last frame, the box around all its boxes (input px), and its
        mean own velocity (input px/s; empty where none was measured)."""
        rows = []
        for life in sorted(self._lives.values(), key=lambda t: (t.start_frame, t.track)):
            x0, y0, x1, y1 = life.reach
            (sx, sy), (ex, ey) = _centre(life.start_box), _centre(life.end_box)
            own_x, own_y = life.mean_own()
            rows.append(
                {
                    "track": life.track,
                    "start_frame": life.start_frame,
                    "end_frame": life.end_frame,
                    "start_s": life.start_s,
                    "end_s": life.end_s,
                    "start_timecode": timecode(life.start_s),
                    "end_timecode": timecode(life.end_s),
                    "duration_s": life.end_s - life.start_s,
                    "frames": life.frames,
                    "peak_frame": life.peak_frame,
                    "peak_score": life.peak_score,
                    "detectors": sorted(life.detectors),
                    "start_cx": sx,
                    "start_cy": sy,
                    "end_cx": ex,
                    "end_cy": ey,
                    "bbox": [x0, y0, x1 - x0, y1 - y0],
                    "own_vx_px_s": own_x,
                    "own_vy_px_s": own_y,
                }
            )
        return rows
