"""Inputs of a batch: what each INPUT argument expands to, and its output name.

Video files, frames folders, or directories of videos; ``recursive``
descends, and frames folders found inside count as inputs. Outputs per
input go to ``OUT/<name>/`` where ``<name>`` mirrors the input's path
relative to the batch directory (or is the input's stem).
"""

from __future__ import annotations

import hashlib
import logging
import re
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from motiondetect.io.decode import STDIN, is_device, is_stream_location
from motiondetect.io.files import display_name
from motiondetect.io.video import (
    IMAGE_EXTENSIONS,
    VIDEO_EXTENSIONS,
    is_animated,
    is_frames_folder,
)

log = logging.getLogger("motiondetect")

Progress = Callable[[int, int], None]  # (frames done, frames expected)


class InputError(Exception):
    """A user-facing, one-line problem with one input."""


@dataclass(frozen=True)
class InputJob:
    """One input of a batch and its output folder name.

    ``location`` is set for a *stream*, read once as it arrives: a URL,
    ``-`` (standard input) or a capture device. A stream is never skipped as
    finished, and has no second pass (clips, thumbnails).
    """

    path: Path
    name: str  # relative output folder name
    location: str | None = None

    @property
    def is_stream(self) -> bool:
        return self.location is not None

    @property
    def source(self) -> str | Path:
        """What :func:`~motiondetect.io.video.open_source` opens."""
        return self.path if self.location is None else self.location

    @property
    def label(self) -> str:
        """The input as the user named it, for messages."""
        return display_name(self.path if self.location is None else self.location)


@dataclass
class InputResult:
    job: InputJob
    status: str  # "done", "skipped", "failed"
    message: str = ""
    summary: dict = field(default_factory=dict)


def stream_job(location: str) -> InputJob:
    """The job of a URL, ``-`` or a capture device; its name is readable and safe."""
    if location == STDIN:
        name = "stdin"
    else:
        name = re.sub(r"[^A-Za-z0-9._-]+", "_", location.split("://", 1)[-1]).strip("._")
    return InputJob(Path(name or "stream"), name or "stream", location)


def discover_inputs(
    paths: list[str | Path],
    recursive: bool,
    *,
    output: Path | None = None,
    include: tuple[str, ...] = (),
    exclude: tuple[str, ...] = (),
) -> list[InputJob]:
    """Expand INPUT arguments into jobs (docs/cli.md states the rule).

    Each argument is an input, except a directory that is not a frames
    folder: it is scanned for videos (and, with ``recursive``, sub-folders
    and frames folders). A scan visits each real path once (symlink loops
    end), never enters ``output`` or a folder holding the tool's own outputs,
    honours ``include``/``exclude`` globs on the path relative to the scanned
    directory (``*.mp4``, ``Annotations``), and skips files that are not
    videos with one warning line. An input given twice, or given and also
    found in a folder given, is taken once (with a warning). Names are
    unique by construction (:func:`unique_names`).
    """
    scanner = _Scanner(recursive, output, include, exclude)
    jobs: list[InputJob] = []
    for given in paths:
        if isinstance(given, str) and is_stream_location(given):
            jobs.append(stream_job(given))
            continue
        path = Path(given)
        if is_device(path):
            jobs.append(stream_job(str(path)))
        elif scanner.seen_before(path):
            log.warning("%s: given more than once (or found in a folder given); taken once", given)
        elif path.is_dir() and not is_frames_folder(path):
            repeats = scanner.repeats
            found = scanner.scan(path)
            if not found and scanner.repeats == repeats:  # none: fails later with a clear message
                jobs.append(InputJob(path, path.name))
            jobs.extend(found)
        else:
            scanner.seen.add(path.resolve())
            name = path.name if path.is_dir() else path.stem
            jobs.append(InputJob(path, name or "input"))
    scanner.report()
    return unique_names(jobs)


def is_output_folder(path: Path) -> bool:
    """A folder this tool wrote for one input."""
    return (path / "summary.json").is_file() or (path / "frames.jsonl").is_file()


class _Scanner:
    def __init__(self, recursive, output, include, exclude) -> None:
        self.recursive, self.include, self.exclude = recursive, include, exclude
        self.output = output.resolve() if output is not None else None
        self.seen: set[Path] = set()
        self.repeats = 0  # inputs a scan found but had taken already
        self.ignored: list[str] = []

    def _wanted(self, rel: Path, is_input: bool) -> bool:
        if any(rel.match(p) for p in self.exclude):
            return False
        return not (is_input and self.include) or any(rel.match(p) for p in self.include)

    def seen_before(self, path: Path) -> bool:
        """Whether ``path`` (its real path) was given or found already."""
        return path.resolve() in self.seen

    def _first_visit(self, path: Path) -> bool:
        real = path.resolve()
        if real in self.seen or real == self.output:
            self.repeats += real in self.seen
            return False
        self.seen.add(real)
        return True

    def scan(self, root: Path, prefix: Path = Path()) -> list[InputJob]:
        jobs: list[InputJob] = []
        if not self._first_visit(root):
            return jobs
        for entry in sorted(root.iterdir()):
            rel = prefix / entry.name
            if entry.name.startswith(".") or not self._wanted(rel, is_input=False):
                continue
            if entry.is_dir():
                if not self.recursive or is_output_folder(entry):
                    continue
                if is_frames_folder(entry):
                    if self._wanted(rel, True) and self._first_visit(entry):
                        jobs.append(InputJob(entry, str(rel)))
                else:
                    jobs.extend(self.scan(entry, rel))
            elif entry.suffix.lower() in VIDEO_EXTENSIONS or (
                entry.suffix.lower() == ".gif" and is_animated(entry)
            ):
                if self._wanted(rel, True) and self._first_visit(entry):
                    jobs.append(InputJob(entry, str(rel.with_suffix(""))))
            elif entry.suffix.lower() not in IMAGE_EXTENSIONS:
                self.ignored.append(str(rel))
        return jobs

    def report(self) -> None:
        if self.ignored:
            log.warning(
                "skipped %d files that are not videos (e.g. %s)", len(self.ignored), self.ignored[0]
            )


def unique_names(jobs: list[InputJob]) -> list[InputJob]:
    """Output names, unique by construction and the same on every run.

    A name shared by several inputs becomes each one's file name with its
    extension (``a.mp4``, ``a.avi``); a name still taken then gets the
    smallest free ``-N`` suffix, checked against every name in the batch.
    """
    counts: dict[str, int] = {}
    for job in jobs:
        counts[job.name] = counts.get(job.name, 0) + 1
    taken: set[str] = set()
    out = []
    for job in jobs:
        name = job.name
        if counts[name] > 1 and job.path.suffix:
            name = str(Path(name).with_name(job.path.name))
        base, n = name, 2
        while name in taken:
            name, n = f"{base}-{n}", n + 1
        taken.add(name)
        out.append(InputJob(job.path, name, job.location))
    return out


def input_identity(job: InputJob) -> dict:
    """What makes an input the same input on a re-run: its real path, size,
    modification time and a hash of its first MiB (of its file list, for a
    frames folder). A stream has only its location: it is never the same."""
    if job.is_stream:
        return {"path": job.location, "stream": True}
    path = job.path
    real = path.resolve()
    stat = real.stat()
    digest = hashlib.sha256()
    if real.is_dir():
        entries = sorted(real.iterdir())
        for entry in entries:
            digest.update(f"{entry.name}:{entry.stat().st_size}\n".encode())
        size = len(entries)
    else:
        with open(real, "rb") as fp:
            digest.update(fp.read(1 << 20))
        size = stat.st_size
    return {
        "path": str(real),
        "size": size,
        "mtime_ns": stat.st_mtime_ns,
        "head_sha256": digest.hexdigest()[:32],
    }
