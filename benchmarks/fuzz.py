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


def damaged(data: bytearray, rng: np.random.Generator) -> bytes:
    """``data`` with random bytes flipped, cut short, or a block overwritten with noise."""
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
    return bytes(data)


def outcome(path: Path, out: Path, timeout: float) -> tuple[str, str]:
    """What ``detect`` made of one damaged file, and its stderr."""
    command = [
        sys.executable, "-m", "motiondetect_cli.main", "detect", str(path),
        "-o", str(out), "-q", "--no-video", "--overwrite",
    ]  # fmt: skip
    try:
        proc = subprocess.run(command, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return "timeout", ""
    if "Traceback" in proc.stderr:
        return "traceback", proc.stderr
    if proc.returncode == 0:
        return "processed" + (" (partial)" if "truncated" in proc.stderr else ""), ""
    if proc.returncode == 1:
        return "failed cleanly", ""
    return f"exit {proc.returncode}", ""


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
            source = sources[case % len(sources)]
            path = tmp / f"case{case}{source.suffix}"
            path.write_bytes(damaged(bytearray(source.read_bytes()), rng))
            kind, stderr = outcome(path, tmp / "out", args.timeout)
            counts[kind] += 1
            if kind == "traceback":
                print(f"case {case}: traceback\n{stderr}")
            path.unlink(missing_ok=True)
    print(
        f"{args.cases} cases, seed {args.seed}: "
        + ", ".join(f"{k} {v}" for k, v in sorted(counts.items()))
    )


if __name__ == "__main__":
    main()
