"""Longer fuzz run: corrupt bytes of small valid videos, run detect on each.

    python benchmarks/fuzz.py --cases 200 --seed 1

Every case must either process (exit 0) or fail cleanly (exit 1, one error
line, no traceback) within the per-file timeout. Prints the counts.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
from collections import Counter
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import make_pan_clip  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--cases", type=int, default=200)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--timeout", type=float, default=60.0)
    args = parser.parse_args()
    rng = np.random.default_rng(args.seed)
    counts: Counter = Counter()
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        sources = [
            make_pan_clip(tmp / f"src{k}{ext}", (160, 120), 12)
            for k, ext in enumerate((".mp4", ".avi", ".mkv"))
        ]
        for case in range(args.cases):
            data = bytearray(sources[case % len(sources)].read_bytes())
            mode = rng.integers(0, 3)
            if mode == 0:  # flip random bytes
                for _ in range(int(rng.integers(1, 200))):
                    data[int(rng.integers(0, len(data)))] = int(rng.integers(0, 256))
            elif mode == 1:  # truncate
                data = data[: int(rng.integers(0, len(data)))]
            else:  # overwrite a block with noise
                start = int(rng.integers(0, len(data)))
                block = rng.integers(0, 256, int(rng.integers(1, 4096)), dtype=np.uint8)
                data[start : start + len(block)] = block.tobytes()[: len(data) - start]
            path = tmp / f"case{case}{sources[case % len(sources)].suffix}"
            path.write_bytes(bytes(data))
            try:
                proc = subprocess.run(
                    [
                        sys.executable,
                        "-m",
                        "motiondetect_cli.main",
                        "detect",
                        str(path),
                        "-o",
                        str(tmp / "out"),
                        "-q",
                        "--no-video",
                        "--overwrite",
                    ],
                    capture_output=True,
                    text=True,
                    timeout=args.timeout,
                )
            except subprocess.TimeoutExpired:
                counts["timeout"] += 1
                continue
            if "Traceback" in proc.stderr:
                counts["traceback"] += 1
                print(f"case {case}: traceback\n{proc.stderr}")
            elif proc.returncode == 0:
                counts["processed" + (" (partial)" if "truncated" in proc.stderr else "")] += 1
            elif proc.returncode == 1:
                counts["failed cleanly"] += 1
            else:
                counts[f"exit {proc.returncode}"] += 1
            path.unlink()
    print(
        f"{args.cases} cases, seed {args.seed}: "
        + ", ".join(f"{k} {v}" for k, v in sorted(counts.items()))
    )


if __name__ == "__main__":
    main()
