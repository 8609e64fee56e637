"""Where a sequence's ground truth is, and which predicted frame each of
its files scores.

Ground truth is a folder of PNG masks (or a sequence folder holding one as
``groundtruth/``, ``Annotations/``, ``truth/`` or ``masks/``), or a text
file of boxes, one ``x,y,w,h`` line per frame (OTB's
``groundtruth_rect.txt``); :mod:`motiondetect.tools.evaluate` scores them.
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Mapping
from pathlib import Path

from motiondetect.io.files import last_number

GT_FOLDERS = ("groundtruth", "Annotations", "truth", "masks")
GT_BOXES = "groundtruth_rect.txt"


class EvaluateError(ValueError):
    """Inputs to evaluate cannot be used; one line for the user."""


def find_gt_folder(path: Path) -> Path:
    """The folder of masks ``path`` is or holds (one of :data:`GT_FOLDERS`)."""
    if not path.is_dir():
        raise EvaluateError(f"{path}: ground truth must be a folder of PNG masks or a box file")
    for name in GT_FOLDERS:
        if (path / name).is_dir():
            return path / name
    return path


def temporal_roi(gt_folder: Path) -> tuple[int, int] | None:
    """(first, last) GT number scored, from a CDnet ``temporalROI.txt`` in or
    beside ``gt_folder``; None when there is none (or it is unreadable)."""
    for candidate in (gt_folder / "temporalROI.txt", gt_folder.parent / "temporalROI.txt"):
        if candidate.is_file():
            try:
                first, last = (int(v) for v in candidate.read_text().split()[:2])
                return first, last
            except ValueError:
                return None
    return None


def find_gt_boxes(path: Path) -> Path | None:
    """The box file ``path`` is or holds, if any."""
    if path.is_file() and path.suffix.lower() == ".txt":
        return path
    if path.is_dir() and (path / GT_BOXES).is_file():
        return path / GT_BOXES
    return None


def read_boxes(path: Path) -> list[tuple[int, int, int, int]]:
    """One ``(x, y, w, h)`` box per frame, input px; blank lines skipped."""
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise EvaluateError(f"{path}: cannot read boxes ({exc.__class__.__name__})") from None
    boxes = []
    for number, line in enumerate(text.splitlines(), 1):
        if not line.strip():
            continue
        try:
            x, y, w, h = (int(float(v)) for v in line.replace("\t", ",").split(","))
        except ValueError:
            raise EvaluateError(
                f"{path}:{number}: expected 'x,y,w,h', got {line.strip()!r}"
            ) from None
        boxes.append((x, y, w, h))
    if not boxes:
        raise EvaluateError(f"{path}: no boxes")
    return boxes


def index_by_number(pairs: Iterable[tuple[int, int]]) -> dict[int, int] | None:
    """{number in a frame file's name: frame index} from ``(number, index)``
    pairs; None when there are none, or a number is missing (negative) or
    repeats (two cameras' frames in one folder): then no number names one
    frame."""
    numbers: dict[int, int] = {}
    for number, index in pairs:
        if number < 0 or number in numbers:
            return None
        numbers[number] = index
    return numbers or None


def recorded_numbers(pred_dir: Path) -> dict[int, int] | None:
    """:func:`index_by_number` of the ``frames.jsonl`` beside ``pred_dir``
    (an output folder's ``masks/``, or the folder itself); None when there
    is none or it records no numbers (a video)."""
    for folder in (pred_dir, pred_dir.parent):
        path = folder / "frames.jsonl"
        if path.is_file():
            break
    else:
        return None
    try:
        with open(path, encoding="utf-8") as lines:  # read a line at a time: long runs
            records = (json.loads(line) for line in lines)
            return index_by_number((int(r.get("number", -1)), int(r["frame"])) for r in records)
    except (OSError, UnicodeDecodeError, ValueError, TypeError, KeyError, AttributeError):
        return None  # not this tool's records: aligned by the GT's own numbers


def aligned_truth(gt_files: list[Path], numbers: Mapping[int, int] | None) -> dict[int, Path]:
    """{predicted frame index: the GT file that scores it}.

    Parameters
    ----------
    gt_files : list of Path
        Ground-truth files, each with a number in its name, sorted by it.
    numbers : mapping of int to int, or None
        {number in a frame file's name: frame index} (:func:`recorded_numbers`).

    Returns
    -------
    dict of int to Path
        With ``numbers`` holding any GT number, GT number ``n`` scores frame
        ``numbers[n]`` (and a GT file whose frame was not read, none);
        otherwise GT number ``n`` scores frame ``n - first``, ``first`` the
        smallest GT number.
    """
    by_number = {last_number(p): p for p in gt_files}
    if numbered_alike(gt_files, numbers):
        return {numbers[n]: p for n, p in by_number.items() if n in numbers}
    first = min(by_number)
    return {n - first: p for n, p in by_number.items()}


def numbered_alike(gt_files: list[Path], numbers: Mapping[int, int] | None) -> bool:
    """Whether :func:`aligned_truth` matches ``gt_files`` by the frame files'
    ``numbers``: there are numbers and some truth file carries one."""
    return bool(numbers) and any(last_number(p) in numbers for p in gt_files)


def aligned_boxes(count: int, numbers: Mapping[int, int] | None) -> dict[int, int]:
    """{predicted frame index: the box file's line that scores it}, for
    ``count`` lines, one per frame from the first (OTB's line ``i`` is the
    frame numbered ``first + i``).

    With ``numbers`` (:func:`recorded_numbers`), line ``k`` scores the frame
    read from the file numbered ``first + k``, ``first`` the first file's
    number (the first frame read's number less its index: files before it
    that were skipped as unreadable are counted), so a file missing from the
    numbering shifts no box; otherwise line ``k`` scores frame ``k``.
    """
    if not numbers:
        return {k: k for k in range(count)}
    first = first_file_number(numbers)
    return {numbers[first + k]: k for k in range(count) if first + k in numbers}


def first_file_number(numbers: Mapping[int, int]) -> int:
    """The number of an input's first frame file: the first frame read's
    number less its index (files before it skipped as unreadable counted)."""
    first = min(numbers)
    return first - numbers[first]
