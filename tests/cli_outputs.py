"""Inputs the CLI tests write and the checks every run's outputs must pass:
schemas, one record per frame, detections, tracks and the annotated video.
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

import cv2
import jsonschema
import numpy as np
from click.testing import CliRunner
from motiondetect_cli.main import main

from motiondetect.io.video import count_decodable_frames

DOCS = Path(__file__).resolve().parents[1] / "docs" / "schemas"
FRAME_SCHEMA = json.loads((DOCS / "frames.schema.json").read_text())
SUMMARY_SCHEMA = json.loads((DOCS / "summary.schema.json").read_text())


def write_video(path: Path, frames, fourcc: str = "mp4v", fps: float = 30.0) -> Path:
    h, w = frames[0].shape[:2]
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*fourcc), fps, (w, h))
    assert writer.isOpened()
    for f in frames:
        writer.write(f)
    writer.release()
    return path


def noise_video(path: Path, frames: int = 6, seed: int = 0) -> Path:
    """A small mp4 of smoothed noise panning 2 px a frame (``seed`` sets the noise)."""
    rng = np.random.default_rng(seed)
    base = cv2.GaussianBlur(rng.integers(0, 255, (120, 160, 3), np.uint8), (5, 5), 0)
    return write_video(path, [np.roll(base, 2 * i, axis=1) for i in range(frames)])


def invoke(*args: str) -> object:
    return CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)


def times_of(out: Path) -> list[float]:
    """Each frame's ``time_s`` in an output folder's ``frames.jsonl``."""
    lines = (out / "frames.jsonl").read_text(encoding="utf-8").splitlines()
    return [json.loads(line)["time_s"] for line in lines]


def check_outputs(out: Path, frames: int, video: bool = True, timeline: bool = True) -> dict:
    summary = json.loads((out / "summary.json").read_text())
    jsonschema.validate(summary, SUMMARY_SCHEMA)
    lines = (out / "frames.jsonl").read_text().splitlines()
    assert len(lines) == frames == summary["totals"]["frames"]
    for i, line in enumerate(lines):
        record = json.loads(line)
        jsonschema.validate(record, FRAME_SCHEMA)
        assert record["frame"] == i
    rows = list(csv.reader((out / "detections.csv").read_text().splitlines()))
    assert rows[0] == [
        "frame", "time_s", "detectors", "x", "y", "w", "h", "area_px", "score", "track", "held",
        "vx_px_s", "vy_px_s", "own_vx_px_s", "own_vy_px_s",
    ]  # fmt: skip
    assert len(rows) - 1 == summary["totals"]["detections"]
    records = [d for r in map(json.loads, lines) for d in r["detections"]]
    tracks = [(str(d.get("track", "")), "1" if d.get("held") else "") for d in records]
    assert [(row[9], row[10]) for row in rows[1:]] == tracks
    velocities = [
        [str(v) for key in ("velocity_px_s", "own_velocity_px_s") for v in d.get(key, ("", ""))]
        for d in records
    ]
    assert [row[11:] for row in rows[1:]] == velocities
    assert (out / "events.csv").exists()
    check_tracks(out, rows[1:], summary)
    assert (out / "timeline.png").exists() == timeline
    if video:
        assert count_decodable_frames(out / "annotated.mp4") == frames
    return summary


def check_tracks(out: Path, detections: list[list[str]], summary: dict) -> list[dict]:
    """tracks.csv agrees with detections.csv: one row per track id, with its
    first and last frame, its count and its peak score."""
    tracks = list(csv.DictReader((out / "tracks.csv").read_text().splitlines()))
    assert len(tracks) == summary["totals"]["tracks"]
    by_id: dict[str, list] = {}
    for row in detections:
        if row[9]:  # the track column
            by_id.setdefault(row[9], []).append(row)
    assert sorted(t["track"] for t in tracks) == sorted(by_id)
    for t in tracks:
        rows = by_id[t["track"]]
        frames = [int(r[0]) for r in rows]
        assert (int(t["start_frame"]), int(t["end_frame"])) == (min(frames), max(frames))
        assert int(t["frames"]) == len(rows)
        assert float(t["peak_score"]) == max(float(r[8]) for r in rows)
    return tracks
