"""Accuracy of the two 2-D velocity measurements on motions with known answers.

    python benchmarks/velocity_accuracy.py

A real photograph (skimage's astronaut) is moved by exact affine warps
(translation, rotation about the centre, zoom about the centre) into
320x320 frames, so the working resolution equals the input's and every
velocity is known at every pixel. Two candidates (issue 13, item 1):

* **DIS**: :class:`motiondetect.measurement.dense_flow.DenseFlow` with its
  defaults, compared with the true velocity at every pixel 20 px or more
  inside the frame;
* **stages + Hough/least squares**: the paper's normal-flow stages and its
  Hough step refined by least squares (:func:`~motiondetect.constraint_ray.hough.coarse_field`),
  one velocity per 4x4 region, compared with the region's mean true velocity.

Prints the median and 90th-percentile error (px/frame), the median error as a
share of the speed, and the share of regions (or pixels) with an answer.
Their speed is measured by ``benchmarks/throughput.py`` and ``benchmarks/stages.py``.

    python benchmarks/velocity_accuracy.py --border

DIS's median error by distance from the frame's border, in DIS patches
(``VelocityField.patch_px``), every pixel counted: the source of
``VelocityRayConfig.edge_error_ratio``.

    python benchmarks/velocity_accuracy.py --edges

DIS's mean error within one patch of each of the four edges, and inside,
in a square, a landscape and an upright (portrait) frame; then in the square
frame with the photo turned by quarters under the fastest rotation and zoom:
whether an edge worse than the others is DIS's (it stays put as the photo
turns) or the picture's (it turns with the photo).
"""

from __future__ import annotations

import sys

import cv2
import numpy as np
from skimage import data

from motiondetect.constraint_ray.hough import coarse_field
from motiondetect.measurement.dense_flow import DenseFlow, DenseFlowConfig
from motiondetect.measurement.normal_flow import NormalFlowPipeline, StageConfig

SIZE = 320
BORDER = 20
PHOTO = cv2.cvtColor(data.astronaut(), cv2.COLOR_RGB2BGR)
CENTRE = np.array([SIZE / 2, SIZE / 2])


def camera(kind: str, amount: float, t: int) -> np.ndarray:
    """3x3 map from frame pixels to photo pixels after ``t`` frames of motion."""
    offset = np.array([[1, 0, 96.0], [0, 1, 96.0], [0, 0, 1]])
    to_centre = np.array([[1, 0, -CENTRE[0]], [0, 1, -CENTRE[1]], [0, 0, 1]])
    back = np.linalg.inv(to_centre)
    if kind == "translation":  # the camera pans right: the scene moves left
        move = np.array([[1, 0, amount * t], [0, 1, 0.0], [0, 0, 1]])
    elif kind == "rotation":
        a = np.deg2rad(amount * t)
        move = back @ np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
        move = move @ to_centre
    else:  # zoom out by ``amount`` per frame: the scene shrinks toward the centre
        s = (1 + amount) ** t
        move = back @ np.diag([s, s, 1.0]) @ to_centre
    return offset @ move


def frame(
    kind: str, amount: float, t: int, size: tuple[int, int] = (SIZE, SIZE), turns: int = 0
) -> np.ndarray:
    """Frame ``t``, ``size`` (width, height) px, of the photo turned
    ``turns`` quarters anticlockwise."""
    photo = np.ascontiguousarray(np.rot90(PHOTO, turns))
    return cv2.warpPerspective(
        photo, camera(kind, amount, t), size, flags=cv2.WARP_INVERSE_MAP | cv2.INTER_CUBIC
    )


def true_velocity(
    kind: str, amount: float, t: int, size: tuple[int, int] = (SIZE, SIZE)
) -> np.ndarray:
    """(height, width, 2) velocity at frame t's pixels: x - (where x was in frame t-1)."""
    yy, xx = np.mgrid[0 : size[1], 0 : size[0]].astype(np.float64)
    pts = np.stack([xx, yy, np.ones_like(xx)], -1) @ camera(kind, amount, t).T
    before = pts @ np.linalg.inv(camera(kind, amount, t - 1)).T
    before = before[..., :2] / before[..., 2:]
    return np.stack([xx, yy], -1) - before


def dis_errors(
    kind: str, amount: float, frames: int = 4, config: DenseFlowConfig | None = None
) -> tuple[np.ndarray, float]:
    flow = DenseFlow(config)
    for t in range(frames):
        field = flow.process(frame(kind, amount, t))
    truth = true_velocity(kind, amount, frames - 1)
    err = np.hypot(*(field.velocity_px - truth).transpose(2, 0, 1))[BORDER:-BORDER, BORDER:-BORDER]
    speed = np.hypot(*truth.transpose(2, 0, 1))[BORDER:-BORDER, BORDER:-BORDER]
    return err.ravel(), float(np.median(speed))


def hough_errors(kind: str, amount: float, frames: int = 4) -> tuple[np.ndarray, float]:
    pipeline = NormalFlowPipeline(StageConfig(work_size=SIZE))
    for t in range(frames):
        field = pipeline.process(frame(kind, amount, t))
    coarse = coarse_field(field)
    truth = true_velocity(kind, amount, frames - 1)
    step = SIZE // 4
    mean = truth.reshape(4, step, 4, step, 2).mean(axis=(1, 3))
    known = coarse.known & coarse.moving
    err = np.hypot(*(coarse.flow_px - mean).transpose(2, 0, 1))
    err = np.where(known, err, np.inf)  # no answer counts as a miss
    return err.ravel(), float(np.median(np.hypot(*mean.transpose(2, 0, 1))))


#: px/frame, off whole pixels (a whole-pixel shift copies pixels exactly);
#: 40.5 and 50.5 lie past DIS's reach from rest, to show where it ends (the
#: default starts the last of the four frames' searches from the field
#: before, ``DenseFlowConfig.start_speed_px``, and reaches further).
SPEEDS = (0.1, 0.3, 0.7, 1.5, 3.5, 7.5, 15.5, 29.5, 40.5, 50.5)
MOTIONS = [
    *(("translation", s, f"translation {s:g} px/frame") for s in SPEEDS),
    *(("rotation", a, f"rotation {a:g} deg/frame") for a in (0.5, 1, 2, 4)),
    *(("zoom", z, f"zoom {100 * z:g} %/frame") for z in (0.005, 0.01, 0.02, 0.05)),
]


def row(label: str, median_speed: float, err: np.ndarray) -> str:
    answered = np.isfinite(err)
    if not answered.any():
        return f"| {label} | {median_speed:.2f} | - | - | - | 0 % |"
    e = err[answered]
    med, p90 = float(np.median(e)), float(np.percentile(e, 90))
    share = 100 * med / median_speed if median_speed else 0.0
    return (
        f"| {label} | {median_speed:.2f} | {med:.3f} | {p90:.3f} | {share:.1f} % "
        f"| {100 * answered.mean():.0f} % |"
    )


#: Distance bands from the border, in DIS patches; the last is the inside.
BANDS = ((0.0, 0.5), (0.5, 1.0), (1.0, 1.5), (1.5, 2.0), (2.0, 3.0), (3.0, None))


def border_errors(kind: str, amount: float, frames: int = 4) -> list[float]:
    """DIS's median error in each of :data:`BANDS`, px/frame."""
    flow = DenseFlow()
    for t in range(frames):
        field = flow.process(frame(kind, amount, t))
    truth = true_velocity(kind, amount, frames - 1)
    err = np.hypot(*(field.velocity_px - truth).transpose(2, 0, 1))
    yy, xx = np.mgrid[0:SIZE, 0:SIZE]
    patches = np.minimum(np.minimum(yy, SIZE - 1 - yy), np.minimum(xx, SIZE - 1 - xx))
    patches = patches / field.patch_px
    return [
        float(np.median(err[(patches >= lo) & ((patches < hi) if hi else True)]))
        for lo, hi in BANDS
    ]


def border_table() -> None:
    names = [f"{lo:g}-{hi:g}" if hi else f"{lo:g}+" for lo, hi in BANDS]
    print("| motion | " + " | ".join(names) + " | ratio within 1 patch |")
    print("|---|" + "---|" * (len(BANDS) + 1))
    for kind, amount, label in MOTIONS:
        if kind == "translation" and amount > 7.5:
            continue  # past the band (section above): errors of another kind
        med = border_errors(kind, amount)
        inside = med[-1]
        ratio = float(np.median(med[:2])) / inside if inside else float("nan")
        cells = " | ".join(f"{m:.3f}" for m in med)
        print(f"| {label} | {cells} | {ratio:.1f} |", flush=True)


#: Frames of the edge table: a square, a landscape and an upright frame.
EDGE_SIZES = ((320, 320), (320, 180), (180, 320))
EDGES = ("top", "bottom", "left", "right")


def edge_errors(
    kind: str, amount: float, size: tuple[int, int], turns: int = 0, frames: int = 4
) -> list[float]:
    """DIS's mean error within one patch of each of :data:`EDGES`, and
    inside, px/frame, in a frame of ``size`` (width, height) of the photo
    turned ``turns`` quarters."""
    flow = DenseFlow(DenseFlowConfig(work_size=max(size)))
    for t in range(frames):
        field = flow.process(frame(kind, amount, t, size, turns))
    err = np.hypot(*(field.velocity_px - true_velocity(kind, amount, frames - 1, size)).T).T
    b = field.patch_px
    bands = (err[:b], err[-b:], err[:, :b], err[:, -b:], err[b:-b, b:-b])
    return [float(band.mean()) for band in bands]


def edge_table() -> None:
    print("| frame | photo turned | motion | " + " | ".join(EDGES) + " | inside |")
    print("|---|---|---|" + "---|" * (len(EDGES) + 1))
    rows = [
        (size, 0, motion)
        for size in EDGE_SIZES
        for motion in MOTIONS
        if motion[0] != "translation" or 0.3 <= motion[1] <= 15.5
    ]
    rows += [((SIZE, SIZE), turns, motion) for turns in (1, 2, 3) for motion in MOTIONS[-5::4]]
    for size, turns, (kind, amount, label) in rows:
        cells = " | ".join(f"{e:.3f}" for e in edge_errors(kind, amount, size, turns))
        print(f"| {size[0]}x{size[1]} | {90 * turns} deg | {label} | {cells} |", flush=True)


def main() -> None:
    cv2.setNumThreads(1)
    if "--border" in sys.argv[1:]:
        border_table()
        return
    if "--edges" in sys.argv[1:]:
        edge_table()
        return
    header = [
        "| motion | median speed (px/frame) | median error | 90th pct error "
        "| median error / speed | answered |",
        "|---|---|---|---|---|---|",
    ]
    for name, measure in (("DIS (default)", dis_errors), ("stages + Hough/LS", hough_errors)):
        print(f"\n**{name}**\n")
        print("\n".join(header))
        for kind, amount, label in MOTIONS:
            err, speed = measure(kind, amount)
            print(row(label, speed, err), flush=True)
    print("\n**DIS, every search from rest (`start_speed_px = inf`)**\n")
    print("\n".join(header))
    rest = DenseFlowConfig(start_speed_px=float("inf"))
    for kind, amount, label in MOTIONS:
        if kind == "translation" and amount > 7.5:  # slower ones never start: as the default
            err, speed = dis_errors(kind, amount, config=rest)
            print(row(label, speed, err), flush=True)


if __name__ == "__main__":
    main()
