"""What reading an input costs, as ``detect`` reads it, on one or more checkouts.

    git worktree add /tmp/before <commit>
    python benchmarks/read_cost.py ../shared/data/davis/dog/JPEGImages /tmp/before .

Each checkout runs in a fresh interpreter (one OpenCV thread) and reads every
frame: what the measurement reads (``measured_picture``, made grey where it
is colour, as the measurement would), alone and then with the annotated
video's picture at 512 px wide (``SourceFrame.picture``). Prints the best of
three passes in ms per frame: the decoding and conversion the rest of the
run does not hide.
"""

from __future__ import annotations

import argparse
import subprocess
import sys

_CHILD = """
import sys, time
sys.path.insert(0, sys.argv[1])
import cv2
cv2.setNumThreads(1)
from motiondetect.detection.streaming import measured_picture
from motiondetect.io.video import open_source

def one_pass(drawn):
    start, n = time.perf_counter(), 0
    with open_source(sys.argv[2]) as source:
        w, h = source.info.width, source.info.height
        size = (512, round(512 * h / w / 2) * 2)
        for frame in source:
            grey = measured_picture(frame)
            if grey.ndim == 3:
                grey = cv2.cvtColor(grey, cv2.COLOR_BGR2GRAY)
            if drawn:
                frame.picture(size)
            n += 1
    return 1000 * (time.perf_counter() - start) / n

print(" ".join(f"{min(one_pass(d) for _ in range(3)):7.2f}" for d in (False, True)))
"""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("source")
    parser.add_argument("checkouts", nargs="+")
    args = parser.parse_args()
    print(f"{'checkout':<30} {'grey':>7} {'+ drawn':>7}  (ms per frame)")
    for checkout in args.checkouts:
        run = [sys.executable, "-c", _CHILD, checkout, args.source]
        got = subprocess.run(run, capture_output=True, text=True, check=True)
        print(f"{checkout:<30} {got.stdout.strip()}")


if __name__ == "__main__":
    main()
