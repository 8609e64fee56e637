"""The same library call timed on two checkouts, alternated (machines here are noisy).

    git worktree add /tmp/before <commit>
    python benchmarks/ab.py /tmp/before . ../shared/data/woman/woman.mp4 --threads 1

Each round runs ``process_input`` (reports, no video) once per checkout in a
fresh interpreter, which imports ``motiondetect`` from that checkout, and
prints the best of ``--best`` runs in ms per frame.

``--judge`` times only the second half of each frame, ``MotionDetector.judge``
(the fit, the detectors, the objects), on measurements computed beforehand:
DIS, the larger cost, then does not hide a change to the rest.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path

_CHILD = """
import sys, tempfile, time
from pathlib import Path
sys.path.insert(0, sys.argv[1])
import cv2
cv2.setNumThreads(int(sys.argv[3]))
import motiondetect.app.process as P
from motiondetect.app.inputs import InputJob
from motiondetect.app.settings import make_settings
clip = Path(sys.argv[2])
out = Path(tempfile.mkdtemp())
s = make_settings({"output": out, "overwrite": True, "video": False, "timeline": False})
best = float("inf")
for _ in range(int(sys.argv[4])):
    t = time.perf_counter()
    r = P.process_input(InputJob(clip, clip.stem), s)
    best = min(best, time.perf_counter() - t)
print(1000 * best / r.summary["totals"]["frames"], P.__file__)
"""

_JUDGE_CHILD = """
import functools, sys, time
sys.path.insert(0, sys.argv[1])
import cv2
cv2.setNumThreads(int(sys.argv[3]))
import motiondetect.detection.detector as D
from motiondetect.io.video import open_source
measuring = D.MotionDetector("both")
with open_source(sys.argv[2]) as source:
    flows = [(measuring.measure_frame(f.image), f.index) for f in source]
best = float("inf")
for _ in range(int(sys.argv[4])):
    for flow, _ in flows:  # the maps judging caches on a field, computed afresh each run
        cached = vars(type(flow)).items() if flow is not None else ()
        for name, attr in cached:
            if isinstance(attr, functools.cached_property):
                flow.__dict__.pop(name, None)
    judging = D.MotionDetector("both")
    t = time.perf_counter()
    for flow, index in flows:
        judging.judge(flow, index, 0.0)
    best = min(best, time.perf_counter() - t)
print(1000 * best / len(flows), D.__file__)
"""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("before", type=Path)
    parser.add_argument("after", type=Path)
    parser.add_argument("clip", type=Path)
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--best", type=int, default=2)
    parser.add_argument("--judge", action="store_true", help="time MotionDetector.judge alone")
    args = parser.parse_args()
    child = _JUDGE_CHILD if args.judge else _CHILD
    for r in range(args.rounds):
        for root in (args.before, args.after):
            cmd = [sys.executable, "-c", child, str(root.resolve()), str(args.clip)]
            cmd += [str(args.threads), str(args.best)]
            ms, module = subprocess.run(
                cmd, capture_output=True, text=True, check=True
            ).stdout.split()
            print(f"round {r + 1}  {root}: {float(ms):.2f} ms/frame  ({module})", flush=True)


if __name__ == "__main__":
    main()
