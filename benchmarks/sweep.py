r"""Variants of motiondetect side by side, pooled per data set (how docs/detectors.md is measured).

    python benchmarks/sweep.py davis,ucsd,sample,fox '{"default": {}}'
    python benchmarks/sweep.py davis,sample \
        '{"default": {}, "vr2": {"dense_flow": {"refinement_iterations": 2}}}'
    python benchmarks/sweep.py davis '{"dense": {"peer": "DenseResidual"}}' --per-sequence

Each variant is a JSON object of config sections, named as in a config file
(``fit``, ``velocity_ray``, ``velocity_animate``, ``track``, ``dense_flow``:
``motiondetect.app.settings.SECTIONS``), each with the fields it changes;
``"detector"`` picks the detectors (default ``both``), ``"measure"`` the
measurement (``velocity`` or the paper's ``normal``), ``"frame_skip"`` judges
every (n+1)-th frame and holds its mask on the others (``--frame-skip``;
default ``"auto"``, as the tool), and ``"peer"`` runs one
of ``compare.py``'s peers instead (``DenseResidual``, ``Mog2``, ...). Data sets
are the prefixes of ``compare.py``'s sequence names: ``sample``, ``davis``,
``ucsd``, ``sbi``, ``otb``, ``fox``, and the fresh renders of
``benchmarks/synth_set.py``, ``synth-rigid`` and ``synth-movers``. Scoring
is ``compare.py``'s, frames 0-1 unscored; sequences run in parallel
(``--jobs``), one OpenCV thread each.
With ``--seeds N`` each variant runs N times, RANSAC drawing other samples
each time (``[fit] seed`` 0 to N-1), and the pooled lines give the mean and
the range over the seeds: a difference between variants smaller than that
range is the fit's luck, not the variant (docs/detectors.md, "How much of a
difference is noise").
Set ``MOTIONDETECT_DATA`` to score another copy of the clips (for example
every 2nd frame, from ``benchmarks/subsample.py``, or through H.264 from
``benchmarks/recompress.py``).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
from multiprocessing import Pool

import compare
import cv2
import numpy as np

from motiondetect.app.settings import SECTIONS
from motiondetect.detection.detector import MotionDetector
from motiondetect.io.video import open_source, read_mask
from motiondetect.tools.evaluate import Counts


def configs(sections: dict) -> list:
    """Config dataclasses from ``{"section": {field: value}}``, each section's
    defaults with the fields given changed."""
    return [dataclasses.replace(SECTIONS[k](), **fields) for k, fields in sections.items()]


def on_masked_sequences(description: str, run) -> tuple[list[str], list]:
    """The command line ``datasets [config] [--jobs N]`` of the per-mask
    benchmarks (``fragments.py``, ``false_pixels.py``): ``run((name, source,
    truth folder, configs))`` on every sequence of those data sets with mask
    ground truth (OTB's boxes and the fox have none), in a pool. Returns the
    data sets asked for and the results, in sequence order."""
    parser = argparse.ArgumentParser(
        description=description, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("datasets", help="comma-separated: davis,ucsd,sbi,sample")
    parser.add_argument("config", nargs="?", default="{}", help="JSON: config sections")
    parser.add_argument("--jobs", type=int, default=2)
    args = parser.parse_args()
    sections = configs(json.loads(args.config))
    groups = args.datasets.split(",")
    jobs = [
        (name, source, gt, sections)
        for name, source, gt, _ in compare.sequences(quick=False)
        if gt is not None and gt.suffix != ".txt" and any(name.startswith(g) for g in groups)
    ]
    with Pool(args.jobs) as pool:
        return groups, pool.map(run, jobs, chunksize=1)


def scored_frames(job: tuple, detector: MotionDetector | None = None):
    """Each scored frame of one job of :func:`on_masked_sequences`, as
    ``(result, truth)``: the ``detector``'s ``FrameResult`` (by default one
    made with the job's config sections) and the frame's ground-truth mask,
    on one OpenCV thread. Every frame is run; those before
    ``compare.WARMUP`` or without a mask are not yielded."""
    _, source, gt, sections = job
    cv2.setNumThreads(1)
    detector = detector or MotionDetector("both", *sections)
    with open_source(source) as frames:
        masks = compare.gt_masks(gt, frames)
        for frame in frames:
            result = detector.process(frame.grey, frame.index, frame.time_s)
            if frame.index >= compare.WARMUP and frame.index in masks:
                yield result, read_mask(masks[frame.index])


def print_summed(description: str, run, line) -> None:
    """:func:`on_masked_sequences` with ``run``, each data set printed by
    :func:`print_by_group` with its sequences' arrays summed."""
    groups, results = on_masked_sequences(description, run)
    print_by_group(groups, results, line, lambda rows: np.sum(rows, axis=0))


def print_by_group(groups: list[str], results: list, line, pooled) -> None:
    """For each data set of ``groups``: its sequences' results (``results``
    as ``(name, result)`` pairs from :func:`on_masked_sequences`), one
    indented ``line(name, result)`` each, then ``line(group,
    pooled([result, ...]))`` for the data set as a whole."""
    for group in groups:
        rows = [(name, result) for name, result in results if name.startswith(group)]
        for name, result in rows:
            print("  " + line(name, result))
        print(line(group, pooled([result for _, result in rows])))


def method(name: str, spec: dict):
    """One variant as a per-frame method of ``compare.run_sequence``, named ``name``."""
    spec = dict(spec)
    peer = spec.pop("peer", None)
    if peer is not None:
        made = getattr(compare, peer)()
        made.name = name
        return made
    detector = spec.pop("detector", "both")
    skip = spec.pop("frame_skip", compare.AUTO)
    measure = spec.pop("measure", "velocity")
    return compare.Ours(
        detector, label=name, measure=measure, configs=configs(spec), frame_skip=skip
    )


def _run(job: tuple) -> tuple[str, dict[str, Counts]]:
    name, source, gt, variants = job
    cv2.setNumThreads(1)
    methods = [method(n, spec) for n, spec in variants.items()]
    return name, {k: counts for k, (counts, _) in compare.run_sequence(source, gt, methods).items()}


def summary(label: str, variant: str, counts: Counts, detail: bool = False) -> str:
    m = counts.metrics()
    text = (
        f"{label:28s} {variant:14s} cell F1 {m['cell_f1'] or 0:.3f}  object recall "
        f"{m['object_recall'] or 0:.3f} ({counts.objects_hit}/{counts.objects})  "
        f"FA/frame {m['false_alarm_regions_per_frame'] or 0:.2f}"
    )
    if detail:
        flagged = max(counts.cell_tp + counts.cell_fp, 1)
        positive = max(counts.cell_tp + counts.cell_fn, 1)
        text += f"  cell P {counts.cell_tp / flagged:.2f} R {counts.cell_tp / positive:.2f}"
    return text


def seeded(variants: dict, seeds: int) -> dict:
    """Each variant once per RANSAC seed, named ``name#seed`` (peers once)."""
    if seeds <= 1:
        return variants
    out = {}
    for name, spec in variants.items():
        if "peer" in spec:
            out[name] = spec
            continue
        for seed in range(seeds):
            fit = {**spec.get("fit", {}), "seed": seed}
            out[f"{name}#{seed}"] = {**spec, "fit": fit}
    return out


def spread(label: str, variant: str, runs: list[Counts]) -> str:
    """The mean and range of each pooled metric over the seeds' runs."""
    keys = ("cell_f1", "object_recall", "false_alarm_regions_per_frame")
    values = [[r.metrics()[k] or 0 for r in runs] for k in keys]
    parts = [
        f"{title} {sum(v) / len(v):.3f} ({min(v):.3f}-{max(v):.3f})"
        for title, v in zip(("cell F1", "object recall", "FA/frame"), values, strict=True)
    ]
    return f"{label:28s} {variant:14s} " + "  ".join(parts) + f"  over {len(runs)} seeds"


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument(
        "datasets",
        help="comma-separated: sample,davis,ucsd,sbi,otb,fox,synth-rigid,synth-movers",
    )
    parser.add_argument("variants", help="JSON object: variant name -> config sections")
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--per-sequence", action="store_true")
    parser.add_argument("--seeds", type=int, default=1, help="RANSAC seeds per variant")
    args = parser.parse_args()
    try:  # fail before any clip is read
        variants = json.loads(args.variants)
        for spec in variants.values():
            method("check", spec)
    except (ValueError, KeyError, TypeError, AttributeError) as exc:
        parser.error(f"bad variants: {exc}")
    groups = args.datasets.split(",")
    runs = seeded(variants, args.seeds)
    jobs = [
        (name, source, gt, runs)
        for name, source, gt, _ in compare.sequences(quick=False, synth="synth" in args.datasets)
        if any(name.startswith(g) for g in groups)
    ]
    with Pool(args.jobs) as pool:
        results = pool.map(_run, jobs, chunksize=1)
    for group in groups:
        for variant in variants:
            copies = [r for r in runs if r == variant or r.startswith(variant + "#")]
            pooled = {r: Counts() for r in copies}
            for name, counts in results:
                if name.startswith(group):
                    for r in copies:
                        pooled[r].add(counts[r])
                        if args.per_sequence:
                            print(summary("  " + name, r, counts[r], True))
            for r in copies:
                print(summary(group, r, pooled[r]), flush=True)
            if len(copies) > 1:
                print(spread(group, variant, list(pooled.values())), flush=True)


if __name__ == "__main__":
    main()
