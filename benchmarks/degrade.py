"""The shared clips as a dim sensor or an auto-exposing phone would deliver them.

Each DAVIS clip, UCSD's moving-camera clips and the fox clip (no mover: every
region is a false alarm) are written into ``OUT`` with

* ``--noise SIGMA``: Gaussian sensor noise of ``SIGMA`` grey levels, drawn
  afresh for every pixel, channel and frame (seeded);
* ``--exposure A``: a brightness gain of ``1 + A sin(2 pi t / 30)`` on frame
  ``t``, an exposure that drifts by up to ``A`` and changes by up to ``A/5`` a
  frame, as a phone's automatic exposure does when the view moves;
* ``--distortion K``: a wide-angle lens's barrel distortion, Fitzgibbon's
  division model ``p_u = p_d / (1 + K r_d^2)`` (``K`` below 0; ``r_d`` in
  half-diagonals), scaled so that the corners stay the corners; the ground
  truth masks are warped with the frames (an action camera or a dashcam is
  about -0.2 to -0.4);
* ``--overlay``: a dashcam's burnt-in caption, white text outlined in black
  along the bottom left (a date, a clock that ticks every 30 frames and a
  speed), fixed to the screen while the view moves;
* ``--letterbox F`` and ``--pillarbox F``: black bars above and below (each
  ``F`` of the height) or left and right (each ``F`` of the width), as a
  film in a 16:9 frame or a 4:3 or upright phone clip posted at 16:9 shows;
  the ground truth masks get the same bars, marked static;
* ``--blurred-sides``: with ``--pillarbox``, the bars filled as social
  media fill them: the frame enlarged to the whole width, blurred (a
  Gaussian of 5 % of the width) and darkened, moving with the video;
* ``--hood F``: a part of the vehicle fixed in the view, as a dashcam or a
  bike's action camera sees its bonnet or handlebars: the bottom ``F`` of
  the height, under a curved edge, shows the same textured, darkened image
  on every frame (the clip's first frame, mirrored); the ground truth marks
  it static;
* ``--shake P``: a handheld camera shaken during the exposure: each frame,
  with probability ``P``, smeared along a line of a random direction and a
  length of 2-6 % of the width (a 1/30 s shutter on a jolt); the ground
  truth is unchanged (heavy blur: the frames the tool may call unreliable);
* ``--vibration A``: a mount's vibration (a vehicle, a walking operator):
  the view displaced by ``A`` of the width along each axis by two sines of
  6-12 Hz (30 frames a second assumed), seen through a rolling shutter that
  reads the rows top to bottom over ``--readout R`` of the frame period (a
  phone's CMOS sensor is about 0.5-0.9; 0, a global shutter, displaces each
  frame whole); each row shows the view at its own read time, so the picture
  wobbles (the "jello" effect) and the masks with it;
* ``--mirror``: each frame and mask mirrored left-right, the same footage
  as a camera turning and walking the other way would record it (nothing
  else changed: a detector built on principles finds the same, within its
  random draws);
* ``--rotate``: each frame and mask turned a quarter clockwise, the same
  footage as an upright (portrait) phone clip;
* ``--reverse``: the clip played backwards, its last frame first (frames and
  masks keep their names, in the order they had): every motion reversed, a
  rigid world still rigid;

as near-lossless JPEGs under the same names, with the ground truth linked,
not copied. The frames never leave this machine::

    python benchmarks/degrade.py /tmp/noise8 --noise 8
    MOTIONDETECT_DATA=/tmp/noise8 python benchmarks/sweep.py davis,ucsd,fox '{"default": {}}'
"""

from __future__ import annotations

import argparse
import functools
from pathlib import Path

import cv2
import numpy as np
from common import SHARED_DATA
from subsample import moving_clips, numbered

from motiondetect.tools.synth import smeared


@functools.lru_cache(maxsize=4)
def barrel_maps(width: int, height: int, k: float) -> tuple[np.ndarray, np.ndarray]:
    """``cv2.remap`` maps that give an image as a lens with division-model
    distortion ``k`` would record it: each recorded pixel ``p_d`` shows the
    scene at ``c + (1 + k) (p_d - c) / (1 + k r_d^2)``."""
    ys, xs = np.mgrid[0:height, 0:width].astype(np.float32)
    cx, cy = (width - 1) / 2, (height - 1) / 2
    half_diagonal = np.hypot(cx, cy)
    r2 = ((xs - cx) ** 2 + (ys - cy) ** 2) / half_diagonal**2
    scale = (1.0 + k) / (1.0 + k * r2)
    return (cx + (xs - cx) * scale).astype(np.float32), (cy + (ys - cy) * scale).astype(np.float32)


def _lens(image: np.ndarray, k: float, nearest: bool = False) -> np.ndarray:
    if k == 0:
        return image
    map_x, map_y = barrel_maps(image.shape[1], image.shape[0], k)
    interpolation = cv2.INTER_NEAREST if nearest else cv2.INTER_LINEAR
    return cv2.remap(image, map_x, map_y, interpolation, borderMode=cv2.BORDER_REFLECT)


def vibration_path(rng, amplitude: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Amplitudes (2, 2), angular frequencies (2, 2) in rad/s and phases
    (2, 2): two sines per axis (rows x, y), together at most ``amplitude``."""
    return (
        rng.uniform(0.5, 1.0, (2, 2)) * amplitude / 2,
        2 * np.pi * rng.uniform(6.0, 12.0, (2, 2)),
        rng.uniform(0.0, 2 * np.pi, (2, 2)),
    )


def wobbled(
    image: np.ndarray, t: int, path: tuple, readout: float, nearest: bool = False
) -> np.ndarray:
    """Frame ``t`` with each row displaced as ``path`` (in widths) has the
    view at that row's read time, ``(t + readout * row / height) / 30`` s."""
    h, w = image.shape[:2]
    amplitude, omega, phase = path
    times = (t + readout * np.arange(h) / h) / 30.0
    shift = (amplitude[..., None] * np.sin(omega[..., None] * times + phase[..., None])).sum(1)
    ys, xs = np.mgrid[0:h, 0:w].astype(np.float32)
    map_x = xs + (w * shift[0])[:, None].astype(np.float32)
    map_y = ys + (w * shift[1])[:, None].astype(np.float32)
    interpolation = cv2.INTER_NEAREST if nearest else cv2.INTER_LINEAR
    return cv2.remap(image, map_x, map_y, interpolation, borderMode=cv2.BORDER_REFLECT)


def caption(image: np.ndarray, t: int) -> np.ndarray:
    """``image`` with a dashcam's caption burnt in (its clock ticks every 30 frames)."""
    h, w = image.shape[:2]
    text = f"2026/11/26 14:03:{10 + t // 30:02d}  52 km/h"
    scale = h / 600
    origin = (int(0.03 * w), int(0.95 * h))
    out = image.copy()
    for colour, thick in (((0, 0, 0), 6), ((255, 255, 255), 2)):
        width = max(1, round(thick * scale))
        cv2.putText(out, text, origin, cv2.FONT_HERSHEY_SIMPLEX, scale, colour, width, cv2.LINE_AA)
    return out


def bars(
    image: np.ndarray, letterbox: float, pillarbox: float, blurred: bool = False
) -> np.ndarray:
    """``image`` with black bars: ``letterbox`` of its height above and below,
    ``pillarbox`` of its width left and right; ``blurred``: the side bars
    filled with the frame enlarged, blurred and darkened (masks stay black)."""
    h, w = image.shape[:2]
    dy, dx = round(letterbox * h), round(pillarbox * w)
    out = cv2.copyMakeBorder(image, dy, dy, dx, dx, cv2.BORDER_CONSTANT, value=0)
    if blurred and dx and image.ndim == 3:
        width = w + 2 * dx
        scale = width / w
        big = cv2.resize(image, (width, round(h * scale)), interpolation=cv2.INTER_LINEAR)
        top = (big.shape[0] - h) // 2
        back = cv2.GaussianBlur(big[top : top + h], (0, 0), 0.05 * width)
        back = (back.astype(np.float32) * 0.6).astype(np.uint8)
        out[dy : dy + h, :dx] = back[:, :dx]
        out[dy : dy + h, dx + w :] = back[:, dx + w :]
    return out


@functools.lru_cache(maxsize=4)
def hood_mask(width: int, height: int, share: float) -> np.ndarray:
    """Bool (height, width): the bottom ``share`` of the frame under an arc
    that rises by a further ``share / 2`` at the middle (a bonnet's edge)."""
    xs = np.linspace(-1.0, 1.0, width)[None, :]
    ys = np.arange(height)[:, None] / height
    return ys >= 1.0 - share * (1.0 + 0.5 * (1.0 - xs**2))


def dashboard(first: np.ndarray) -> np.ndarray:
    """What the part of the vehicle shows: ``first`` mirrored left-right and
    up-down, at 60 % brightness."""
    return (first[::-1, ::-1].astype(np.float32) * 0.6).astype(first.dtype)


def hooded(image: np.ndarray, part: np.ndarray, share: float) -> np.ndarray:
    """``image`` with its bottom ``share`` (:func:`hood_mask`) showing ``part``."""
    if share <= 0:
        return image
    out = image.copy()
    mask = hood_mask(image.shape[1], image.shape[0], share)
    out[mask] = part[mask]
    return out


def degraded(
    image: np.ndarray, t: int, noise: float, exposure: float, rng, distortion: float = 0.0,
    overlay: bool = False, letterbox: float = 0.0, pillarbox: float = 0.0,
    blurred: bool = False, smear: tuple[float, float] | None = None,
) -> np.ndarray:  # fmt: skip
    """Frame ``t`` (uint8) through the lens, smeared by ``smear`` (length px,
    direction rad; :func:`~motiondetect.tools.synth.smeared`), with the
    exposure drift and the sensor noise applied, the bars added and the
    caption burnt in last."""
    gain = np.float32(1.0 + exposure * np.sin(2 * np.pi * t / 30))
    out = _lens(image, distortion)
    if smear is not None:
        out = smeared(out, *smear)
    out = out.astype(np.float32) * gain
    if noise > 0:
        out += rng.normal(0.0, noise, image.shape).astype(np.float32)
    out = bars(np.clip(np.rint(out), 0, 255).astype(np.uint8), letterbox, pillarbox, blurred)
    return caption(out, t) if overlay else out


def _turned(image: np.ndarray, args: argparse.Namespace) -> np.ndarray:
    """``image`` mirrored left-right (``--mirror``) and turned a quarter
    clockwise (``--rotate``), as asked."""
    if args.mirror:
        image = image[:, ::-1]
    if args.rotate:
        image = cv2.rotate(np.ascontiguousarray(image), cv2.ROTATE_90_CLOCKWISE)
    return np.ascontiguousarray(image)


def _ordered(files: list[Path], args: argparse.Namespace) -> list[Path]:
    """``files`` in the order they are played: backwards with ``--reverse``."""
    return files[::-1] if args.reverse else files


def degrade(frames: list[Path], target: Path, args: argparse.Namespace, seed: int) -> None:
    """Write each of ``frames`` degraded into ``target``, under its own name."""
    rng = np.random.default_rng(seed)
    path = vibration_path(np.random.default_rng(1000 + seed), args.vibration)
    target.mkdir(parents=True, exist_ok=True)
    for t, (frame, name) in enumerate(zip(_ordered(frames, args), frames, strict=True)):
        image = cv2.imread(str(frame))
        image = _turned(image, args)
        if args.vibration > 0:
            image = wobbled(image, t, path, args.readout)
        if t == 0:
            part = dashboard(image)
        smear = None
        if args.shake > 0 and rng.random() < args.shake:
            smear = (rng.uniform(0.02, 0.06) * image.shape[1], rng.uniform(0, np.pi))
        image = degraded(
            hooded(image, part, args.hood), t, args.noise, args.exposure, rng,
            args.distortion, args.overlay, args.letterbox, args.pillarbox, args.blurred_sides,
            smear,
        )  # fmt: skip
        cv2.imwrite(str(target / name.name), image, [cv2.IMWRITE_JPEG_QUALITY, 99])


def _truth(source: Path, target: Path, args: argparse.Namespace, seed: int) -> None:
    """The ground truth: linked, or its masks warped through the lens and
    given the frames' bars."""
    if target.exists():
        return
    target.parent.mkdir(parents=True, exist_ok=True)
    changed = args.distortion != 0 or max(args.letterbox, args.pillarbox, args.hood) > 0
    changed = changed or args.vibration > 0 or args.mirror or args.rotate or args.reverse
    if not changed or not source.is_dir():
        target.symlink_to(source.resolve())
        return
    target.mkdir()
    path = vibration_path(np.random.default_rng(1000 + seed), args.vibration)
    masks = numbered(source, ".png")
    for t, (mask, name) in enumerate(zip(_ordered(masks, args), masks, strict=True)):
        image = cv2.imread(str(mask), cv2.IMREAD_UNCHANGED)
        image = _turned(image, args)
        if args.vibration > 0:
            image = wobbled(image, t, path, args.readout, nearest=True)
        if args.hood > 0:
            image = image.copy()
            image[hood_mask(image.shape[1], image.shape[0], args.hood)] = 0
        image = _lens(image, args.distortion, nearest=True)
        cv2.imwrite(str(target / name.name), bars(image, args.letterbox, args.pillarbox))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path)
    parser.add_argument("--noise", type=float, default=0.0, help="grey levels (sigma)")
    parser.add_argument("--exposure", type=float, default=0.0, help="gain amplitude, 0-1")
    parser.add_argument("--distortion", type=float, default=0.0, help="division model, -0.5-0")
    parser.add_argument("--overlay", action="store_true", help="a dashcam's burnt-in caption")
    parser.add_argument("--letterbox", type=float, default=0.0, help="bar height, 0-0.5")
    parser.add_argument("--pillarbox", type=float, default=0.0, help="bar width, 0-0.5")
    parser.add_argument("--blurred-sides", action="store_true", help="fill the side bars")
    parser.add_argument("--hood", type=float, default=0.0, help="camera-fixed share, 0-0.5")
    parser.add_argument("--shake", type=float, default=0.0, help="share of frames smeared, 0-1")
    parser.add_argument("--vibration", type=float, default=0.0, help="share of the width")
    parser.add_argument("--readout", type=float, default=0.0, help="share of the frame period")
    parser.add_argument("--mirror", action="store_true", help="mirror left-right")
    parser.add_argument("--rotate", action="store_true", help="turn a quarter clockwise")
    parser.add_argument("--reverse", action="store_true", help="play backwards")
    args = parser.parse_args()
    if args.noise < 0 or not 0 <= args.exposure < 1 or not -0.5 <= args.distortion <= 0:
        parser.error("--noise must be >= 0, --exposure in [0, 1), --distortion in [-0.5, 0]")
    if not (0 <= args.letterbox <= 0.5 and 0 <= args.pillarbox <= 0.5 and 0 <= args.hood <= 0.5):
        parser.error("--letterbox, --pillarbox and --hood must be in [0, 0.5]")
    if not (0 <= args.shake <= 1 and 0 <= args.readout <= 1 and 0 <= args.vibration <= 0.1):
        parser.error("--shake and --readout must be in [0, 1], --vibration in [0, 0.1]")
    clips = [(im, truth, args.out / group / im.parent.name) for im, truth, group in moving_clips()]
    fox = SHARED_DATA / "fox"
    if (fox / "images").is_dir():
        clips.append((fox / "images", fox / "transforms.json", args.out / "fox"))
    for seed, (images, truth, target) in enumerate(clips):
        frames = numbered(images, ".jpg") or numbered(images, ".png")
        degrade(frames, target / images.name, args, seed)
        _truth(truth, target / truth.name, args, seed)
    print(f"{len(clips)} clips written into {args.out}")


if __name__ == "__main__":
    main()
