"""One ``run()`` drives the library over a batch of inputs.

The inputs are discovered (:mod:`.inputs`) and processed one by one or in
``jobs`` worker processes (:mod:`.process`); one failing input never stops
the others. A batch of more than one input also gets a top-level
``events.csv`` listing every input's events.
"""

from __future__ import annotations

import json
import multiprocessing
import os
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path

import cv2

from motiondetect.app.inputs import (
    InputError,
    InputJob,
    InputResult,
    Progress,
    discover_inputs,
)
from motiondetect.app.process import process_input
from motiondetect.app.settings import Settings
from motiondetect.io.report import atomic_text, write_events_csv

__all__ = ["InputError", "InputJob", "InputResult", "RunResult", "discover_inputs", "run"]


@dataclass
class RunResult:
    results: list[InputResult]

    @property
    def failed(self) -> list[InputResult]:
        return [r for r in self.results if r.status == "failed"]

    @property
    def exit_code(self) -> int:
        return 1 if self.failed else 0


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
    with atomic_text(output / "events.csv") as fp:
        write_events_csv(fp, batch_events(output, results), with_input=True)


def batch_events(output: Path, results: list[InputResult]) -> list[dict]:
    """Every input's events (finished now or before), each with its ``input``."""
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
    return rows
