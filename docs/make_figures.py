"""Make the figures in docs/img from the code.

    python docs/make_figures.py                       # committed figures (sample videos)
    python docs/make_figures.py --clip PATH --out DIR  # the same views of any clip

The committed figures use the bundled sample videos (rendered from real
photographs) so that no third-party footage is redistributed; ``--clip``
draws the normal-flow, coarse-field and detection views of any real clip,
e.g. ``../shared/data/davis/blackswan/JPEGImages``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import cv2
import numpy as np
from skimage import data

from motiondetect.animate.normal_footprints import footprint_cells
from motiondetect.constraint_ray.normal_filter import allowed_interval
from motiondetect.constraint_ray.observer_motion import UNBOUNDED
from motiondetect.detection.detector import MotionDetector
from motiondetect.io.annotate import annotate, annotated_size
from motiondetect.io.video import open_source, to_display
from motiondetect.measurement.normal_flow import NormalFlowPipeline

ROOT = Path(__file__).resolve().parents[1]
FONT = cv2.FONT_HERSHEY_SIMPLEX


def draw_normal_flow(img: np.ndarray, field, step: int = 2) -> None:
    """Arrows m*n x3 of every ``step``-th cell, in place (yellow: fine level,
    blue: coarse level)."""
    h, w = img.shape[:2]
    sx, sy = w / 64, h / 64
    nx, ny = field.normal
    scale = 3.0 * w / field.geometry.work_size[0]
    for r in range(1, 63, step):
        for c in range(1, 63, step):
            if not field.valid[r, c]:
                continue
            m = float(field.flow_px[r, c])
            p0 = (int((c + 0.5) * sx), int((r + 0.5) * sy))
            p1 = (int(p0[0] + m * nx[r, c] * scale), int(p0[1] + m * ny[r, c] * scale))
            colour = (80, 220, 255) if field.level[r, c] == 0 else (255, 160, 60)
            cv2.arrowedLine(img, p0, p1, colour, 1, cv2.LINE_AA, tipLength=0.3)


def normal_flow_figure(frames: list[np.ndarray], title: str) -> np.ndarray:
    """The 64x64 normal flow of one frame pair as arrows m*n on the frame."""
    pipe = NormalFlowPipeline()
    field = None
    for f in frames:
        field = pipe.process(f) or field
    img = to_display(frames[-1])
    size = annotated_size(img.shape[1], img.shape[0], 768)
    img = cv2.resize(img, size, interpolation=cv2.INTER_AREA)
    img = (img * 0.6).astype(np.uint8)
    draw_normal_flow(img, field)
    cv2.putText(img, title, (8, 20), FONT, 0.55, (255, 255, 255), 1, cv2.LINE_AA)
    cv2.putText(
        img,
        "normal flow m*n x3 (yellow fine level, blue coarse level)",
        (8, size[1] - 10),
        FONT,
        0.45,
        (255, 255, 255),
        1,
        cv2.LINE_AA,
    )
    return img


def constraint_regions_figure() -> np.ndarray:
    """Figure 4: shaded velocity-space regions allowed for gradient-parallel flow."""
    panels = []
    cases = [
        ("segment, bounded depth", np.array([1.0, -0.5]), np.array([1.0, 1.5]), 1.0),
        ("segment away from origin", np.array([1.5, 0.8]), np.array([0.8, -0.6]), 1.5),
        ("a -> infinity: disk + half-plane", np.array([0.8, 0.6]), np.array([1.0, 0.3]), UNBOUNDED),
    ]
    n = 300
    extent = 3.0
    for title, vw, vxy, a in cases:
        ys, xs = np.mgrid[extent : -extent : n * 1j, -extent : extent : n * 1j]
        r = np.hypot(xs, ys)
        nx, ny = xs / np.maximum(r, 1e-9), ys / np.maximum(r, 1e-9)
        lo, hi = allowed_interval(vw, vxy, a, nx, ny)
        allowed = (r >= lo) & (r <= hi)
        img = np.full((n, n, 3), 255, np.uint8)
        img[allowed] = (230, 190, 140)

        def px(v):
            return (
                int((v[0] + extent) / (2 * extent) * n),
                int((extent - v[1]) / (2 * extent) * n),
            )

        cv2.line(img, (0, n // 2), (n, n // 2), (150, 150, 150), 1)
        cv2.line(img, (n // 2, 0), (n // 2, n), (150, 150, 150), 1)
        end = vw + min(a, 6.0) * vxy
        cv2.line(img, px(vw), px(end), (0, 0, 200), 2, cv2.LINE_AA)
        cv2.circle(img, px(vw), 4, (0, 0, 200), -1)
        for v in (vw, end if a < UNBOUNDED else None):
            if v is not None:
                c = px(v / 2)
                rad = int(np.linalg.norm(v) / 2 / (2 * extent) * n)
                cv2.circle(img, c, rad, (60, 60, 60), 1, cv2.LINE_AA)
        cv2.putText(img, title, (6, 16), FONT, 0.42, (0, 0, 0), 1, cv2.LINE_AA)
        cv2.putText(img, "V_w", (px(vw)[0] + 6, px(vw)[1] - 4), FONT, 0.4, (0, 0, 200), 1)
        panels.append(img)
    return np.hstack([np.pad(p, ((4, 4), (4, 4), (0, 0)), constant_values=200) for p in panels])


def footprints_figure() -> np.ndarray:
    """Figure 8: a footprint, extended through the counterflow side, and ahead."""
    panels = []
    for title, back, ahead in (
        ("footprint", 0.0, 0.0),
        ("+ counterflow side (Fig. 8)", 1.0, 0.0),
        ("+ ahead (uncovered background)", 1.0, 2.0),
    ):
        cell = 28
        r = 4
        img = np.full(((2 * r + 1) * cell, (2 * r + 1) * cell, 3), 255, np.uint8)
        cells = footprint_cells(12.0, np.deg2rad(30), (8.0, 8.0), 14.0, back, ahead)
        for dy, dx in cells:
            y0, x0 = (dy + r) * cell, (dx + r) * cell
            cv2.rectangle(img, (x0, y0), (x0 + cell - 1, y0 + cell - 1), (240, 200, 150), -1)
        for k in range(2 * r + 2):
            cv2.line(img, (k * cell, 0), (k * cell, img.shape[0]), (220, 220, 220), 1)
            cv2.line(img, (0, k * cell), (img.shape[1], k * cell), (220, 220, 220), 1)
        c = (r * cell + cell // 2, r * cell + cell // 2)
        tip = (
            int(c[0] + 12 / 8 * cell * np.cos(np.deg2rad(30))),
            int(c[1] + 12 / 8 * cell * np.sin(np.deg2rad(30))),
        )
        cv2.circle(img, c, 5, (0, 0, 0), -1)
        cv2.arrowedLine(img, c, tip, (0, 0, 200), 2, cv2.LINE_AA, tipLength=0.25)
        cv2.putText(img, title, (4, 14), FONT, 0.42, (0, 0, 0), 1, cv2.LINE_AA)
        panels.append(img)
    return np.hstack([np.pad(p, ((4, 4), (4, 4), (0, 0)), constant_values=200) for p in panels])


def first_frames(path: Path, count: int, skip: int = 0) -> list[np.ndarray]:
    out = []
    with open_source(path) as source:
        for frame in source:
            if frame.index >= skip:
                out.append(frame.image)
            if len(out) == count:
                break
    return out


def detection_figure(
    path: Path,
    at: int,
    detector: str = "both",
    egomotion=None,
    withhold_pixels: bool = False,
    measure: str = "velocity",
) -> np.ndarray:
    """Frame ``at`` annotated with the detections (``measure="normal"``: the
    paper's path, with its coarse field drawn). With ``withhold_pixels`` the
    footage is replaced by a grey canvas carrying only what the detector saw,
    its normal flow (so the normal path), for clips whose pixels may not be
    redistributed."""
    measure = "normal" if withhold_pixels else measure
    md = MotionDetector(detector, egomotion=egomotion, measure=measure)
    with open_source(path) as source:
        for frame in source:
            result = md.process(frame.image, frame.index, frame.time_s)
            if frame.index == at:
                img = to_display(frame.image)
                size = annotated_size(img.shape[1], img.shape[0], 640)
                if not withhold_pixels:
                    return annotate(img, result, size)
                grow = max(1.0, 640 / size[0])
                size = (round(size[0] * grow), round(size[1] * grow))
                out = annotate(np.full_like(img, 70), result, size)
                draw_normal_flow(out, result.field)
                return out
    raise ValueError(f"{path} has fewer than {at + 1} frames")


def clip_figures(clip: Path, frame: int, out: Path) -> None:
    """The figures of one given clip (``--clip``), around ``frame``."""
    frames = first_frames(clip, 2, skip=frame - 1)
    cv2.imwrite(str(out / "clip_normal_flow.png"), normal_flow_figure(frames, clip.name))
    cv2.imwrite(str(out / "clip_detection.png"), detection_figure(clip, frame))
    cv2.imwrite(str(out / "clip_detection_animate.png"), detection_figure(clip, frame, "animate"))
    cv2.imwrite(
        str(out / "clip_detection_animate_flow_only.png"),
        detection_figure(clip, frame, "animate", withhold_pixels=True),
    )


def rotation_zoom_pair() -> list[np.ndarray]:
    """A photograph rotated by -0.75 and 0.75 deg and zoomed by -0.6 and 0.6 %."""
    photo = data.astronaut()
    h, w = photo.shape[:2]
    pair = []
    for sign in (-1, 1):
        m = cv2.getRotationMatrix2D((w / 2, h / 2), sign * 0.75, 1.0 + sign * 0.006)
        flags = cv2.INTER_CUBIC
        pair.append(
            cv2.warpAffine(photo[..., ::-1], m, (w, h), flags=flags, borderMode=cv2.BORDER_REFLECT)
        )
    return pair


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--clip", type=Path)
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "img")
    parser.add_argument("--frame", type=int, default=20)
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    if args.clip is not None:
        clip_figures(args.clip, args.frame, args.out)
        return
    cv2.imwrite(
        str(args.out / "normal_flow_rotation_zoom.png"),
        normal_flow_figure(
            rotation_zoom_pair(), "photograph rotating 1.5 deg and zooming 1.2 %/frame"
        ),
    )
    samples = ROOT / "sample_videos"
    clip = samples / "uniform_mixed" / "video.mp4"
    cv2.imwrite(
        str(args.out / "normal_flow_sample.png"),
        normal_flow_figure(first_frames(clip, 2, skip=19), "uniform_mixed, frame 20"),
    )
    cv2.imwrite(str(args.out / "constraint_regions.png"), constraint_regions_figure())
    cv2.imwrite(str(args.out / "footprints.png"), footprints_figure())
    cv2.imwrite(str(args.out / "detection_uniform_mixed.png"), detection_figure(clip, 21))
    cv2.imwrite(
        str(args.out / "coarse_field_forward.png"),
        detection_figure(
            samples / "forward_crossing" / "video.mp4", 30, "constraint-ray", measure="normal"
        ),
    )
    cv2.imwrite(
        str(args.out / "detection_handheld_animate.png"),
        detection_figure(
            samples / "handheld_emerging" / "video.mp4", 25, "animate", measure="normal"
        ),
    )
    woman = ROOT.parent / "shared" / "data" / "woman" / "woman.mp4"
    if woman.exists():  # a real clip; its pixels are withheld (not ours to redistribute)
        cv2.imwrite(
            str(args.out / "real_woman_animate_flow_only.png"),
            detection_figure(woman, 120, "animate", withhold_pixels=True),
        )


if __name__ == "__main__":
    main()
