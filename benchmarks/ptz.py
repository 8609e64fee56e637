"""The shared static-camera clips seen through a virtual pan-tilt-zoom camera.

    python benchmarks/ptz.py /tmp/ptz --pan 0.01
    MOTIONDETECT_DATA=/tmp/ptz python benchmarks/sweep.py davis,ucsd,sbi '{"default": {}}'

A static camera's clip is real footage whose ground truth is exact at every
pixel; a window moved over it is the same footage from a camera that pans,
tilts and zooms, as a surveillance dome (changedetection.net's PTZ
category) or a robot's head moves, with the truth moved alike. The scene
behind the movers stays a plane (the clip's own picture), so a rigid point's
motion is the window's alone, a homography: no parallax, and every flagged
region off the movers is a false alarm the camera's motion caused.

Each static-camera clip with masks (SBI IBMtest2, UCSD peds and traffic,
DAVIS breakdance) is written into ``OUT`` in its own layout, as
near-lossless JPEGs (masks as PNGs, nearest-neighbour, CDnet's 170
"unknown" kept). The window holds ``--window`` of each side at no zoom, and
its picture is the output frame's (enlarged when zoomed in: a digital
zoom's softness):

* ``--pan S`` and ``--tilt S``: the window moves S of the output's width
  (height) a frame, back and forth between the picture's edges; turning
  back at an edge is an abrupt change of the camera's motion;
* ``--zoom A``: it zooms in to ``1 + A`` times and back out over
  ``--period`` frames, around its moving centre;
* ``--hold K``: it moves for K frames, then stands for K, and so on
  (changedetection.net's intermittent pan);
* ``--jump K``: every K frames it jumps to the picture's other end (a PTZ
  camera switching between two presets: a cut).
"""

from __future__ import annotations

import argparse
import shutil
from pathlib import Path

import cv2
import numpy as np
from common import SHARED_DATA
from subsample import numbered

from motiondetect.io.files import last_number

#: (data set, clip, frames folder, ground-truth folder) of the static-camera clips.
STATIC = (
    ("sbi", "IBMtest2", "input", "groundtruth"),
    ("ucsd", "peds", "in", "groundtruth"),
    ("ucsd", "traffic", "in", "groundtruth"),
    ("davis", "breakdance", "JPEGImages", "Annotations"),
)


def _bounce(travel: float) -> float:
    """A position in [0, 1] that has travelled ``travel`` back and forth from 0."""
    phase = travel % 2.0
    return phase if phase <= 1.0 else 2.0 - phase


def _moving_frames(t: int, hold: int) -> int:
    """Frames the window has moved on before frame ``t``: all of them, or with
    ``hold`` K the first K of every 2K (it stands for the other K)."""
    if hold <= 0:
        return t
    return (t // (2 * hold)) * hold + min(t % (2 * hold), hold)


def window(t: int, size: tuple[int, int], args: argparse.Namespace) -> np.ndarray:
    """The 2x3 affine map from frame ``t``'s output pixels to the picture's
    (``size``: the picture's width and height)."""
    width, height = size
    moved = _moving_frames(t, args.hold)
    zoom = 1.0
    if args.zoom > 0:
        zoom += args.zoom * (1.0 - np.cos(2.0 * np.pi * moved / args.period)) / 2.0
    out_w, out_h = args.window * width, args.window * height
    win_w, win_h = out_w / zoom, out_h / zoom
    spare_w, spare_h = width - win_w, height - win_h
    rest = 0.0 if args.jump > 0 else 0.5  # where a still window stands: the two presets' one end
    across = _bounce(moved * args.pan * out_w / max(spare_w, 1e-9)) if args.pan > 0 else rest
    down = _bounce(moved * args.tilt * out_h / max(spare_h, 1e-9)) if args.tilt > 0 else rest
    if args.jump > 0 and (t // args.jump) % 2:
        across, down = 1.0 - across, 1.0 - down
    scale = 1.0 / zoom
    return np.array([[scale, 0.0, across * spare_w], [0.0, scale, down * spare_h]])


def output_size(size: tuple[int, int], args: argparse.Namespace) -> tuple[int, int]:
    return round(args.window * size[0]), round(args.window * size[1])


def seen(image: np.ndarray, t: int, args: argparse.Namespace, nearest: bool = False) -> np.ndarray:
    """Frame ``t``'s view of ``image`` (a frame or its mask)."""
    size = (image.shape[1], image.shape[0])
    flags = (cv2.INTER_NEAREST if nearest else cv2.INTER_LINEAR) | cv2.WARP_INVERSE_MAP
    return cv2.warpAffine(image, window(t, size, args), output_size(size, args), flags=flags)


def write_clip(source: Path, frames: str, truth: str, target: Path, args) -> None:
    """The clip in ``source`` through the window into ``target``."""
    images = numbered(source / frames, ".jpg") or numbered(source / frames, ".png")
    index = {last_number(p): t for t, p in enumerate(images)}
    (target / frames).mkdir(parents=True, exist_ok=True)
    for t, path in enumerate(images):
        name = target / frames / f"{path.stem}.jpg"
        cv2.imwrite(str(name), seen(cv2.imread(str(path)), t, args), [cv2.IMWRITE_JPEG_QUALITY, 99])
    (target / truth).mkdir(parents=True, exist_ok=True)
    for mask in numbered(source / truth, ".png"):
        t = index.get(last_number(mask))
        if t is not None:
            image = cv2.imread(str(mask), cv2.IMREAD_UNCHANGED)
            cv2.imwrite(str(target / truth / mask.name), seen(image, t, args, nearest=True))
    if (source / "temporalROI.txt").exists():  # the frames CDnet scores
        shutil.copy(source / "temporalROI.txt", target / "temporalROI.txt")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path)
    parser.add_argument("--window", type=float, default=0.7, help="share of each side, 0.3-1")
    parser.add_argument("--pan", type=float, default=0.0, help="share of the width a frame")
    parser.add_argument("--tilt", type=float, default=0.0, help="share of the height a frame")
    parser.add_argument("--zoom", type=float, default=0.0, help="zoomed in to 1 + A times")
    parser.add_argument("--period", type=float, default=40.0, help="frames of a zoom in and out")
    parser.add_argument("--hold", type=int, default=0, help="frames moving, then standing")
    parser.add_argument("--jump", type=int, default=0, help="frames between preset switches")
    args = parser.parse_args()
    if not 0.3 <= args.window <= 1.0 or min(args.pan, args.tilt, args.zoom) < 0:
        parser.error("--window must be in [0.3, 1]; --pan, --tilt and --zoom at least 0")
    if args.period <= 0:
        parser.error("--period must be above 0")
    written = 0
    for group, clip, frames, truth in STATIC:
        source = SHARED_DATA / group / clip
        if (source / frames).is_dir():
            written += 1
            write_clip(source, frames, truth, args.out / group / clip, args)
    print(f"{written} clips written into {args.out}")


if __name__ == "__main__":
    main()
