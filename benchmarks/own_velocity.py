"""Each detection's own velocity, with and without a panning camera.

    python benchmarks/own_velocity.py [--pan 0.02]

A detection's own velocity (``own_velocity_px_s`` in frames.jsonl) is its
image velocity less the camera's: it should not depend on how the camera
moves. The still-camera clips with truth (SBI IBMtest2, UCSD peds and
traffic, DAVIS breakdance) are run twice through ``ptz.py``'s window: still,
and panning ``--pan`` of the width a frame (back and forth). The same
mover on the same frame is matched between the two by its box centre in the
clip's own pixels (within ``--match`` px). For each matched pair this
prints the median difference of their own velocities, against the median
own speed itself, and how far the difference of their image velocities is
from the window's motion (the background's image velocity in the pan
copy); output px per second at 30 frames/s.
"""

from __future__ import annotations

import argparse

import cv2
import numpy as np
from common import SHARED_DATA
from ptz import STATIC, seen, window
from subsample import numbered

from motiondetect import detect

FPS = 30.0


def _views(images: list, still: argparse.Namespace, moving: argparse.Namespace):
    """Each frame through the still window and the moving one."""
    for t, path in enumerate(images):
        image = cv2.imread(str(path))
        yield t, seen(image, t, still), seen(image, t, moving)


def _detections(frames: list, fps: float) -> list[list]:
    """Per frame: (box centre, velocity, own velocity) of each detection not held."""
    out = []
    for result in detect(frames, fps=fps, frame_skip=0):
        found = []
        for r in result.regions:
            if r.held or r.velocity_px_s is None:
                continue
            x, y, w, h = r.bbox
            found.append(((x + w / 2, y + h / 2), r.velocity_px_s, r.own_velocity_px_s))
        out.append(found)
    return out


def _in_source(centre: tuple, t: int, size: tuple, args) -> np.ndarray:
    return window(t, size, args) @ np.array([centre[0], centre[1], 1.0])


def clip_pairs(name: str, images: list, pan: float, match_px: float) -> list[tuple]:
    """(own difference, own speed, image difference less the window's motion),
    px/s, for each mover matched between the still and the panning views."""
    base = dict(window=0.7, tilt=0.0, zoom=0.0, period=60, hold=0, jump=0)
    still, moving = argparse.Namespace(pan=0.0, **base), argparse.Namespace(pan=pan, **base)
    first = cv2.imread(str(images[0]))
    size = (first.shape[1], first.shape[0])
    views = list(_views(images, still, moving))
    a = _detections([v[1] for v in views], FPS)
    b = _detections([v[2] for v in views], FPS)
    pairs = []
    for t in range(1, len(views)):
        # The background's image velocity in the panning view: minus the window's shift.
        shift = window(t, size, moving)[:, 2] - window(t - 1, size, moving)[:, 2]
        for centre, velocity, own in b[t]:
            where = _in_source(centre, t, size, moving)
            near = [
                d for d in a[t] if np.hypot(*(_in_source(d[0], t, size, still) - where)) < match_px
            ]
            if len(near) != 1:
                continue
            _, velocity_still, own_still = near[0]
            own_gap = float(np.hypot(*np.subtract(own, own_still)))
            moved = np.subtract(velocity, velocity_still) + shift * FPS
            pairs.append((own_gap, float(np.hypot(*own_still)), float(np.hypot(*moved))))
    print(f"{name:22s} {len(pairs):5d} pairs", _summary(pairs))
    return pairs


def _summary(pairs: list[tuple]) -> str:
    if not pairs:
        return ""
    own_gap, own_speed, image_gap = np.median(np.array(pairs), axis=0)
    return (
        f"own speed {own_speed:6.1f}  own still vs panning {own_gap:5.1f}  "
        f"image difference less the pan {image_gap:5.1f}  (px/s, medians)"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pan", type=float, default=0.02, help="share of the width a frame")
    parser.add_argument("--match", type=float, default=12.0, help="box centres within, px")
    args = parser.parse_args()
    every = []
    for data_set, clip, frames, _ in STATIC:
        source = SHARED_DATA / data_set / clip / frames
        images = numbered(source, ".jpg") or numbered(source, ".png")
        if images:
            every += clip_pairs(f"{data_set}/{clip}", images, args.pan, args.match)
    print(f"{'all':22s} {len(every):5d} pairs", _summary(every))


if __name__ == "__main__":
    main()
