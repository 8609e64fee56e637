"""What each setting that trades detection for time saves, beside MOG2.

    python benchmarks/settings_speed.py            # the 512x512 pan and woman.mp4
    python benchmarks/settings_speed.py --repeat 1 --frames 150

``detect`` end to end (decode, reports, with and without the annotated
H.264 video) under each of :data:`SETTINGS`, and OpenCV MOG2 (decode +
apply) on the same file in the same run, with one OpenCV thread and with
its default threads. What the settings cost in detection is measured by
``benchmarks/sweep.py`` (docs/detectors.md, "The settings that trade
detection for time").
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import cv2

sys.path.insert(0, str(Path(__file__).resolve().parent))

from common import SHARED_DATA, make_pan_clip, mog2_on  # noqa: E402
from throughput import best_rate, run_detect  # noqa: E402

#: Name -> the settings ``detect`` runs with (as in a config file or on the command line).
SETTINGS = {
    "default": {},
    "refinement_iterations 0": {"dense_flow": {"refinement_iterations": 0}},
    "--flow-preset fast": {"flow_preset": "fast"},
    "--frame-skip 1": {"frame_skip": 1},
    "--frame-skip 1, refinement 0": {"frame_skip": 1, "dense_flow": {"refinement_iterations": 0}},
}


def report(clip: Path, tmp: Path, repeat: int) -> None:
    """MOG2, then ``detect`` under each of :data:`SETTINGS` with and without
    the video, on ``clip`` with OpenCV's threads as they are set."""
    mog = best_rate(lambda: mog2_on(clip), repeat)
    print(f"\n{clip.name}, cv2 threads = {cv2.getNumThreads()}: MOG2 {mog:.1f} frames/s")
    for video in (False, True):
        for name, options in SETTINGS.items():
            rate = best_rate(
                lambda v=video, o=options: run_detect(
                    clip, tmp / "out", video=v, timeline=False, **o
                ),
                repeat,
            )
            what = f"{name}, {'H.264 video' if video else 'no video'}"
            print(f"  {what:42s} {rate:6.1f} frames/s  {rate / mog:.2f}x MOG2")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--frames", type=int, default=300, help="frames of the pan clip")
    parser.add_argument("--repeat", type=int, default=2)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        clips = [make_pan_clip(tmp / "clip512.mp4", (512, 512), args.frames)]
        woman = SHARED_DATA / "woman" / "woman.mp4"
        clips += [woman] if woman.exists() else []
        for clip in clips:
            for threads in (1, -1):
                cv2.setNumThreads(threads)
                report(clip, tmp, args.repeat)


if __name__ == "__main__":
    main()
