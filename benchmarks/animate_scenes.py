"""Detector 2 on synthetic scenes with exact ground truth (issue 4's table).

Renders anti-aliased scenes (supersample 2) and prints, per camera: how
often the oscillating mover is flagged near its reversals and elsewhere,
rigid-scene false alarms, the smooth and emerging movers, and jitter with
and without compensation. Raw detector (persistence 1).

    python benchmarks/animate_scenes.py [--frames 36]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from motiondetect.animate.normal_footprints import AnimateConfig  # noqa: E402
from tests.scenes import (  # noqa: E402
    near_reversal,
    object_hits,
    run_detector,
    scene,
    to_input_mask,
)

PERIOD = 20


def false_alarms_near_movers(results, frames, cells: int = 2) -> float:
    """False-alarm regions per frame (connected flagged areas touching no
    moving or unknown ground truth, as ``evaluate`` counts them) that lie
    within ``cells`` grid cells of a mover: spill of its motion across its
    outline, or background it uncovers."""
    near = scored = 0
    for res, fr in zip(results, frames):
        if fr.index < 2:
            continue
        scored += 1
        truth = fr.mask > 0
        size = int(2 * cells * max(fr.mask.shape) / 64 + 1)
        grown = cv2.dilate(truth.astype(np.uint8), np.ones((size, size), np.uint8)) > 0
        flagged = to_input_mask(res.flagged, fr.mask.shape) > 0
        count, labels = cv2.connectedComponents(flagged.astype(np.uint8), connectivity=8)
        for label in range(1, count):
            region = labels == label
            if not (region & truth).any() and (region & grown).any():
                near += 1
    return near / max(scored, 1)


def rate(values) -> str:
    return f"{np.mean(values):.2f} (n={len(values)})" if values else "-"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=36)
    args = parser.parse_args()

    def render(camera, movers=(), frames=args.frames, **kw):
        return scene(camera, movers, frames=frames, supersample=2, period_frames=PERIOD, **kw)

    print(
        "| camera | near reversals, region | near reversals, 10 % pixels "
        "| elsewhere, region | FA regions/frame, with mover (within 2 cells of it) "
        "| FA regions/frame, rigid |"
    )
    print("|---|---|---|---|---|---|")
    for camera in ("uniform", "pan", "forward-yaw", "forward", "oblique", "fixation"):
        frames = render(camera, ("animate",))
        counts, _, results = run_detector(frames, "animate")
        hits = object_hits(results, frames)
        near = [h for h in hits if near_reversal(h[0], PERIOD)]
        other = [h[1] for h in hits if not near_reversal(h[0], PERIOD)]
        rigid, _, _ = run_detector(render(camera), "animate")
        print(
            f"| {camera} | {rate([h[1] for h in near])} | {rate([h[2] for h in near])} "
            f"| {rate(other)} | {counts.metrics()['false_alarm_regions_per_frame']:.2f} "
            f"({false_alarms_near_movers(results, frames):.2f}) "
            f"| {rigid.metrics()['false_alarm_regions_per_frame']:.2f} |"
        )
    print()
    for mover, frames in (("smooth", args.frames), ("emerging", 48)):
        clip = render("uniform", (mover,), frames=frames)
        _, _, results = run_detector(clip, "animate")
        hits = object_hits(results, clip)
        print(f"{mover} mover, uniform camera: flagged (region) in {rate([h[1] for h in hits])}")
    rigid = render("uniform", jitter_deg=0.15)
    waving = render("uniform", ("animate",), jitter_deg=0.15)
    for on in (True, False):
        config = AnimateConfig(jitter_compensation=on)
        counts, _, _ = run_detector(rigid, "animate", animate=config)
        with_mover, _, results = run_detector(waving, "animate", animate=config)
        near = [h[1] for h in object_hits(results, waving) if near_reversal(h[0], PERIOD)]
        print(
            f"jitter 0.15 deg/frame, uniform camera, compensation {'on ' if on else 'off'}: "
            f"rigid {counts.metrics()['false_alarm_regions_per_frame']:.2f} FA regions/frame; "
            f"oscillating mover near reversals {rate(near)}, "
            f"{with_mover.metrics()['false_alarm_regions_per_frame']:.2f} FA regions/frame"
        )


if __name__ == "__main__":
    main()
