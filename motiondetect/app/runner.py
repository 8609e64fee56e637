"""One ``run()`` drives the library over a batch of inputs.

Inputs: video files, frames folders, or directories of videos (a batch;
``recursive`` descends, and frames folders found inside count as inputs).
Outputs per input go to ``OUT/<name>/`` where ``<name>`` mirrors the input's
path relative to the batch directory (or is the input's stem).

An input is *finished* when its ``summary.json`` exists: it is written last,
by atomic rename. Re-running skips finished inputs unless ``overwrite``.
One failing input never stops the others.
"""

from __future__ import annotations

import dataclasses
import json
import logging
import multiprocessing
import os
import shutil
import time
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np

from motiondetect import __version__
from motiondetect.app.events import EventRules, EventTimeline
from motiondetect.app.settings import Settings
from motiondetect.constraint_ray.egomotion import EgoMotion, EgoMotionError
from motiondetect.detection.detector import FrameResult, MotionDetector
from motiondetect.detection.regions import Region, regions_mask
from motiondetect.io.annotate import annotate, annotated_size
from motiondetect.io.report import (
    SCHEMA_VERSION,
    DetectionsCsvWriter,
    FramesJsonlWriter,
    atomic_text,
    write_events_csv,
    write_json,
)
from motiondetect.io.timeline import draw_timeline
from motiondetect.io.video import (
    IMAGE_EXTENSIONS,
    FrameSource,
    VideoError,
    VideoSink,
    is_frames_folder,
    open_source,
    to_display,
    write_png,
)

log = logging.getLogger("motiondetect")

Progress = Callable[[int, int], None]  # (frames done, frames expected)


class InputError(Exception):
    """A user-facing, one-line problem with one input."""


@dataclass(frozen=True)
class InputJob:
    path: Path
    name: str  # relative output folder name


@dataclass
class InputResult:
    job: InputJob
    status: str  # "done", "skipped", "failed"
    message: str = ""
    summary: dict = field(default_factory=dict)


@dataclass
class RunResult:
    results: list[InputResult]

    @property
    def failed(self) -> list[InputResult]:
        return [r for r in self.results if r.status == "failed"]

    @property
    def exit_code(self) -> int:
        return 1 if self.failed else 0


# ----------------------------------------------------------------------------
# Inputs
# ----------------------------------------------------------------------------


def discover_inputs(paths: list[Path], recursive: bool) -> list[InputJob]:
    """Expand INPUT arguments into jobs (see docs/cli.md for the rule)."""
    jobs: list[InputJob] = []
    for path in paths:
        if path.is_dir() and not is_frames_folder(path):
            found = _scan_directory(path, recursive)
            if not found:
                jobs.append(InputJob(path, path.name))  # fails later with a clear message
            jobs.extend(found)
        else:
            name = path.name if path.is_dir() else path.stem
            jobs.append(InputJob(path, name or "input"))
    return _unique_names(jobs)


def _scan_directory(root: Path, recursive: bool) -> list[InputJob]:
    """Videos in ``root``; with ``recursive``, also in sub-folders, and each
    frames folder found below ``root`` as one input (not descended into).
    Loose images are skipped; other files become inputs that fail with a
    clear "not a video" line, so nothing is skipped silently."""
    jobs = []
    for entry in sorted(root.iterdir()):
        if entry.name.startswith("."):
            continue
        rel = entry.relative_to(root)
        if entry.is_dir():
            if recursive and is_frames_folder(entry):
                jobs.append(InputJob(entry, str(rel)))
            elif recursive:
                jobs.extend(
                    InputJob(j.path, str(rel / j.name)) for j in _scan_directory(entry, recursive)
                )
        elif entry.suffix.lower() not in IMAGE_EXTENSIONS:
            jobs.append(InputJob(entry, str(rel.with_suffix(""))))
    return jobs


def _unique_names(jobs: list[InputJob]) -> list[InputJob]:
    seen: dict[str, int] = {}
    out = []
    for job in jobs:
        name = job.name
        if name in seen:
            seen[name] += 1
            name = f"{name}-{seen[name]}"
        else:
            seen[name] = 0
        out.append(InputJob(job.path, name))
    return out


# ----------------------------------------------------------------------------
# One input
# ----------------------------------------------------------------------------


def _roi_mask(settings: Settings, width: int, height: int) -> np.ndarray | None:
    """(64, 64) bool mask of cells whose centre lies in any region of interest."""
    polygons = []
    for x, y, w, h in settings.roi:
        polygons.append(np.array([[x, y], [x + w, y], [x + w, y + h], [x, y + h]], np.int32))
    if settings.roi_file is not None:
        polygons.extend(load_polygons(settings.roi_file))
    if not polygons:
        return None
    full = np.zeros((height, width), np.uint8)
    cv2.fillPoly(full, polygons, 1)
    ys = ((np.arange(64) + 0.5) * height / 64).astype(int)
    xs = ((np.arange(64) + 0.5) * width / 64).astype(int)
    return full[np.ix_(ys, xs)] > 0


def load_polygons(path: Path) -> list[np.ndarray]:
    """A polygon file: one polygon per line, ``x,y x,y x,y ...`` in input pixels."""
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except OSError as exc:
        raise InputError(f"cannot read ROI file {path}: {exc.strerror or exc}") from exc
    polygons = []
    for n, line in enumerate(lines, 1):
        line = line.split("#")[0].strip()
        if not line:
            continue
        try:
            pts = [tuple(int(float(v)) for v in p.split(",")) for p in line.split()]
        except ValueError:
            raise InputError(f"ROI file {path}, line {n}: expected 'x,y x,y x,y ...'") from None
        if len(pts) < 3 or any(len(p) != 2 for p in pts):
            raise InputError(f"ROI file {path}, line {n}: a polygon needs at least 3 x,y points")
        polygons.append(np.array(pts, np.int32))
    return polygons


def _keep(region: Region, roi: np.ndarray | None, min_area: int) -> bool:
    if region.area_px < min_area:
        return False
    if roi is None:
        return True
    return bool(roi[region.cells[:, 0], region.cells[:, 1]].any())


def _filter(result: FrameResult, roi: np.ndarray | None, min_area: int) -> FrameResult:
    if roi is None and min_area <= 0:
        return result
    kept = [r for r in result.regions if _keep(r, roi, min_area)]
    flagged = regions_mask(kept) if kept else np.zeros_like(result.flagged)
    mask = result.mask
    if mask is not None:
        h, w = mask.shape
        mask = mask & (
            cv2.resize(flagged.astype(np.uint8), (w, h), interpolation=cv2.INTER_NEAREST) > 0
        )
    return dataclasses.replace(result, regions=kept, flagged=flagged, mask=mask)


def _observer_record(result: FrameResult) -> dict:
    if result.observer is not None:
        return result.observer.to_json()
    if result.camera is not None:
        return {"class": result.camera.class_id, **result.camera.to_json(), "params": {}}
    name = "warm-up" if result.warm_up else "none"
    return {"class": -1, "name": name, "confidence": 0.0, "params": {}}


def _frame_record(result: FrameResult) -> dict:
    record = {
        "frame": result.index,
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
    return record


def _make_detector(settings: Settings, source: FrameSource) -> MotionDetector:
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
        persistence=settings.persistence,
    )


def _check_paths(job: InputJob, out_dir: Path) -> None:
    """No output may ever point at (or inside) an input."""
    src = job.path.resolve()
    dst = out_dir.resolve()
    if dst == src or src in dst.parents or (src.is_dir() and dst.is_relative_to(src)):
        raise InputError(f"{job.path}: the output folder {out_dir} would be inside the input")


def process_input(
    job: InputJob, settings: Settings, progress: Progress | None = None
) -> InputResult:
    """Detect motion in one input and write its outputs. Never raises for bad input."""
    out_dir = settings.output / job.name
    summary_path = out_dir / "summary.json"
    if summary_path.exists() and not settings.overwrite:
        return InputResult(job, "skipped", "already finished (use --overwrite to redo)")
    try:
        _check_paths(job, out_dir)
        with open_source(job.path, settings.frames_fps) as source:
            summary = _process(job, source, out_dir, settings, progress)
        return InputResult(job, "done", summary=summary)
    except (VideoError, InputError) as exc:
        return InputResult(job, "failed", str(exc))
    except OSError as exc:
        where = exc.filename or out_dir
        return InputResult(
            job, "failed", f"{job.path}: cannot write {where}: {exc.strerror or exc}"
        )
    except MemoryError:
        return InputResult(job, "failed", f"{job.path}: out of memory")


def _process(
    job: InputJob, source: FrameSource, out_dir: Path, settings: Settings, progress: Progress | None
) -> dict:
    info = source.info
    out_dir.mkdir(parents=True, exist_ok=True)
    (out_dir / "summary.json").unlink(missing_ok=True)
    for stale in out_dir.glob(".*.part*"):  # temporaries of an interrupted run
        stale.unlink(missing_ok=True)
    detector = _make_detector(settings, source)
    roi = _roi_mask(settings, info.width, info.height)
    timeline = EventTimeline()
    masks_dir = out_dir / "masks"
    if settings.masks:
        if masks_dir.exists():
            shutil.rmtree(masks_dir)
        masks_dir.mkdir()
    size = annotated_size(info.width, info.height, settings.work_size)
    video_path = out_dir / f"annotated.{settings.video_format}"
    sink = VideoSink(video_path, info.fps, size) if settings.video else None
    started = time.perf_counter()
    n_detections = 0
    try:
        with (
            open(out_dir / "frames.jsonl", "w", encoding="utf-8") as jf,
            open(out_dir / "detections.csv", "w", encoding="utf-8", newline="") as cf,
        ):
            frames_out, csv_out = FramesJsonlWriter(jf), DetectionsCsvWriter(cf)
            for frame in source:
                result = _filter(
                    detector.process(frame.image, frame.index, frame.time_s), roi, settings.min_area
                )
                record = _frame_record(result)
                frames_out.append(record)
                for det in record["detections"]:
                    csv_out.append(result.index, result.time_s, det)
                csv_out.flush()
                n_detections += len(record["detections"])
                timeline.add(
                    result.time_s,
                    result.score,
                    result.moving_fraction,
                    record["observer_motion"]["class"],
                    record["detections"],
                )
                if settings.masks:
                    mask = result.input_mask(info.width, info.height)
                    write_png(masks_dir / f"{result.index:06d}.png", mask)
                if sink is not None:
                    sink.write(annotate(to_display(frame.image), result, size))
                if progress is not None:
                    progress(len(timeline), info.frame_count)
    except BaseException:
        if sink is not None:
            sink.close(keep=False)
        raise
    if sink is not None:
        sink.close(keep=len(timeline) > 0)
    elapsed = time.perf_counter() - started
    if len(timeline) == 0:
        raise InputError(f"{job.path}: no frames could be decoded")
    rules = EventRules(settings.min_event_frames, settings.merge_gap_frames, settings.pad_frames)
    events = timeline.events(rules, info.fps)
    with atomic_text(out_dir / "events.csv") as fp:
        write_events_csv(fp, events)
    if settings.timeline:
        write_png(out_dir / "timeline.png", draw_timeline(timeline, events))
    if settings.extract_clips and events:
        extract_clips(job.path, out_dir / "events", events, settings)
    partial = source.partial
    if partial:
        log.warning(
            "%s: input is truncated or damaged; processed %d frames", job.path, len(timeline)
        )
    summary = {
        "schema_version": SCHEMA_VERSION,
        "tool": {"name": "motiondetect", "version": __version__},
        "input": {**info.to_json(), "path": str(job.path)},
        "status": "partial" if partial else "complete",
        "settings": settings.to_json(),
        "totals": {
            "frames": len(timeline),
            "frames_with_detections": int(sum(b is not None for b in timeline.boxes)),
            "detections": n_detections,
            "events": len(events),
        },
        "speed": {
            "wall_s": round(elapsed, 3),
            "frames_per_s": round(len(timeline) / elapsed, 2) if elapsed > 0 else None,
        },
        "events": events,
        "outputs": sorted(p.name for p in out_dir.iterdir() if not p.name.startswith(".")),
    }
    with atomic_text(out_dir / "summary.json") as fp:
        write_json(fp, summary)
    return summary


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
    detector = None
    with open_source(path, settings.frames_fps) as source:
        info = source.info
        size = (info.width - info.width % 2, info.height - info.height % 2)
        if settings.clips_annotated:
            detector = _make_detector(settings, source)
        for frame in source:
            result = detector.process(frame.image, frame.index, frame.time_s) if detector else None
            if not pending:
                break
            ev = pending[0]
            if frame.index == ev["start_frame"]:
                target = clip_dir / f"event_{ev['event']:04d}.mp4"
                sink = VideoSink(target, info.fps, size)
            if sink is not None:
                image = to_display(frame.image)[: size[1], : size[0]]
                if result is not None:
                    image = annotate(image, result, size)
                sink.write(image)
            if frame.index == ev["end_frame"] and sink is not None:
                sink.close()
                written.append(sink.path)
                sink = None
                pending.pop(0)
    if sink is not None:
        sink.close()
        written.append(sink.path)
    return written


# ----------------------------------------------------------------------------
# A batch
# ----------------------------------------------------------------------------


def _worker(job: InputJob, settings: Settings) -> InputResult:
    cv2.setNumThreads(1)
    return process_input(job, settings)


def run(
    inputs: list[Path],
    settings: Settings,
    *,
    on_start: Callable[[InputJob, int], Progress | None] | None = None,
    on_done: Callable[[InputResult], None] | None = None,
    on_jobs: Callable[[int], None] | None = None,
) -> RunResult:
    """Process every input; one failure never stops the others.

    ``on_start(job, expected_frames)`` may return a per-frame progress
    callback (used with one job at a time); ``on_done(result)`` is called as
    each input finishes; ``on_jobs(count)`` once the inputs are known.
    """
    jobs = discover_inputs(inputs, settings.recursive)
    if on_jobs is not None:
        on_jobs(len(jobs))
    try:
        settings.output.mkdir(parents=True, exist_ok=True)
        probe = settings.output / f".motiondetect-write-test-{os.getpid()}"
        probe.write_text("")
        probe.unlink()
    except OSError as exc:
        raise InputError(
            f"output folder {settings.output} is not writable: {exc.strerror or exc}"
        ) from exc
    results: list[InputResult] = []

    def finish(result: InputResult) -> None:
        results.append(result)
        if on_done is not None:
            on_done(result)

    if settings.jobs <= 1 or len(jobs) <= 1:
        for job in jobs:
            progress = on_start(job, 0) if on_start else None
            finish(process_input(job, settings, progress))
    else:
        # spawn, not fork: forking after OpenCV's thread pool started can deadlock.
        # One thread per worker process: the parallelism is across inputs.
        for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
            os.environ.setdefault(var, "1")
        context = multiprocessing.get_context("spawn")
        with ProcessPoolExecutor(max_workers=settings.jobs, mp_context=context) as pool:
            futures = {pool.submit(_worker, job, settings): job for job in jobs}
            for future in as_completed(futures):
                job = futures[future]
                try:
                    finish(future.result())
                except Exception as exc:  # a crashed worker: report, keep going
                    finish(InputResult(job, "failed", f"{job.path}: worker failed: {exc}"))
    order = {job: i for i, job in enumerate(jobs)}
    results.sort(key=lambda r: order.get(r.job, 0))
    if len(jobs) > 1:
        _write_batch_events(settings.output, results)
    return RunResult(results)


def _write_batch_events(output: Path, results: list[InputResult]) -> None:
    """One events.csv at the top level listing every input's events."""
    rows = []
    for result in results:
        summary = result.summary
        if not summary and result.status == "skipped":
            try:
                text = (output / result.job.name / "summary.json").read_text(encoding="utf-8")
                summary = json.loads(text)
            except (OSError, ValueError):
                summary = {}
        rows.extend({**ev, "input": str(result.job.path)} for ev in summary.get("events", []))
    with atomic_text(output / "events.csv") as fp:
        write_events_csv(fp, rows, with_input=True)
