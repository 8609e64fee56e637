"""What is written per frame and per input: the frames.jsonl record and the summary.

Kept beside the report writers (:mod:`.report`), which take these dicts;
their schemas are docs/schemas/frames.schema.json and summary.schema.json.
"""

from __future__ import annotations

from motiondetect import __version__
from motiondetect.detection.detector import FrameResult
from motiondetect.detection.regions import velocity_json
from motiondetect.io.report import SCHEMA_VERSION
from motiondetect.io.video import VideoInfo


def _observer_record(result: FrameResult) -> dict:
    if result.observer is not None:
        return result.observer.to_json()
    if result.camera is not None:
        record = {"class": result.camera.class_id, **result.camera.to_json(), "params": {}}
        view = result.view_velocity_px_s
        if view is not None:
            record["view_velocity_px_s"] = velocity_json(view)
        return record
    name = "warm-up" if result.warm_up else "none"
    return {"class": -1, "name": name, "confidence": 0.0, "params": {}}


def frame_record(result: FrameResult, number: int | None = None) -> dict:
    """The frames.jsonl record of one result; ``number`` is the number in
    the name of the frame's file (frames folders), recorded when given, so
    that ground truth numbered as the files finds its frame
    (:func:`motiondetect.tools.ground_truth.aligned_truth`)."""
    record = {"frame": result.index}
    if number is not None and number >= 0:
        record["number"] = number
    record |= {
        "time_s": round(result.time_s, 4),
        "warm_up": result.warm_up,
        "reliable": result.reliable,
        "observer_motion": _observer_record(result),
        "moving_fraction": round(result.moving_fraction, 5),
        "score": round(result.score, 4),
        "detections": [r.to_json() for r in result.regions],
    }
    if result.reason:
        record["reason"] = result.reason
    if result.held_from is not None:
        record["held_from"] = result.held_from
    if result.repeat:
        record["repeat"] = True
    return record


def summary_record(
    path: str, info: VideoInfo, status: str, settings: dict, totals: dict, wall_s: float,
    events: list[dict], outputs: list[str],
) -> dict:  # fmt: skip
    """The summary.json document of one input."""
    frames = totals["frames"]
    return {
        "schema_version": SCHEMA_VERSION,
        "tool": {"name": "motiondetect", "version": __version__},
        "input": {**info.to_json(), "path": path},
        "status": status,
        "settings": settings,
        "totals": totals,
        "speed": {
            "wall_s": round(wall_s, 3),
            "frames_per_s": round(frames / wall_s, 2) if wall_s > 0 else None,
        },
        "events": events,
        "outputs": outputs,
    }
