"""The shared clips as a dim sensor or an auto-exposing phone would deliver them.

Each DAVIS clip, UCSD's moving-camera clips and the fox clip (no mover: every
region is a false alarm) are written into ``OUT`` with

* ``--noise SIGMA``: Gaussian sensor noise of ``SIGMA`` grey levels, drawn
  afresh for every pixel, channel and frame (seeded);
* ``--exposure A``: a brightness gain of ``1 + A sin(2 pi t / 30)`` on frame
  ``t``, an exposure that drifts by up to ``A`` and changes by up to ``A/5`` a
  frame, as a phone's automatic exposure does when the view moves;

as near-lossless JPEGs under the same names, with the ground truth linked,
not copied. The frames never leave this machine::

    python benchmarks/degrade.py /tmp/noise8 --noise 8
    MOTIONDETECT_DATA=/tmp/noise8 python benchmarks/sweep.py davis,ucsd,fox '{"default": {}}'
"""

from __future__ import annotations

import argparse
from pathlib import Path

import cv2
import numpy as np
from common import SHARED_DATA
from subsample import moving_clips, numbered


def degraded(image: np.ndarray, t: int, noise: float, exposure: float, rng) -> np.ndarray:
    """Frame ``t`` (uint8) with the exposure drift and the sensor noise applied."""
    out = image.astype(np.float32) * np.float32(1.0 + exposure * np.sin(2 * np.pi * t / 30))
    if noise > 0:
        out += rng.normal(0.0, noise, image.shape).astype(np.float32)
    return np.clip(np.rint(out), 0, 255).astype(np.uint8)


def degrade(frames: list[Path], target: Path, noise: float, exposure: float, seed: int) -> None:
    """Write each of ``frames`` degraded into ``target``, under its own name."""
    rng = np.random.default_rng(seed)
    target.mkdir(parents=True, exist_ok=True)
    for t, path in enumerate(frames):
        image = degraded(cv2.imread(str(path)), t, noise, exposure, rng)
        cv2.imwrite(str(target / path.name), image, [cv2.IMWRITE_JPEG_QUALITY, 99])


def _link(source: Path, target: Path) -> None:
    if not target.exists():
        target.parent.mkdir(parents=True, exist_ok=True)
        target.symlink_to(source.resolve())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path)
    parser.add_argument("--noise", type=float, default=0.0, help="grey levels (sigma)")
    parser.add_argument("--exposure", type=float, default=0.0, help="gain amplitude, 0-1")
    args = parser.parse_args()
    if args.noise < 0 or not 0 <= args.exposure < 1:
        parser.error("--noise must be at least 0 and --exposure within [0, 1)")
    clips = [(im, truth, args.out / group / im.parent.name) for im, truth, group in moving_clips()]
    fox = SHARED_DATA / "fox"
    if (fox / "images").is_dir():
        clips.append((fox / "images", fox / "transforms.json", args.out / "fox"))
    for seed, (images, truth, target) in enumerate(clips):
        frames = numbered(images, ".jpg") or numbered(images, ".png")
        degrade(frames, target / images.name, args.noise, args.exposure, seed)
        _link(truth, target / truth.name)
    print(f"{len(clips)} clips, noise {args.noise}, exposure {args.exposure}, in {args.out}")


if __name__ == "__main__":
    main()
