"""One input, start to finish: detect frame by frame, write every output.

An input is *finished* when its ``summary.json`` exists: it is written last,
by atomic rename. :func:`process_input` is the failure boundary of one
input: whatever goes wrong becomes that input's one-line failure.
"""

from __future__ import annotations

import collections
import contextlib
import json
import logging
import shutil
import time
from collections.abc import Iterator
from pathlib import Path

from motiondetect.app.clips import extract_clips, write_thumbnails
from motiondetect.app.inputs import InputError, InputJob, InputResult, Progress, input_identity
from motiondetect.app.roi import keep_detections, roi_mask
from motiondetect.app.settings import AUTO, Settings
from motiondetect.constraint_ray.egomotion import EgoMotion, EgoMotionError
from motiondetect.detection.detector import FrameResult, MotionDetector
from motiondetect.detection.events import EventTimeline
from motiondetect.detection.track_table import TrackTable
from motiondetect.io.annotate import Trails, annotate, annotated_size
from motiondetect.io.encode import BackgroundSink
from motiondetect.io.files import TEMPORARY_PREFIX
from motiondetect.io.records import frame_record, summary_record
from motiondetect.io.report import (
    DetectionsCsvWriter,
    FramesJsonlWriter,
    atomic_text,
    write_events_csv,
    write_json,
    write_tracks_csv,
)
from motiondetect.io.timeline import draw_timeline
from motiondetect.io.video import (
    FrameSource,
    SourceFrame,
    VideoError,
    VideoSink,
    open_source,
    write_image,
)

log = logging.getLogger("motiondetect")


class StreamStop:
    """Set by the runner's signal handler while a stream is read in this
    process: the stream closes after its current frame, with every output
    complete and ``status: stopped``; the runner then exits 130 or 143."""

    def __init__(self) -> None:
        self.reading = False  # a stream is being read now
        self.code = 0  # the exit code asked for, once a signal came

    @contextlib.contextmanager
    def around(self, job: InputJob):
        self.reading = job.is_stream
        try:
            yield
        finally:
            self.reading = False


STREAM_STOP = StreamStop()


def make_detector(settings: Settings, source: FrameSource) -> MotionDetector:
    """The detector a run's settings describe, with its known ego-motion if any."""
    ego = None
    if settings.egomotion is not None:
        numbers = getattr(source, "frame_numbers", None)
        try:
            ego = EgoMotion.load(settings.egomotion, numbers)
        except EgoMotionError as exc:
            raise InputError(str(exc)) from exc
    return MotionDetector(
        settings.detector,
        *settings.detector_configs(),
        measure=settings.measure,
        egomotion=ego,
    )


def _check_paths(job: InputJob, out_dir: Path) -> None:
    """No output may ever point at (or inside) an input."""
    if job.is_stream:
        return
    src = job.path.resolve()
    dst = out_dir.resolve()
    if dst == src or src in dst.parents or (src.is_dir() and dst.is_relative_to(src)):
        raise InputError(f"{job.label}: the output folder {out_dir} would be inside the input")


def process_input(
    job: InputJob, settings: Settings, progress: Progress | None = None
) -> InputResult:
    """Detect motion in one input and write its outputs. Never raises for bad input."""
    out_dir = settings.output / job.name
    if (out_dir / "summary.json").exists() and not (settings.overwrite or job.is_stream):
        finished = _finished(job, out_dir, settings)
        if finished is not None:
            log.info("%s: %s", job.label, finished.message)
            return finished
    log.info("%s: processing into %s", job.label, out_dir)
    with STREAM_STOP.around(job):
        result = _guarded(job, settings, out_dir, progress)
    if result.status == "done":
        totals = result.summary["totals"]
        log.info("%s: done, %d frames, %d events", job.label, totals["frames"], totals["events"])
    else:
        log.info("%s: failed: %s", job.label, result.message)
    return result


def _finished(job: InputJob, out_dir: Path, settings: Settings) -> InputResult | None:
    """The result of a finished earlier run into ``out_dir``, or None to (re)do it."""
    try:
        done = json.loads((out_dir / "summary.json").read_text(encoding="utf-8"))
        identity, previous = input_identity(job), done["input"].get("identity")
    except (OSError, ValueError, KeyError, TypeError):
        return None  # unreadable: redo it
    if previous != identity:
        other = (previous or {}).get("path", done["input"].get("path"))
        return InputResult(
            job, "failed",
            f"{job.label}: {out_dir} holds the results of another input ({other}); "
            "use another --output or --overwrite",
        )  # fmt: skip
    if done.get("settings_hash") != settings.result_hash():
        return InputResult(
            job, "skipped", "finished with other settings (use --overwrite to redo it)"
        )
    return InputResult(job, "skipped", "already finished (use --overwrite to redo)")


def _guarded(
    job: InputJob, settings: Settings, out_dir: Path, progress: Progress | None
) -> InputResult:
    """The failure boundary of one input: every exception becomes its failure."""
    try:
        _check_paths(job, out_dir)
        with open_source(job.source, settings.frames_fps) as source:
            summary = _process(job, source, out_dir, settings, progress)
        return InputResult(job, "done", summary=summary)
    except (VideoError, InputError) as exc:
        return InputResult(job, "failed", str(exc))
    except OSError as exc:
        where = exc.filename or out_dir
        return InputResult(
            job, "failed", f"{job.label}: cannot write {where}: {exc.strerror or exc}"
        )
    except MemoryError:
        return InputResult(job, "failed", f"{job.label}: out of memory")
    except Exception as exc:  # the failure boundary: any bug stays this input's failure
        log.debug("%s: internal error", job.label, exc_info=True)
        return InputResult(job, "failed", f"{job.label}: internal error: {exc!r}")


class _FrameWriters:
    """frames.jsonl, detections.csv, masks and the annotated video of one input."""

    def __init__(self, out_dir: Path, settings: Settings, source: FrameSource) -> None:
        info = source.info
        self.settings, self.info = settings, info
        self.masks_dir = out_dir / "masks" if settings.masks else None
        if self.masks_dir is not None:
            shutil.rmtree(self.masks_dir, ignore_errors=True)
            self.masks_dir.mkdir()
        self.size = annotated_size(info.width, info.height, settings.video_size)
        self._trails = Trails()  # drawn on the video's thread, in frame order
        video = out_dir / f"annotated.{settings.video_format}"
        self.sink = (
            BackgroundSink(VideoSink(video, info.fps, self.size), self._draw)
            if settings.video
            else None
        )
        with contextlib.ExitStack() as files:  # every file closes, whatever fails first
            jsonl = files.enter_context(open(out_dir / "frames.jsonl", "w", encoding="utf-8"))
            csv = files.enter_context(
                open(out_dir / "detections.csv", "w", encoding="utf-8", newline="")
            )
            self.frames = FramesJsonlWriter(jsonl)
            self.detections = DetectionsCsvWriter(csv)
            self._files = files.pop_all()

    def write(self, frame: SourceFrame, result: FrameResult) -> dict:
        record = frame_record(result, frame.number)
        self.frames.append(record)
        for det in record["detections"]:
            self.detections.append(result.index, result.time_s, det)
        self.detections.flush()
        if self.masks_dir is not None:
            mask = result.input_mask(self.info.width, self.info.height)
            write_image(self.masks_dir / f"{result.index:06d}.png", mask)
        if self.sink is not None:
            self.sink.put((frame, result))
        return record

    def _draw(self, item: tuple[SourceFrame, FrameResult]) -> tuple:
        frame, result = item
        picture, whole = frame.picture(self.size), (self.info.width, self.info.height)
        return annotate(picture, result, self.size, self._trails, whole), frame.time_s

    def close(self, ok: bool) -> None:
        with self._files:
            if self.sink is not None:
                self.sink.close(keep=ok)


class _InRange:
    """The frames of ``--start``/``--end``, until Ctrl-C stops a stream;
    ``last`` is the last frame read, in range or not."""

    def __init__(self, source: FrameSource, settings: Settings) -> None:
        self.source, self.settings = source, settings
        self.last: SourceFrame | None = None

    def __iter__(self) -> Iterator[SourceFrame]:
        for frame in self.source:
            if STREAM_STOP.code and not self.source.seekable:
                return  # Ctrl-C on a stream: close it with complete outputs
            self.last = frame
            before, past = self.settings.in_range(frame.index, frame.time_s)
            if past:
                return
            if not before:
                yield frame

    def nothing_read(self, label: str) -> str:
        """Why no frame was processed."""
        if self.last is None:
            return f"{label}: no frames could be decoded"
        return (
            f"{label}: no frame lies between --start and --end: the input ends at frame "
            f"{self.last.index} ({self.last.time_s:.2f} s)"
        )


def _detect_frames(
    frames: _InRange, writers: _FrameWriters, settings: Settings, progress: Progress | None
) -> tuple[EventTimeline, TrackTable, dict]:
    """The per-frame loop; returns the timeline, the tracks and the totals of the summary
    that it counts: detections, frames judged (the others held a result,
    ``--frame-skip``), judged frames marked unreliable, by reason, judged
    frames on which an overlay (a burnt-in caption or logo) was not flagged,
    frames that repeated the one before (held its result), and the picture
    inside black bars the last judged frame was measured on."""
    source = frames.source
    detector = make_detector(settings, source)
    info = source.info
    roi = roi_mask(settings, info.width, info.height)
    timeline, tracks, detections, judged = EventTimeline(), TrackTable(), 0, 0
    unreliable: collections.Counter = collections.Counter()
    overlaid, repeated, picture = 0, 0, None
    skip = settings.skipped_frames(info.fps)
    if skip and settings.frame_skip == AUTO:
        log.info("%.4g frames/s: judging one frame in %d (--frame-skip auto)", info.fps, skip + 1)
    for frame, result in detector.stream(frames, skip):
        result = keep_detections(result, roi, settings.min_area)
        record = writers.write(frame, result)
        detections += len(record["detections"])
        tracks.add(result.index, result.time_s, record["detections"])
        judged += result.held_from is None
        if result.held_from is None and result.reason:
            unreliable[result.reason] += 1
        overlaid += result.held_from is None and result.overlay is not None
        repeated += result.repeat
        if result.held_from is None and result.field is not None:
            picture = getattr(result.field, "picture", None)
        timeline.add(
            result.time_s, result.score, result.moving_fraction,
            record["observer_motion"]["class"], record["detections"], result.index,
        )  # fmt: skip
        if progress is not None:
            progress(len(timeline), info.frame_count)
    counted = {
        "frames_judged": judged,
        "frames_unreliable": dict(sorted(unreliable.items())),
        "frames_overlay": overlaid,
        "frames_repeated": repeated,
    }
    if picture is not None:
        counted["picture"] = list(picture.box)
    return timeline, tracks, {**counted, "detections": detections}


def _second_passes(
    job: InputJob, source: FrameSource, out_dir: Path, events: list[dict], settings: Settings
) -> None:
    """Clips and thumbnails read the input again: a stream cannot be."""
    wanted = [flag for flag, on in (("--clips", settings.extract_clips),
                                    ("--thumbnails", settings.thumbnails)) if on]  # fmt: skip
    if not (wanted and events):
        return
    if not source.seekable:
        log.warning("%s: %s need a file; not written for a stream", job.label, " and ".join(wanted))
        return
    if settings.extract_clips:
        extract_clips(job.path, out_dir / "events", events, settings)
    if settings.thumbnails:
        write_thumbnails(job.path, out_dir, events, settings)


def _prepare(out_dir: Path) -> None:
    out_dir.mkdir(parents=True, exist_ok=True)
    (out_dir / "summary.json").unlink(missing_ok=True)
    for stale in out_dir.glob(f"{TEMPORARY_PREFIX}*"):  # temporaries of an interrupted run
        stale.unlink(missing_ok=True)


def _process(
    job: InputJob, source: FrameSource, out_dir: Path, settings: Settings, progress: Progress | None
) -> dict:
    _prepare(out_dir)
    writers = _FrameWriters(out_dir, settings, source)
    started = time.perf_counter()
    frames = _InRange(source, settings)
    try:
        timeline, tracks, counted = _detect_frames(frames, writers, settings, progress)
    except BaseException:
        writers.close(ok=False)
        raise
    writers.close(ok=len(timeline) > 0)
    elapsed = time.perf_counter() - started
    if len(timeline) == 0:
        raise InputError(frames.nothing_read(job.label))
    events = timeline.events(settings.event_rules(source.info.fps), source.info.fps)
    with atomic_text(out_dir / "events.csv") as fp:
        write_events_csv(fp, events)
    with atomic_text(out_dir / "tracks.csv") as fp:
        write_tracks_csv(fp, tracks.rows())
    if settings.timeline:
        write_image(out_dir / "timeline.png", draw_timeline(timeline, events))
    _second_passes(job, source, out_dir, events, settings)
    if source.partial:
        log.warning(
            "%s: input is truncated or damaged; processed %d frames", job.label, len(timeline)
        )
    totals = {
        "frames": len(timeline),
        **counted,
        "frames_with_detections": int(sum(b is not None for b in timeline.boxes)),
        "events": len(events),
        "tracks": len(tracks),
    }
    outputs = sorted(p.name for p in out_dir.iterdir() if not p.name.startswith("."))
    status = "partial" if source.partial else "complete"
    if STREAM_STOP.code and not source.seekable:
        status = "stopped"
    summary = summary_record(
        job.label, source.info, status, settings.to_json(), totals, elapsed, events, outputs
    )
    summary["input"]["identity"] = input_identity(job)
    summary["settings_hash"] = settings.result_hash()
    summary["decode_errors"] = source.decode_errors
    with atomic_text(out_dir / "summary.json") as fp:
        write_json(fp, summary)
    return summary
