"""How the two halves of each frame share the cores, alternated (machines here are noisy).

    python benchmarks/threads.py ../shared/data/woman/woman.mp4 --rounds 5

``MotionDetector.stream`` measures the next frame (decode, grey, DIS) on a
second thread while this one is judged (the fit, the detectors, the
objects) when OpenCV may use more than one thread. Each round runs, each in
a fresh interpreter:

* ``one``: one thread, measure then judge;
* ``ahead``: default threads, measuring ahead;
* ``ahead-pool1``: measuring ahead, OpenCV's own pool at one thread (DIS
  cannot spread over the core the judging thread needs).

It prints the wall time, the time inside ``measure_frame``, ``prepare``
(on the measuring thread while the judging one is busy; what it leaves,
``judge`` does) and ``judge``, and the process's CPU time, each in ms per
frame.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys

MODES = ("one", "ahead", "ahead-pool1")

_CHILD = """
import resource, sys, time
import cv2
mode = sys.argv[2]
if mode != "ahead":  # "ahead" keeps OpenCV's default threads
    cv2.setNumThreads(1)
if mode == "ahead-pool1":
    cv2.getNumThreads = lambda: 2  # this process only: stream() then measures ahead
from motiondetect.detection.detector import MotionDetector
from motiondetect.io.video import open_source
detector = MotionDetector("both")
spent = {"measure_frame": 0.0, "prepare": 0.0, "judge": 0.0}
for name in spent:
    call = getattr(detector, name)
    def timed(*args, _call=call, _name=name):
        t = time.perf_counter()
        got = _call(*args)
        spent[_name] += time.perf_counter() - t
        return got
    setattr(detector, name, timed)
t, n = time.perf_counter(), 0
with open_source(sys.argv[1]) as source:
    for _ in detector.stream(source):
        n += 1
wall = time.perf_counter() - t
usage = resource.getrusage(resource.RUSAGE_SELF)
cpu = usage.ru_utime + usage.ru_stime
print(" ".join(f"{1000 * s / n:7.2f}" for s in (wall, *spent.values(), cpu)))
"""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("clip")
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    print(
        f"{'mode':<12} {'wall':>7} {'measure':>7} {'prepare':>7} {'judge':>7} {'cpu':>7}"
        "  (ms per frame)"
    )
    for _ in range(args.rounds):
        for mode in MODES:
            run = [sys.executable, "-c", _CHILD, args.clip, mode]
            env = dict(os.environ)
            if mode != "ahead":  # one thread as common.single_thread has it, BLAS included
                env.update(OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
            got = subprocess.run(run, capture_output=True, text=True, check=True, env=env)
            print(f"{mode:<12} {got.stdout.strip()}")


if __name__ == "__main__":
    main()
