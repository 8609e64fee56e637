"""Second passes over an input once its events are known: clips and thumbnails.

Each is one more streaming pass (memory stays flat in the video's length);
only the few frames an event needs are kept at a time.
"""

from __future__ import annotations

import json
from pathlib import Path

from motiondetect.app.settings import Settings
from motiondetect.detection.detector import MotionDetector
from motiondetect.io.annotate import Trails, annotate, draw_boxes
from motiondetect.io.video import SourceFrame, VideoSink, open_source, to_display, write_image


def _make_detector(settings: Settings, source) -> MotionDetector:
    from motiondetect.app.process import make_detector  # one builder for both passes

    return make_detector(settings, source)


def peak_detections(frames_jsonl: Path, peaks: set[int]) -> dict[int, list[dict]]:
    """The detections recorded on each peak frame, read line by line."""
    found: dict[int, list[dict]] = {}
    with open(frames_jsonl, encoding="utf-8") as fp:
        for line in fp:
            record = json.loads(line)
            if record["frame"] in peaks:
                found[record["frame"]] = record["detections"]
    return found


def write_thumbnails(path: Path, out_dir: Path, events: list[dict], settings: Settings) -> list:
    """``thumbnails/event_NNNN.jpg``: each event's peak-score frame with its boxes."""
    folder = out_dir / "thumbnails"
    folder.mkdir(exist_ok=True)
    wanted = {ev["peak_frame"]: ev["event"] for ev in events}
    boxes = peak_detections(out_dir / "frames.jsonl", set(wanted))
    written = []
    with open_source(path, settings.frames_fps) as source:
        for frame in source:
            if frame.index in wanted:
                image = draw_boxes(to_display(frame.image).copy(), boxes.get(frame.index, []))
                target = folder / f"event_{wanted.pop(frame.index):04d}.jpg"
                write_image(target, image)
                written.append(target)
            if not wanted:
                break
    return written


def _annotated_result(detector: MotionDetector | None, frame: SourceFrame):
    return detector.process(frame.grey, frame.index, frame.time_s) if detector else None


def extract_clips(path: Path, clip_dir: Path, events: list[dict], settings: Settings) -> list[Path]:
    """Cut one clip per event (padding included) from the input frames.

    A second streaming pass over the input; with ``clips_annotated`` the
    frames are annotated (the detector is re-run, which costs one more pass
    of detection but keeps memory flat).
    """
    clip_dir.mkdir(parents=True, exist_ok=True)
    written: list[Path] = []
    pending = list(events)
    sink: VideoSink | None = None
    with open_source(path, settings.frames_fps) as source:
        info = source.info
        size = (info.width - info.width % 2, info.height - info.height % 2)
        detector = _make_detector(settings, source) if settings.clips_annotated else None
        trails = Trails()
        for frame in source:
            result = _annotated_result(detector, frame)
            if not pending:
                break
            ev = pending[0]
            if frame.index == ev["start_frame"]:
                sink = VideoSink(clip_dir / f"event_{ev['event']:04d}.mp4", info.fps, size)
            if sink is not None:
                image = to_display(frame.image)[: size[1], : size[0]]
                sink.write(image if result is None else annotate(image, result, size, trails))
            if frame.index == ev["end_frame"] and sink is not None:
                sink.close()
                written.append(sink.path)
                sink, _ = None, pending.pop(0)
    if sink is not None:
        sink.close()
        written.append(sink.path)
    return written
