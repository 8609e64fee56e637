"""Time each Maxvideo stage and the whole pipeline on a 512x512 clip (issue 2).

In the same run, on the same frames: decode only, and OpenCV MOG2
(``createBackgroundSubtractorMOG2().apply``). One thread.

    python benchmarks/stages.py [--frames 300]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import cv2
import numpy as np
from common import decode_only, make_pan_clip, mog2_on, read_all, single_thread, timed

from motiondetect.measurement import luts, stages
from motiondetect.measurement.normal_flow import NormalFlowPipeline, StageConfig, measure_level


def per_stage(frames: list[np.ndarray], config: StageConfig) -> dict[str, float]:
    """Milliseconds per frame for each stage, float path, 512x512 input."""
    grid = (config.derivative_grid, config.derivative_grid)
    spacing = (512 / grid[1], 512 / grid[0])
    t = dict.fromkeys(
        [
            "grey",
            "pre-reduce",
            "blur",
            "reduce",
            "diff_avg",
            "gradients",
            "polar",
            "normal_flow",
            "subsample",
            "coarse level",
        ],
        0.0,
    )
    prev = None
    for f in frames:
        a = time.perf_counter()
        g = stages.to_grey(f)
        a2 = time.perf_counter()
        g = stages.to_working_size(g.astype(np.float32), (256, 256))  # as the pipeline does
        b = time.perf_counter()
        bl = stages.blur(g, config.blur_sigma_px / 2)
        c = time.perf_counter()
        r = stages.reduce_to_grid(bl, grid)
        d = time.perf_counter()
        t["grey"] += a2 - a
        t["pre-reduce"] += b - a2
        t["blur"] += c - b
        t["reduce"] += d - c
        if prev is not None:
            e = time.perf_counter()
            diff, avg = stages.difference_and_average(prev, r)
            f1 = time.perf_counter()
            gx, gy = stages.gradients(avg, spacing)
            f2 = time.perf_counter()
            mag, direction = stages.gradient_polar(gx, gy)
            f3 = time.perf_counter()
            flow, valid = stages.normal_flow(diff, mag, config.min_gradient)
            f4 = time.perf_counter()
            stages.subsample(np.where(valid, mag, -1), flow, direction, mag, valid)
            f5 = time.perf_counter()
            coarse = stages.reduce_to_grid(stages.blur(r, 2.0), (64, 64))
            measure_level(
                stages.reduce_to_grid(stages.blur(prev, 2.0), (64, 64)), coarse, (8.0, 8.0), config
            )
            f6 = time.perf_counter()
            t["diff_avg"] += f1 - e
            t["gradients"] += f2 - f1
            t["polar"] += f3 - f2
            t["normal_flow"] += f4 - f3
            t["subsample"] += f5 - f4
            t["coarse level"] += f6 - f5
        prev = r
    return {k: 1000 * v / len(frames) for k, v in t.items()}


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--frames", type=int, default=300)
    args = parser.parse_args()
    single_thread()
    with tempfile.TemporaryDirectory() as tmp:
        clip = make_pan_clip(Path(tmp) / "pan512.mp4", (512, 512), args.frames)
        frames = read_all(clip)
        n = len(frames)
        print(f"clip: 512x512, {n} frames, one thread (cv2.setNumThreads(1))")
        results = {}
        results["decode only"] = timed(lambda: decode_only(clip), 2)
        results["MOG2 (decode + apply)"] = timed(lambda: mog2_on(clip), 2)
        sub = cv2.createBackgroundSubtractorMOG2()
        results["MOG2 apply only"] = timed(lambda: [sub.apply(f) for f in frames], 1)
        for name, cfg in [
            ("pipeline float (default)", StageConfig()),
            ("pipeline lut", StageConfig(arithmetic="lut")),
            ("pipeline float, no pyramid", StageConfig(pyramid=False)),
            (
                "pipeline float, 512 derivative grid",
                StageConfig(derivative_grid=512, pyramid=False),
            ),
        ]:

            def go(cfg=cfg):
                p = NormalFlowPipeline(cfg)
                for f in frames:
                    p.process(f)

            results[name] = timed(go, 2)
        luts.MaxMuxTables.build(1.0)
        mog = results["MOG2 apply only"]
        print(f"{'':40s} {'frames/s':>10s} {'ms/frame':>9s} {'x MOG2 apply':>13s}")
        for name, secs in results.items():
            print(f"{name:40s} {n / secs:10.1f} {1000 * secs / n:9.2f} {mog / secs:13.2f}")
        print("\nper stage, float path, ms/frame (decoded frames in memory):")
        for name, ms in per_stage(frames, StageConfig()).items():
            print(f"  {name:14s} {ms:6.3f}")


if __name__ == "__main__":
    main()
