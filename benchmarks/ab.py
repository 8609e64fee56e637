"""The same library call timed on two checkouts, alternated (machines here are noisy).

    git worktree add /tmp/before <commit>
    python benchmarks/ab.py /tmp/before . ../shared/data/woman/woman.mp4 --threads 1

Each round runs ``process_input`` (reports, no video) once per checkout in a
fresh interpreter, which imports ``motiondetect`` from that checkout, and
prints the best of ``--best`` runs in ms per frame.
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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("before", type=Path)
    parser.add_argument("after", type=Path)
    parser.add_argument("clip", type=Path)
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--best", type=int, default=2)
    args = parser.parse_args()
    for r in range(args.rounds):
        for root in (args.before, args.after):
            cmd = [sys.executable, "-c", _CHILD, str(root.resolve()), str(args.clip)]
            cmd += [str(args.threads), str(args.best)]
            ms, module = subprocess.run(
                cmd, capture_output=True, text=True, check=True
            ).stdout.split()
            print(f"round {r + 1}  {root}: {float(ms):.2f} ms/frame  ({module})", flush=True)


if __name__ == "__main__":
    main()
