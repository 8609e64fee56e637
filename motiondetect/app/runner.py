"""One ``run()`` drives the library over a batch of inputs.

The inputs are discovered (:mod:`.inputs`) and processed one by one or in
``jobs`` worker processes (:mod:`.process`); one failing input never stops
the others. A batch of more than one input also gets a top-level
``events.csv`` listing every input's events.
"""

from __future__ import annotations

import contextlib
import csv
import ctypes
import fcntl
import json
import logging
import multiprocessing
import os
import signal
import threading
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
from motiondetect.app.process import STREAM_STOP, process_input
from motiondetect.app.settings import Settings
from motiondetect.io.report import (
    TRACK_COLUMNS,
    atomic_text,
    write_batch_tracks_csv,
    write_events_csv,
)

LOCK_NAME = ".motiondetect.lock"

__all__ = [
    "Interrupted",
    "InputError",
    "InputJob",
    "InputResult",
    "RunResult",
    "discover_inputs",
    "run",
]


@dataclass
class RunResult:
    results: list[InputResult]

    @property
    def failed(self) -> list[InputResult]:
        return [r for r in self.results if r.status == "failed"]

    @property
    def exit_code(self) -> int:
        return 1 if self.failed else 0


class Interrupted(BaseException):
    """SIGINT or SIGTERM stopped the batch; ``code`` is the exit code (130, 143).

    A BaseException, like KeyboardInterrupt, so that no input's failure
    boundary mistakes it for that input's failure: the input in progress is
    left unfinished and is redone on the next run.
    """

    def __init__(self, code: int) -> None:
        super().__init__(f"interrupted by {'SIGTERM' if code == 143 else 'SIGINT'}")
        self.code = code


@contextlib.contextmanager
def _stopping_on_signals():
    """SIGTERM (and SIGINT) raise :class:`Interrupted` in the main thread."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def stop(signum, frame):
        code = 143 if signum == signal.SIGTERM else 130
        if STREAM_STOP.reading and not STREAM_STOP.code:  # a second signal does not wait
            STREAM_STOP.code = code
            return
        raise Interrupted(code)

    saved = {s: signal.signal(s, stop) for s in (signal.SIGTERM, signal.SIGINT)}
    try:
        yield
    finally:
        for s, handler in saved.items():
            signal.signal(s, handler)


@contextlib.contextmanager
def output_lock(output: Path):
    """Hold the output folder for this run; a second run into it refuses."""
    file = next((p for p in (output, *output.parents) if p.is_file()), None)
    if file is not None:
        where = "is" if file == output else f"lies inside {file}, which is"
        raise InputError(f"output folder {output} {where} a file, not a folder")
    try:
        output.mkdir(parents=True, exist_ok=True)
        fp = open(output / LOCK_NAME, "a+")
    except OSError as exc:
        raise InputError(f"output folder {output} is not writable: {exc.strerror or exc}") from exc
    with fp:
        try:
            fcntl.flock(fp, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise InputError(
                f"output folder {output} is in use by another motiondetect run"
            ) from None
        try:
            yield
        finally:
            fcntl.flock(fp, fcntl.LOCK_UN)


def _one_thread_per_worker() -> None:
    """One BLAS thread per worker process: the parallelism is across inputs."""
    for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(var, "1")


def _worker_init() -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the parent decides when to stop
    cv2.setNumThreads(1)


def _run_pool(jobs: list[InputJob], settings: Settings, finish) -> None:
    """``jobs`` in worker processes; a signal cancels the queue and ends the workers."""
    # spawn, not fork: forking after OpenCV's thread pool started can deadlock.
    _one_thread_per_worker()
    context = multiprocessing.get_context("spawn")
    pool = ProcessPoolExecutor(settings.jobs, mp_context=context, initializer=_worker_init)
    try:
        futures = {pool.submit(process_input, job, settings): job for job in jobs}
        for future in as_completed(futures):
            job = futures[future]
            try:
                finish(future.result())
            except Exception as exc:  # a crashed worker: report, keep going
                finish(InputResult(job, "failed", f"{job.label}: worker failed: {exc}"))
    except BaseException:
        workers = list(getattr(pool, "_processes", {}).values())
        pool.shutdown(wait=False, cancel_futures=True)
        for process in workers:
            process.terminate()
        for process in workers:
            process.join(timeout=2)
            if process.is_alive():
                process.kill()
        raise
    pool.shutdown()


# glibc's own adaptive limits reach these; Dask's nanny fixes the trim limit at
# 64 KiB (MALLOC_TRIM_THRESHOLD_), which also freezes the mmap limit at 128 KiB:
# every frame-sized array is then mmapped and unmapped, 1.7x slower per input
# (docs/performance.md).
MALLOC_LIMITS = {-3: 32 << 20, -1: 64 << 20}  # M_MMAP_THRESHOLD, M_TRIM_THRESHOLD: bytes


def _keep_freed_memory() -> None:
    """Let glibc reuse freed frame buffers, as it does by default."""
    try:
        mallopt = ctypes.CDLL(None).mallopt
    except (OSError, AttributeError):  # not glibc: nothing to undo
        return
    for option, value in MALLOC_LIMITS.items():
        mallopt(option, value)


def _dask_task(job: InputJob, settings: Settings) -> InputResult:
    cv2.setNumThreads(1)  # one thread per worker process, as with --jobs
    _keep_freed_memory()
    return process_input(job, settings)


def _sees(path: str) -> bool:
    return Path(path).is_file()


def _dask_client(scheduler: str, workers: int):
    try:
        from dask.distributed import Client, LocalCluster
    except ImportError:
        raise InputError(
            "--scheduler needs the dask extra: pip install 'motiondetect[dask]'"
        ) from None
    if scheduler == "local":
        _one_thread_per_worker()  # the workers inherit this environment
        cluster = LocalCluster(
            n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None,
            silence_logs=logging.CRITICAL,  # its shutdown races are not the user's business
        )  # fmt: skip
        return Client(cluster), cluster
    try:
        return Client(scheduler, timeout="10s"), None
    except OSError as exc:
        raise InputError(f"cannot reach the Dask scheduler {scheduler}: {exc}") from None


def _run_dask(jobs: list[InputJob], settings: Settings, finish) -> None:
    """One Dask task per input; each keeps process_input's failure boundary."""
    from dask.distributed import as_completed as dask_completed

    client, cluster = _dask_client(settings.scheduler, settings.jobs)
    probe = settings.output / f".motiondetect-shared-{os.getpid()}"
    try:
        probe.write_text("")
        blind = [w for w, ok in client.run(_sees, str(probe.resolve())).items() if not ok]
        if blind:
            raise InputError(
                f"output folder {settings.output} is not visible to Dask worker {blind[0]}: "
                "it must be on a filesystem every worker shares"
            )
        futures = {client.submit(_dask_task, job, settings, pure=False): job for job in jobs}
        try:
            for future in dask_completed(list(futures)):
                job = futures[future]
                try:
                    finish(future.result())
                except Exception as exc:  # a lost worker: report, keep going
                    finish(InputResult(job, "failed", f"{job.label}: worker failed: {exc}"))
        except BaseException:
            client.cancel(list(futures))
            raise
    finally:
        probe.unlink(missing_ok=True)
        client.close()
        if cluster is not None:
            cluster.close()


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
    SIGINT or SIGTERM raises :class:`Interrupted` once the workers are gone.
    """
    jobs = discover_inputs(
        inputs, settings.recursive, output=settings.output,
        include=settings.include, exclude=settings.exclude,
    )  # fmt: skip
    if on_jobs is not None:
        on_jobs(len(jobs))
    results: list[InputResult] = []

    def finish(result: InputResult) -> None:
        results.append(result)
        if on_done is not None:
            on_done(result)

    with output_lock(settings.output), _stopping_on_signals():
        STREAM_STOP.code = 0
        streams = [job for job in jobs if job.is_stream]  # read here, where stdin is
        for job in streams:
            finish(process_input(job, settings, on_start(job, 0) if on_start else None))
            if STREAM_STOP.code:
                raise Interrupted(STREAM_STOP.code)
        files = [job for job in jobs if not job.is_stream]
        if settings.scheduler is not None and files:
            _run_dask(files, settings, finish)
        elif settings.jobs <= 1 or len(files) <= 1:
            for job in files:
                finish(process_input(job, settings, on_start(job, 0) if on_start else None))
        else:
            _run_pool(files, settings, finish)
        order = {job: i for i, job in enumerate(jobs)}
        results.sort(key=lambda r: order.get(r.job, 0))
        if len(jobs) > 1:
            _write_batch_events(settings.output, results)
            _write_batch_tracks(settings.output, results)
    return RunResult(results)


def _write_batch_events(output: Path, results: list[InputResult]) -> None:
    """One events.csv at the top level listing every input's events."""
    with atomic_text(output / "events.csv") as fp:
        write_events_csv(fp, batch_events(output, results), with_input=True)


def _write_batch_tracks(output: Path, results: list[InputResult]) -> None:
    """One tracks.csv at the top level listing every finished input's tracks,
    by today's columns (an input finished by an earlier version, which wrote
    fewer, leaves the later ones empty)."""
    rows = []
    for result in results:
        path = output / result.job.name / "tracks.csv"
        if result.status == "failed" or not path.is_file():
            continue
        with open(path, encoding="utf-8", newline="") as fp:
            for row in csv.DictReader(fp):
                rows.append([result.job.label, *(row.get(c) or "" for c in TRACK_COLUMNS)])
    with atomic_text(output / "tracks.csv") as fp:
        write_batch_tracks_csv(fp, rows)


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
        rows.extend({**ev, "input": result.job.label} for ev in summary.get("events", []))
    return rows
