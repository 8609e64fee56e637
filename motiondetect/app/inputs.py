"""Inputs of a batch: what each INPUT argument expands to, and its output name.

Video files, frames folders, or directories of videos; ``recursive``
descends, and frames folders found inside count as inputs. Outputs per
input go to ``OUT/<name>/`` where ``<name>`` mirrors the input's path
relative to the batch directory (or is the input's stem).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from motiondetect.io.video import IMAGE_EXTENSIONS, is_frames_folder

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
