"""A lower frame rate of the shared clips, or repeated frames, for checking that results hold.

Every ``step``-th frame of each DAVIS clip and of UCSD's moving-camera clips
(with its ground truth) is linked, renumbered, into ``OUT``; nothing is
copied. Motion per frame grows ``step`` times, as in footage shot at a lower
frame rate::

    python benchmarks/subsample.py /tmp/half --step 2
    MOTIONDETECT_DATA=/tmp/half python benchmarks/compare.py --out /tmp/half.md

With ``--repeat N`` every frame is kept and each ``N``-th is shown twice,
as a 24 fps film converted to 30 fps by repeating frames (``--repeat 4``),
a screen recording or a phone's video in low light delivers it::

    python benchmarks/subsample.py /tmp/repeat4 --repeat 4
"""

from __future__ import annotations

import argparse
from pathlib import Path

from common import SHARED_DATA

from motiondetect.io.files import last_number

UCSD_MOVING = ("birds", "cyclists", "surfers", "landing")


def _link(source: Path, target: Path) -> None:
    target.parent.mkdir(parents=True, exist_ok=True)
    target.unlink(missing_ok=True)
    target.symlink_to(source.resolve())


def numbered(folder: Path, suffix: str) -> list[Path]:
    return sorted(folder.glob(f"*{suffix}"), key=last_number)


def moving_clips() -> list[tuple[Path, Path, str]]:
    """(images, ground truth, data set) of each DAVIS clip and of UCSD's
    moving-camera clips that exist, sorted."""
    clips = [
        (p, p.parent / "Annotations", "davis") for p in (SHARED_DATA / "davis").glob("*/JPEGImages")
    ]
    clips += [
        (SHARED_DATA / "ucsd" / n / "in", SHARED_DATA / "ucsd" / n / "groundtruth", "ucsd")
        for n in UCSD_MOVING
    ]
    return sorted(c for c in clips if c[0].is_dir())


def picked(frames: list[Path], step: int, repeat: int = 0) -> list[Path]:
    """Every ``step``-th of ``frames``; with ``repeat`` N, each N-th twice."""
    frames = frames[::step]
    if repeat <= 0:
        return frames
    return [
        f
        for i, frame in enumerate(frames)
        for f in [frame] * (2 if i % repeat == repeat - 1 else 1)
    ]


def subsample_davis(out: Path, step: int, repeat: int = 0) -> int:
    clips = 0
    for images in sorted((SHARED_DATA / "davis").glob("*/JPEGImages")):
        masks = images.parent / "Annotations"
        for new, frame in enumerate(picked(numbered(images, ".jpg"), step, repeat)):
            seq = out / "davis" / images.parent.name
            _link(frame, seq / "JPEGImages" / f"{new:05d}.jpg")
            _link(masks / f"{frame.stem}.png", seq / "Annotations" / f"{new:05d}.png")
        clips += 1
    return clips


def subsample_ucsd(out: Path, step: int, repeat: int = 0) -> int:
    clips = 0
    for name in UCSD_MOVING:
        seq = SHARED_DATA / "ucsd" / name
        if not seq.is_dir():
            continue
        for new, frame in enumerate(picked(numbered(seq / "in", ".jpg"), step, repeat), start=1):
            truth = seq / "groundtruth" / f"gt{last_number(frame):04d}.png"
            _link(frame, out / "ucsd" / name / "in" / f"frame_{new}.jpg")
            if truth.exists():
                _link(truth, out / "ucsd" / name / "groundtruth" / f"gt{new:04d}.png")
        clips += 1
    return clips


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path)
    parser.add_argument("--step", type=int, default=None, help="keep every step-th frame (2)")
    parser.add_argument("--repeat", type=int, default=0, help="show every N-th frame twice")
    args = parser.parse_args()
    step = args.step or (1 if args.repeat else 2)
    if step < 1 or args.repeat < 0:
        parser.error("--step must be at least 1 and --repeat at least 0")
    davis = subsample_davis(args.out, step, args.repeat)
    ucsd = subsample_ucsd(args.out, step, args.repeat)
    shown = f", each {args.repeat}th twice" if args.repeat else ""
    print(f"{davis} DAVIS and {ucsd} UCSD clips at 1/{step} of their frames{shown} in {args.out}")


if __name__ == "__main__":
    main()
