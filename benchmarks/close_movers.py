"""DAVIS's movers seen close up: each clip cropped so that its mover fills a given share.

    python benchmarks/close_movers.py /tmp/close --share 0.5
    MOTIONDETECT_DATA=/tmp/close python benchmarks/sweep.py davis \\
        '{"default": {}, "no order": {"fit": {"occluder_frames": 0}}}' --per-sequence

A mover that fills about half the view from the first frame takes the
plane's motion, and no track is ever on it to leave it out of the fit (the
layer order, ``[fit] occluder_frames``, is for this case). The shared clips
hold no such mover: DAVIS's fill about a tenth of the frame. This makes
them: a window of the frame's aspect whose area is the mover's median area
over ``share``, centred on the mover's centroid smoothed over 9 frames (a
virtual camera following the mover, as a close follow shot does), or held
where it starts with ``--fixed``. The crop is written at its own size
(never scaled) as JPEG with its cropped masks, in DAVIS's layout, so that
every benchmark reads it through ``MOTIONDETECT_DATA``. Clips whose window
would be under ``--min-width`` px wide are left out.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import cv2
import numpy as np
from common import SHARED_DATA
from subsample import numbered


def centroids(masks: list[np.ndarray]) -> np.ndarray:
    """(N, 2) x, y of each mask's centre; a frame without the mover keeps the last."""
    out, last = [], None
    for m in masks:
        ys, xs = np.nonzero(m)
        last = (xs.mean(), ys.mean()) if xs.size else last
        out.append(last)
    first = next(c for c in out if c is not None)
    return np.array([c if c is not None else first for c in out], float)


def window(masks: list[np.ndarray], share: float, fixed: bool) -> tuple[int, int, np.ndarray]:
    """(width, height, (N, 2) top-left corners) of the crop, inside the frame."""
    h, w = masks[0].shape
    area = float(np.median([m.sum() for m in masks])) / share
    cw = int(min(w, round(np.sqrt(area * w / h))))
    ch = int(min(h, round(cw * h / w)))
    centre = centroids(masks)
    if fixed:
        centre = np.repeat(centre[:1], len(masks), axis=0)
    else:
        kernel = np.ones(9) / 9
        padded = np.pad(centre, ((4, 4), (0, 0)), mode="edge")
        centre = np.stack([np.convolve(padded[:, i], kernel, "valid") for i in (0, 1)], axis=1)
    x = np.clip(np.round(centre[:, 0] - cw / 2), 0, w - cw).astype(int)
    y = np.clip(np.round(centre[:, 1] - ch / 2), 0, h - ch).astype(int)
    return cw, ch, np.stack([x, y], axis=1)


def crop_clip(seq: Path, out: Path, share: float, fixed: bool, min_width: int) -> str:
    frames = numbered(seq / "JPEGImages", ".jpg")
    masks = [cv2.imread(str(seq / "Annotations" / f"{f.stem}.png"), 0) > 0 for f in frames]
    cw, ch, corners = window(masks, share, fixed)
    if cw < min_width:
        return f"{seq.name}: left out, window {cw}x{ch}"
    shares = []
    for frame, mask, (x, y) in zip(frames, masks, corners):
        image = cv2.imread(str(frame))[y : y + ch, x : x + cw]
        part = mask[y : y + ch, x : x + cw]
        shares.append(part.mean())
        target = out / "davis" / seq.name
        (target / "JPEGImages").mkdir(parents=True, exist_ok=True)
        (target / "Annotations").mkdir(parents=True, exist_ok=True)
        cv2.imwrite(str(target / "JPEGImages" / frame.name), image, [cv2.IMWRITE_JPEG_QUALITY, 95])
        cv2.imwrite(str(target / "Annotations" / f"{frame.stem}.png"), part.astype(np.uint8) * 255)
    return (
        f"{seq.name}: {cw}x{ch}, mover's share first {shares[0]:.2f}, "
        f"median {np.median(shares):.2f}, range {min(shares):.2f}-{max(shares):.2f}"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path)
    parser.add_argument("--share", type=float, default=0.5, help="the mover's median share")
    parser.add_argument("--fixed", action="store_true", help="hold the window where it starts")
    parser.add_argument("--min-width", type=int, default=160)
    args = parser.parse_args()
    if not 0 < args.share <= 1:
        parser.error("--share must be in (0, 1]")
    for seq in sorted(p.parent for p in (SHARED_DATA / "davis").glob("*/JPEGImages")):
        print(crop_clip(seq, args.out, args.share, args.fixed, args.min_width))


if __name__ == "__main__":
    main()
