"""Are a version's outputs identical to another's on the sample videos?

    python benchmarks/identity.py digest OUT.json [--measure normal] [--src DIR] [--real]
    python benchmarks/identity.py compare A.json B.json

``--real`` adds the shared real clips that are present (``woman.mp4``, six
DAVIS clips, UCSD birds and surfers, the fox): the check for a change
meant to leave every result as it was, such as a faster way to the same
arrays.

``digest`` runs detect (masks on, no video) on every sample video with the
library found in ``--src`` (default: this checkout; any earlier checkout of
the project works too) and writes a digest: per-frame detections (box,
score, detectors), observer class, events, and a hash of every mask.
Fields that a newer version added (``reliable``, ``track``, ``reason``, the
velocities, and their columns in detections.csv) are left out, so a newer
version's output can be compared with an older one's.
"""

from __future__ import annotations

import argparse
import csv
import hashlib
import json
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SAMPLES = sorted(p for p in (ROOT / "sample_videos").iterdir() if (p / "video.mp4").exists())
#: Shared real clips of ``--real`` (name: path under ``SHARED_DATA``): a mover
#: among others, the close and the camera-filling movers, fast pans, water, parallax.
REAL = {
    "woman": "woman/woman.mp4",
    **{s: f"davis/{s}/JPEGImages" for s in ("camel", "goat", "drift-turn", "motocross-bumps",
                                            "dog-agility", "breakdance")},
    "birds": "ucsd/birds/in", "surfers": "ucsd/surfers/in", "fox": "fox/images",
}  # fmt: skip


def inputs(real: bool) -> list[tuple[str, Path]]:
    """(name, video or frames folder) of every input digested."""
    found = [(p.name, p / "video.mp4") for p in SAMPLES]
    if real:
        from common import SHARED_DATA

        found += [(n, SHARED_DATA / r) for n, r in REAL.items() if (SHARED_DATA / r).exists()]
    return found


_RUN = """
import sys
from pathlib import Path
try:
    from motiondetect.app.inputs import InputJob
    from motiondetect.app.process import process_input
    from motiondetect.app.settings import make_settings
except ImportError:  # a checkout before the app/ layer
    from motiondetect.runner import InputJob, process_input
    from motiondetect.settings import make_settings
values = {"output": sys.argv[2], "masks": True, "video": False}
if sys.argv[3]:
    values["measure"] = sys.argv[3]
result = process_input(InputJob(Path(sys.argv[1]), "v"), make_settings(values))
assert result.status == "done", result.message
"""


def _frame(record: dict) -> dict:
    return {
        "frame": record["frame"],
        "class": record["observer_motion"]["class"],
        "detections": [
            [d["bbox"], d["score"], d["detectors"], d["area_px"]] for d in record["detections"]
        ],
    }


#: detections.csv's columns every version writes; later ones (``track``,
#: ``held``, the velocities) are left out, as in :func:`_frame`.
CSV_COLUMNS = ("frame", "time_s", "detectors", "x", "y", "w", "h", "area_px", "score")


def _csv_rows(path: Path) -> list[list[str]]:
    rows = list(csv.DictReader(path.read_text().splitlines()))
    return [[row[c] for c in CSV_COLUMNS] for row in rows]


def digest_output(folder: Path) -> dict:
    frames = [json.loads(x) for x in (folder / "frames.jsonl").read_text().splitlines()]
    masks = sorted((folder / "masks").glob("*.png"))
    return {
        "frames": [_frame(r) for r in frames],
        "detections_csv": _csv_rows(folder / "detections.csv"),
        "events_csv": (folder / "events.csv").read_text(),
        "masks": [hashlib.sha256(m.read_bytes()).hexdigest()[:16] for m in masks],
    }


def digest(out: Path, measure: str, src: Path, real: bool = False) -> None:
    result = {}
    with tempfile.TemporaryDirectory() as tmp:
        for name, path in inputs(real):
            target = Path(tmp) / name
            subprocess.run(
                [sys.executable, "-c", _RUN, str(path), str(target), measure],
                check=True,
                cwd=src,  # "-c" puts the working directory first on sys.path
                env={"PYTHONPATH": f"{src}", "OMP_NUM_THREADS": "1", "PATH": "/usr/bin:/bin"},
            )
            result[name] = digest_output(target / "v")
            print(f"{name}: {len(result[name]['frames'])} frames", flush=True)
    out.write_text(json.dumps(result, indent=1))


def compare(a: Path, b: Path) -> int:
    da, db = json.loads(a.read_text()), json.loads(b.read_text())
    differing = 0
    for name in sorted(set(da) | set(db)):
        if name not in da or name not in db:
            print(f"{name}: only in {'B' if name not in da else 'A'}")
            differing += 1
            continue
        parts = [k for k in da[name] if da[name][k] != db[name].get(k)]
        print(f"{name}: {'identical' if not parts else 'DIFFERS in ' + ', '.join(parts)}")
        differing += bool(parts)
    print(f"{len(set(da) | set(db)) - differing} of {len(set(da) | set(db))} inputs identical")
    return 1 if differing else 0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    d = sub.add_parser("digest")
    d.add_argument("out", type=Path)
    d.add_argument("--measure", default="")
    d.add_argument("--src", type=Path, default=ROOT)
    d.add_argument("--real", action="store_true", help="also the shared real clips present")
    c = sub.add_parser("compare")
    c.add_argument("a", type=Path)
    c.add_argument("b", type=Path)
    args = parser.parse_args()
    if args.command == "digest":
        digest(args.out, args.measure, args.src.resolve(), args.real)
    else:
        sys.exit(compare(args.a, args.b))


if __name__ == "__main__":
    main()
