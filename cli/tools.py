"""``motiondetect info``, ``synth`` and ``evaluate``."""

from __future__ import annotations

import csv
import json
import sys
from pathlib import Path

import click
from motiondetect_cli.common import _fail, _guard, _setup_logging

# ----------------------------------------------------------------------------
# info
# ----------------------------------------------------------------------------


@click.command()
@click.argument("inputs", nargs=-1, required=True, type=click.Path())
@click.option("--json", "as_json", is_flag=True, help="One JSON object per input.")
def info(inputs, as_json) -> None:
    """Print what the tool sees in each input: frames, fps, size and codec."""
    from motiondetect.detection.streaming import auto_frame_skip
    from motiondetect.io.video import VideoError, open_source

    failed = 0
    for path in inputs:
        try:
            with open_source(path) as source:
                meta = source.info.to_json()
                numbering = getattr(source, "numbering", None)  # frames folders
        except VideoError as exc:
            click.echo(f"error: {exc}", err=True)
            failed += 1
            continue
        skip = auto_frame_skip(meta["fps"])  # detect's --frame-skip auto
        if as_json:
            click.echo(json.dumps(meta | ({"numbering": numbering} if numbering else {})))
        else:
            click.echo(
                f"{path}: {meta['kind']}, {meta['width']}x{meta['height']}, "
                f"{meta['fps']:.3f} fps"
                + (" (assumed)" if meta["fps_source"] == "assumed" else "")
                + f", {meta['frame_count']} frames, "
                f"{meta['duration_s']:.2f} s, codec {meta['codec']}"
                + (f", rotation {meta['rotation_deg']} deg" if meta["rotation_deg"] else "")
                + (
                    f", files numbered {numbering['first']}-{numbering['last']}"
                    + (f" with {numbering['gaps']} gaps" if numbering["gaps"] else "")
                    if numbering
                    else ""
                )
                + (f"; detect judges one frame in {skip + 1}" if skip else "")
            )
    sys.exit(1 if failed else 0)


# ----------------------------------------------------------------------------
# synth
# ----------------------------------------------------------------------------


@click.command()
@click.argument("output", type=click.Path(path_type=Path, file_okay=False))
@click.option(
    "--camera",
    type=click.Choice(
        ["static", "uniform", "pan", "forward", "oblique", "forward-yaw", "fixation", "jitter"]
    ),
    default="uniform",
    show_default=True,
    help="Observer motion (the paper's classes 0-5).",
)
@click.option(
    "--mover",
    "movers",
    multiple=True,
    type=click.Choice(["smooth", "on-ray", "animate", "emerging"]),
    help="Independent movers (repeatable; none for a rigid scene).",
)
@click.option("--frames", type=click.IntRange(2, 100000), default=60, show_default=True)
@click.option("--width", type=click.IntRange(64, 4096), default=320, show_default=True)
@click.option("--height", type=click.IntRange(64, 4096), default=240, show_default=True)
@click.option("--fps", type=click.FloatRange(1, 240), default=30.0, show_default=True)
@click.option(
    "--noise",
    type=click.FloatRange(0, 50),
    default=1.0,
    show_default=True,
    help="Sensor noise, grey levels (std).",
)
@click.option("--speed", type=click.FloatRange(0.01, 20), default=1.0, show_default=True)
@click.option(
    "--jitter",
    type=click.FloatRange(0, 5),
    default=0.0,
    show_default=True,
    help="Rotational jitter per frame, degrees (std).",
)
@click.option(
    "--period",
    type=click.IntRange(4, 1000),
    default=20,
    show_default=True,
    help="Oscillation period of animate movers, frames.",
)
@click.option("--supersample", type=click.IntRange(1, 4), default=2, show_default=True)
@click.option(
    "--seed", type=int, default=0, show_default=True, help="Of the sensor noise and the jitter."
)
@click.option(
    "--world-seed",
    type=click.IntRange(0, None),
    default=0,
    show_default=True,
    help="Lay out the rigid world's boxes and near post anew; 0: the samples' world.",
)
def synth(
    output,
    camera,
    movers,
    frames,
    width,
    height,
    fps,
    noise,
    speed,
    jitter,
    period,
    supersample,
    seed,
    world_seed,
) -> None:
    """Render a rigid 3-D scene seen by a moving camera, with ground truth."""
    from motiondetect.tools.synth import SynthConfig, write_sequence

    with _guard(False):
        config = SynthConfig(
            camera=camera,
            movers=tuple(movers),
            width=width,
            height=height,
            frames=frames,
            fps=fps,
            noise_grey=noise,
            speed=speed,
            jitter_deg=jitter,
            period_frames=period,
            supersample=supersample,
            seed=seed,
            world_seed=world_seed,
        )
        try:
            output.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            _fail(f"cannot create {output}: {exc.strerror or exc}")
        write_sequence(config, output)
        click.echo(f"wrote {output}/video.mp4, {output}/truth/, {output}/scene.json")


# ----------------------------------------------------------------------------
# evaluate
# ----------------------------------------------------------------------------


@click.command()
@click.argument("pred", type=click.Path(path_type=Path, exists=True, file_okay=False))
@click.argument("gt", type=click.Path(path_type=Path, exists=True))
@click.option(
    "--warmup",
    type=click.IntRange(0),
    default=2,
    show_default=True,
    help="Frames at the start not scored (detector history).",
)
@click.option(
    "-o",
    "--output",
    type=click.Path(path_type=Path, dir_okay=False),
    help="Write the table as .csv or .json.",
)
def evaluate(pred, gt, warmup, output) -> None:
    """Score predicted masks (detect --masks) against ground-truth masks.

    Pixels follow changedetection.net: ground truth 0 is background, 255 mover,
    85 and 170 are not scored. GT may instead be a box file (OTB's
    groundtruth_rect.txt: one x,y,w,h line per frame, or a folder holding
    it); then only obj.rec is scored, a hit being >= 10 % of the box flagged.
    The columns:

    \b
    recall   share of mover pixels flagged (TP / (TP + FN))
    spec     specificity: share of background pixels left alone (TN / (TN + FP))
    FPR      false positive rate: background pixels flagged (FP / (FP + TN))
    FNR      false negative rate: mover pixels missed (FN / (TP + FN))
    PWC      percentage of wrong classifications: 100 (FN + FP) / all scored pixels
    prec     precision: share of flagged pixels that are mover (TP / (TP + FP))
    F        F-measure: harmonic mean of precision and recall
    obj.rec  object recall: share of (frame, object) pairs with >= 10 % of
             the object's pixels flagged
    FA/frm   false-alarm regions per frame: flagged connected regions that
             touch no mover or unknown pixel
    cellF1   F1 over 10x10-pixel cells: a mover cell is >= 30 % mover, a
             background cell <= 5 % mover or unknown, a flagged cell >= 30 %
             flagged; cells in between are not scored
    frames   frames scored (warm-up frames and frames without ground truth are not)
    """
    from motiondetect.io.report import atomic_text
    from motiondetect.tools.evaluate import EvaluateError, format_table, table_rows
    from motiondetect.tools.evaluate import evaluate as run_evaluate

    _setup_logging(verbose=False, quiet=False)  # the alignment's warning
    try:
        rows = table_rows(run_evaluate(pred, gt, warmup=warmup))
    except EvaluateError as exc:
        _fail(str(exc))
    click.echo(format_table(rows))
    if output is not None:
        with atomic_text(output) as fp:
            if output.suffix.lower() == ".json":
                json.dump(rows, fp, indent=2)
            else:
                writer = csv.DictWriter(fp, fieldnames=list(rows[0]), lineterminator="\n")
                writer.writeheader()
                writer.writerows(rows)
