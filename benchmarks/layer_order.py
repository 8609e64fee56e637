r"""Which layer the layer-order test puts in front, frame by frame, on every clip.

    python benchmarks/layer_order.py davis,ucsd,sample,fox,otb,sbi

The test behind ``[fit] occluder_frames`` (``constraint_ray/layer_order.py``)
finds a mover that fills about half the view from the first frame, whose
motion the plane takes: its outline carries the background's boundary.
A clip where no mover does must never reach ``occluder_frames`` frames in a
row that put the plane's own layer in front. For each clip this prints the
verdicts, one character a frame (``+`` the plane's layer in front, ``-``
the other's, ``.`` undecided or not tested), and the longest run of ``+``
as the detector counts it: undecided frames skipped, a ``-`` or more than
``occluder_frames`` frames without a ``+`` starting again.
The plane here is the one all the samples vote for, each frame alone (no
tracks), as the detector's is before it has any.
"""

from __future__ import annotations

import argparse
from multiprocessing import Pool

import compare

from motiondetect.constraint_ray.camera_fit import fit_camera
from motiondetect.constraint_ray.fit_config import FitConfig
from motiondetect.constraint_ray.layer_order import LayerOrder
from motiondetect.detection.detector import MotionDetector
from motiondetect.io.video import open_source


def verdicts(job: tuple[str, object]) -> tuple[str, list[int], int]:
    name, source = job
    config = FitConfig()
    measuring, order, out, longest = MotionDetector("both"), LayerOrder(config), [], 0
    with open_source(source) as frames:
        for frame in frames:
            field = measuring.measure_frame(frame.grey)
            if field is None or not hasattr(field, "velocity_px"):
                order.reset()
                continue
            fit = fit_camera(field, config)
            out.append(order.update(field, fit.voted, fit.voted_inliers, fit.edge_band_px))
            longest = max(longest, order.run)
    return name, out, longest


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "datasets", help="comma-separated: davis,ucsd,sample,fox,otb,sbi,synth-rigid,synth-movers"
    )
    parser.add_argument("--jobs", type=int, default=2)
    args = parser.parse_args()
    groups = args.datasets.split(",")
    jobs = [
        (name, source)
        for name, source, _, _ in compare.sequences(quick=False, synth="synth" in args.datasets)
        if any(name.startswith(g) for g in groups)
    ]
    with Pool(args.jobs) as pool:
        results = pool.map(verdicts, jobs, chunksize=1)
    for name, seq, longest in results:
        marks = "".join("+" if v > 0 else "-" if v < 0 else "." for v in seq)
        print(f"{name:28s} longest run {longest}  {marks}")


if __name__ == "__main__":
    main()
