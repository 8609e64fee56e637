"""Fresh synthetic scenes with exact ground truth, beyond the committed samples.

    python benchmarks/synth_set.py                 # render what is missing
    python benchmarks/sweep.py synth-rigid,synth-movers '{"default": {}}' --per-sequence

The nine committed samples (``sample_videos/``) are one rendering each, at
one speed and one noise seed, in an older MPEG-4 encoding. A rule tuned on
them can fit that rendering: a fresh H.264 render of ``uniform_rigid``
(same scene, same seed) gives about 0.15 false-alarm regions per frame and
one event against the committed file's 0.09 and none. This set renders
every moving camera of ``motiondetect synth`` at two speeds (0.7 and 1.4
times the samples'), with noise seeds the samples do not use, twice: with
no mover (``synth-rigid``: every flagged region is a false alarm) and with
a smooth and an animate mover (``synth-movers``).

The scenes go to ``$MOTIONDETECT_SYNTH`` (default: a folder in the
system's temporary directory), never into the checkout; each is rendered
once and reused. ``compare.sequences(synth=True)`` lists them. ``--world N``
lays the rigid world out anew (``motiondetect synth --world-seed``); render
it into a folder of its own and point ``$MOTIONDETECT_SYNTH`` there:

    MOTIONDETECT_SYNTH=/tmp/synth-world3 python benchmarks/synth_set.py --world 3

``--rate 2`` records the same scenes at 60 frames/s (the same paths in
time, half the motion per frame; docs/detectors.md, "Judged about every
1/30 s"):

    MOTIONDETECT_SYNTH=/tmp/synth60 python benchmarks/synth_set.py --rate 2
"""

from __future__ import annotations

import argparse
import shutil
from multiprocessing import Pool
from pathlib import Path

from common import SYNTH_SET

from motiondetect.tools.synth import SynthConfig, write_sequence

#: The moving cameras (``static`` is the samples' still-camera control).
CAMERAS = ("uniform", "pan", "forward", "oblique", "forward-yaw", "fixation", "jitter")
SPEEDS = (0.7, 1.4)
#: Movers of the "movers" half; the "rigid" half has none.
MOVERS = ("smooth", "animate")
FRAMES = 60
#: Noise seeds, none of them the samples' (1).
SEEDS = {0.7: 107, 1.4: 114}


def scenes(world_seed: int = 0, rate: int = 1) -> list[tuple[str, SynthConfig]]:
    """(folder name under the set, what to render) for every scene of the set,
    in the world laid out by ``world_seed`` (0: the samples'), recorded at
    ``rate`` times 30 frames/s: the same paths in time, a ``rate``-th of the
    motion per frame."""
    out = []
    for kind, movers in (("rigid", ()), ("movers", MOVERS)):
        for camera in CAMERAS:
            for speed in SPEEDS:
                config = SynthConfig(
                    camera=camera, movers=movers, frames=FRAMES * rate, speed=speed / rate,
                    fps=30.0 * rate, period_frames=SynthConfig.period_frames * rate,
                    seed=SEEDS[speed], world_seed=world_seed,
                )  # fmt: skip
                out.append((f"{kind}/{camera}-x{speed}", config))
    return out


def _render(job: tuple[Path, SynthConfig]) -> str:
    folder, config = job
    partial = folder.with_name(folder.name + ".partial")
    shutil.rmtree(partial, ignore_errors=True)  # left by a run that was stopped
    write_sequence(config, partial)
    partial.rename(folder)  # a scene is there whole or not at all
    return folder.name


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("out", nargs="?", type=Path, default=SYNTH_SET)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument(
        "--world", type=int, default=0, help="world seed of every scene (0: the samples' world)"
    )
    parser.add_argument(
        "--rate", type=int, default=1, help="record at RATE x 30 frames/s (same paths in time)"
    )
    args = parser.parse_args()
    todo = []
    for name, config in scenes(args.world, args.rate):
        folder = args.out / name
        if not (folder / "scene.json").exists():
            folder.parent.mkdir(parents=True, exist_ok=True)
            todo.append((folder, config))
    with Pool(args.jobs) as pool:
        for name in pool.imap_unordered(_render, todo):
            print("rendered", name, flush=True)
    print(f"{len(scenes())} scenes in {args.out} ({len(todo)} rendered now)")


if __name__ == "__main__":
    main()
