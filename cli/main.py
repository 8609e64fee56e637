"""The ``motiondetect`` command. Click parses and validates; the library runs.

Exit codes: 0 every input done, 1 some inputs failed (the others finished),
2 usage error. Each failure is one line; ``-v`` adds tracebacks.
"""

from __future__ import annotations

import csv
import json
import logging
import sys
from pathlib import Path

import click
from tqdm import tqdm
from tqdm.contrib.logging import logging_redirect_tqdm

from motiondetect import __version__
from motiondetect.app.settings import DEFAULTS, SettingsError, load_config_file, make_settings

log = logging.getLogger("motiondetect")


def _setup_logging(verbose: bool, quiet: bool) -> None:
    level = logging.DEBUG if verbose else (logging.ERROR if quiet else logging.WARNING)
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(logging.Formatter("%(levelname)s: %(message)s"))
    log.handlers[:] = [handler]
    log.setLevel(level)
    log.propagate = False


def _fail(message: str, code: int = 1) -> None:
    click.echo(f"error: {message}", err=True)
    sys.exit(code)


def _guard(verbose: bool):
    """Turn unexpected exceptions into one line (traceback with -v)."""

    class Guard:
        def __enter__(self):
            return self

        def __exit__(self, exc_type, exc, tb):
            if exc_type is None or issubclass(
                exc_type, (SystemExit, click.exceptions.Exit, click.ClickException)
            ):
                return False
            if issubclass(exc_type, KeyboardInterrupt):
                click.echo("interrupted", err=True)
                sys.exit(130)
            if verbose:
                return False
            click.echo(f"error: {exc}", err=True)
            sys.exit(1)

    return Guard()


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="motiondetect")
def main() -> None:
    """Find independently moving objects in video shot by a moving camera."""


# ----------------------------------------------------------------------------
# detect
# ----------------------------------------------------------------------------


def _d(key: str) -> str:
    return f"(default: {DEFAULTS[key]})"


@main.command()
@click.argument("inputs", nargs=-1, required=True, type=click.Path(path_type=Path))
@click.option(
    "-o", "--output", type=click.Path(path_type=Path), help=f"Output folder {_d('output')}."
)
@click.option(
    "--detector",
    type=click.Choice(["constraint-ray", "animate", "both"]),
    help=f"Which detector {_d('detector')}.",
)
@click.option(
    "--measure",
    type=click.Choice(["velocity", "normal"]),
    help="Motion measurement: the dense 2-D velocity, or the paper's 64x64 normal flow "
    f"{_d('measure')}.",
)
@click.option(
    "--persistence",
    type=click.IntRange(1, 30),
    help="Report a region only if it overlaps flagged cells in each of the previous "
    f"N-1 frames; 1 is the detectors' raw output {_d('persistence')}.",
)
@click.option("--masks/--no-masks", default=None, help="Write masks/NNNNNN.png (0/255).")
@click.option("--video/--no-video", default=None, help="Write annotated.webm (default: on).")
@click.option(
    "--video-format",
    type=click.Choice(["webm", "mp4"]),
    help="annotated.webm (VP8, plays in browsers) or annotated.mp4 (MPEG-4 Part 2, "
    f"several times faster to encode, not for browsers) {_d('video_format')}.",
)
@click.option(
    "--work-size",
    type=click.IntRange(64, 4096),
    help=f"Long side of the working resolution, px {_d('work_size')}.",
)
@click.option(
    "--egomotion",
    type=click.Path(path_type=Path, exists=True, dir_okay=False),
    help="Known camera motion (motiondetect ego-motion JSON or NeRF transforms.json).",
)
@click.option("-j", "--jobs", type=click.IntRange(1, 64), help="Inputs processed in parallel.")
@click.option(
    "--overwrite/--no-overwrite",
    default=None,
    help="Redo inputs already finished (default: skip them).",
)
@click.option(
    "-r",
    "--recursive/--no-recursive",
    default=None,
    help="Descend into sub-folders of a batch directory.",
)
@click.option(
    "--frames-fps",
    type=click.FloatRange(0.1, 1000),
    help=f"Frame rate of image-sequence inputs {_d('frames_fps')}.",
)
@click.option(
    "--ego-model",
    type=click.Choice(["fitted", "paper"]),
    help=f"Constraint ray model {_d('ego_model')}.",
)
@click.option(
    "--arithmetic",
    type=click.Choice(["float", "lut"]),
    help=f"Stage arithmetic {_d('arithmetic')}.",
)
@click.option("--pyramid/--no-pyramid", default=None, help="Coarse level for fast motion (on).")
@click.option(
    "--first-appearance",
    type=click.Choice(["ignore", "flag"]),
    help=f"Animate detector: motion no footprint predicted {_d('first_appearance')}.",
)
@click.option(
    "--jitter-compensation/--no-jitter-compensation",
    default=None,
    help="Animate detector: remove the frame's global jitter shift (on).",
)
@click.option("--min-event-frames", type=int, help=f"Shortest event {_d('min_event_frames')}.")
@click.option("--merge-gap-frames", type=int, help=f"Gap bridged {_d('merge_gap_frames')}.")
@click.option("--pad-frames", type=int, help=f"Event padding {_d('pad_frames')}.")
@click.option(
    "--extract-clips/--no-extract-clips",
    default=None,
    help="Write events/event_NNNN.mp4, one clip per event.",
)
@click.option(
    "--clips-annotated/--no-clips-annotated", default=None, help="Draw the detections on the clips."
)
@click.option(
    "--roi", multiple=True, metavar="X,Y,W,H", help="Region of interest in input px (repeatable)."
)
@click.option(
    "--roi-file",
    type=click.Path(path_type=Path, exists=True, dir_okay=False),
    help="Polygons, one per line: 'x,y x,y x,y ...'.",
)
@click.option("--min-area", type=click.IntRange(0), help="Drop detections smaller than this, px.")
@click.option("--timeline/--no-timeline", default=None, help="Write timeline.png (on).")
@click.option(
    "--config",
    "config_file",
    type=click.Path(path_type=Path, dir_okay=False),
    help="TOML file with the same keys as these options.",
)
@click.option("-q", "--quiet", is_flag=True, help="No progress bars or tables.")
@click.option("-v", "--verbose", is_flag=True, help="Debug logging and tracebacks.")
def detect(inputs, config_file, quiet, verbose, **options) -> None:
    """Detect independent motion in videos, frame folders or directories of videos."""
    from motiondetect.app.runner import InputError, run

    _setup_logging(verbose, quiet)
    with _guard(verbose):
        try:
            values = load_config_file(config_file) if config_file else {}
            values.update({k: v for k, v in options.items() if v is not None and v != ()})
            settings = make_settings(values)
        except SettingsError as exc:
            raise click.UsageError(str(exc)) from exc
        bars: dict = {}

        def on_start(job, expected):
            if quiet:
                return None
            bar = tqdm(desc=str(job.name)[-30:], unit="frame", leave=False, dynamic_ncols=True)
            bars["frame"] = bar

            def progress(done, total):
                if total and bar.total != total:
                    bar.total = total
                bar.update(done - bar.n)

            return progress

        bars["overall"] = None

        def on_jobs(count):
            if count > 1 and not quiet:
                bars["overall"] = tqdm(total=count, desc="inputs", unit="input", dynamic_ncols=True)

        def on_done(result):
            bar = bars.pop("frame", None)
            if bar is not None:
                bar.close()
            if bars["overall"] is not None:
                bars["overall"].update(1)
            if result.status == "failed":
                log.error("%s", result.message)

        with logging_redirect_tqdm(loggers=[log]):
            try:
                result = run(
                    list(inputs),
                    settings,
                    on_start=on_start if settings.jobs == 1 else None,
                    on_done=on_done,
                    on_jobs=on_jobs,
                )
            except InputError as exc:
                _fail(str(exc))
            finally:
                if bars["overall"] is not None:
                    bars["overall"].close()
        if not quiet:
            _print_summary(result)
        if result.failed:
            click.echo(f"{len(result.failed)} of {len(result.results)} inputs failed:", err=True)
            for failure in result.failed:
                click.echo(f"  {failure.message}", err=True)
        sys.exit(result.exit_code)


def _print_summary(result) -> None:
    for r in result.results:
        if r.status == "done":
            s = r.summary
            click.echo(
                f"{r.job.name}: {s['totals']['frames']} frames, {s['totals']['detections']} "
                f"detections, {s['totals']['events']} events, {s['speed']['frames_per_s']} fps"
                + (" (partial input)" if s["status"] == "partial" else "")
            )
            for ev in s["events"][:10]:
                click.echo(
                    f"  event {ev['event']}: {ev['start_timecode']} - {ev['end_timecode']}"
                    f"  peak {ev['peak_score']:.2f}  {'+'.join(ev['detectors'])}"
                )
            if len(s["events"]) > 10:
                click.echo(f"  ... {len(s['events']) - 10} more in events.csv")
        elif r.status == "skipped":
            click.echo(f"{r.job.name}: skipped, {r.message}")


# ----------------------------------------------------------------------------
# info
# ----------------------------------------------------------------------------


@main.command()
@click.argument("inputs", nargs=-1, required=True, type=click.Path(path_type=Path))
@click.option("--json", "as_json", is_flag=True, help="One JSON object per input.")
def info(inputs, as_json) -> None:
    """Print what the tool sees in each input: frames, fps, size and codec."""
    from motiondetect.io.video import VideoError, open_source

    failed = 0
    for path in inputs:
        try:
            with open_source(path) as source:
                meta = source.info.to_json()
        except VideoError as exc:
            click.echo(f"error: {exc}", err=True)
            failed += 1
            continue
        if as_json:
            click.echo(json.dumps(meta))
        else:
            click.echo(
                f"{path}: {meta['kind']}, {meta['width']}x{meta['height']}, "
                f"{meta['fps']:.3f} fps, {meta['frame_count']} frames, "
                f"{meta['duration_s']:.2f} s, codec {meta['codec']}"
                + (f", rotation {meta['rotation_deg']} deg" if meta["rotation_deg"] else "")
            )
    sys.exit(1 if failed else 0)


# ----------------------------------------------------------------------------
# synth
# ----------------------------------------------------------------------------


@main.command()
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
@click.option("--seed", type=int, default=0, show_default=True)
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


@main.command()
@click.argument("pred", type=click.Path(path_type=Path, exists=True, file_okay=False))
@click.argument("gt", type=click.Path(path_type=Path, exists=True, file_okay=False))
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
    """Score predicted masks (detect --masks) against ground-truth masks."""
    from motiondetect.io.report import atomic_text
    from motiondetect.tools.evaluate import EvaluateError, format_table, table_rows
    from motiondetect.tools.evaluate import evaluate as run_evaluate

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


if __name__ == "__main__":  # pragma: no cover
    main()
