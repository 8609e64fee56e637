"""Report writers: JSON lines, CSV (detections, events, tracks), the summary. They take open files.

``frames.jsonl`` is flushed line by line, so a crash loses no finished frame;
the summary is written through :func:`atomic_text`, so it either exists
complete or not at all (its presence marks an input as finished).
"""

from __future__ import annotations

import contextlib
import csv
import json
import os
from collections.abc import Iterator
from pathlib import Path
from typing import TextIO

SCHEMA_VERSION = "1.0"

# ``track``: the object's track id (empty where the detector keeps no tracks);
# ``held``: 1 where the track was not found on the frame and is reported where
# its own motion puts it (docs/detectors.md, "Held tracks"), else empty;
# ``vx_px_s``, ``vy_px_s``: its image velocity, and ``own_vx_px_s``,
# ``own_vy_px_s``: that less the camera's, input px per second (empty where
# not measured: the paper's normal-flow path).
DETECTION_COLUMNS = [
    "frame", "time_s", "detectors", "x", "y", "w", "h", "area_px", "score", "track", "held",
    "vx_px_s", "vy_px_s", "own_vx_px_s", "own_vy_px_s",
]  # fmt: skip
EVENT_COLUMNS = [
    "event",
    "start_frame",
    "end_frame",
    "start_s",
    "end_s",
    "start_timecode",
    "end_timecode",
    "duration_s",
    "peak_frame",
    "peak_score",
    "detectors",
    "x",
    "y",
    "w",
    "h",
]

# One row per track (an object kept across frames): tracks.csv; ``own_vx_px_s``,
# ``own_vy_px_s``: its mean own velocity over the frames it was found on.
TRACK_COLUMNS = [
    "track", "start_frame", "end_frame", "start_s", "end_s", "start_timecode",
    "end_timecode", "duration_s", "frames", "peak_frame", "peak_score", "detectors",
    "start_cx", "start_cy", "end_cx", "end_cy", "x", "y", "w", "h", "own_vx_px_s", "own_vy_px_s",
]  # fmt: skip


@contextlib.contextmanager
def atomic_text(path: str | Path) -> Iterator[TextIO]:
    """Open ``path`` for writing through a temporary file renamed on success.

    On an exception the temporary file is removed and ``path`` is untouched.
    """
    path = Path(path)
    tmp = path.with_name(f".{path.name}.part{os.getpid()}")
    try:
        with open(tmp, "w", encoding="utf-8", newline="") as fp:
            yield fp
            fp.flush()
            os.fsync(fp.fileno())
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()


class FramesJsonlWriter:
    """One JSON object per frame, flushed as it goes."""

    def __init__(self, fp: TextIO) -> None:
        self.fp = fp

    def append(self, record: dict) -> None:
        self.fp.write(json.dumps(record, separators=(",", ":"), allow_nan=False) + "\n")
        self.fp.flush()


class DetectionsCsvWriter:
    """One row per detection, with a header."""

    def __init__(self, fp: TextIO) -> None:
        self.fp = fp
        self._csv = csv.writer(fp, lineterminator="\n")
        self._csv.writerow(DETECTION_COLUMNS)

    def append(self, frame: int, time_s: float, detection: dict) -> None:
        x, y, w, h = detection["bbox"]
        self._csv.writerow(
            [
                frame,
                f"{time_s:.4f}",
                "+".join(detection["detectors"]),
                x,
                y,
                w,
                h,
                detection["area_px"],
                f"{detection['score']:.4f}",
                detection.get("track", ""),
                1 if detection.get("held") else "",
                *detection.get("velocity_px_s", ("", "")),
                *detection.get("own_velocity_px_s", ("", "")),
            ]
        )

    def flush(self) -> None:
        """Called once per frame, after its rows."""
        self.fp.flush()


def write_events_csv(fp: TextIO, events: list[dict], *, with_input: bool = False) -> None:
    """Events as CSV; ``with_input`` adds a leading ``input`` column from ``ev["input"]``."""
    writer = csv.writer(fp, lineterminator="\n")
    writer.writerow((["input"] if with_input else []) + EVENT_COLUMNS)
    for ev in events:
        x, y, w, h = ev["bbox"]
        writer.writerow(
            ([ev["input"]] if with_input else [])
            + [
                ev["event"],
                ev["start_frame"],
                ev["end_frame"],
                f"{ev['start_s']:.4f}",
                f"{ev['end_s']:.4f}",
                ev["start_timecode"],
                ev["end_timecode"],
                f"{ev['duration_s']:.4f}",
                ev.get("peak_frame", ""),
                f"{ev['peak_score']:.4f}",
                "+".join(ev["detectors"]),
                x,
                y,
                w,
                h,
            ]
        )


def write_tracks_csv(fp: TextIO, tracks: list[dict]) -> None:
    """Tracks as CSV (:meth:`~motiondetect.detection.track_table.TrackTable.rows`)."""
    writer = csv.writer(fp, lineterminator="\n")
    writer.writerow(TRACK_COLUMNS)
    for t in tracks:
        writer.writerow(
            [t["track"], t["start_frame"], t["end_frame"], f"{t['start_s']:.4f}",
             f"{t['end_s']:.4f}", t["start_timecode"], t["end_timecode"],
             f"{t['duration_s']:.4f}", t["frames"], t["peak_frame"], f"{t['peak_score']:.4f}",
             "+".join(t["detectors"]), t["start_cx"], t["start_cy"], t["end_cx"], t["end_cy"],
             *t["bbox"], t["own_vx_px_s"], t["own_vy_px_s"]]
        )  # fmt: skip


def write_batch_tracks_csv(fp: TextIO, rows: list[list[str]]) -> None:
    """A batch's tracks: the rows of each input's tracks.csv, each led by its input."""
    writer = csv.writer(fp, lineterminator="\n")
    writer.writerow(["input", *TRACK_COLUMNS])
    writer.writerows(rows)


def write_json(fp: TextIO, document: dict) -> None:
    json.dump(document, fp, indent=2, allow_nan=False)
    fp.write("\n")
