"""``motiondetect detect``: click builds the settings, one library call runs them."""

from __future__ import annotations

import logging
import sys
from pathlib import Path

import click
from motiondetect_cli.common import _fail, _guard, _setup_logging, close_log_files
from tqdm import tqdm

from motiondetect.app.settings import (
    SettingsError,
    choices_of,
    default_of,
    load_config_file,
    make_settings,
)

log = logging.getLogger("motiondetect")


def _number_or_word(_ctx, _param, value: str | None) -> int | str | None:
    """An option's text as a whole number where it is one ("auto" stays a word);
    the settings check what it may be (a click callback)."""
    try:
        return int(value) if value is not None else None
    except ValueError:
        return value


def _d(key: str) -> str:
    value = default_of(key)
    if isinstance(value, dict):
        value = ", ".join(f"{v} with --measure {k}" for k, v in value.items())
    return f"(default: {value})"


@click.command()
@click.argument("inputs", nargs=-1, required=True, type=click.Path())
@click.option(
    "-o", "--output", type=click.Path(path_type=Path), help=f"Output folder {_d('output')}."
)
@click.option(
    "--detector",
    type=click.Choice(choices_of("detector")),
    help=f"Which detector {_d('detector')}.",
)
@click.option(
    "--measure",
    type=click.Choice(choices_of("measure")),
    help="Motion measurement: the dense 2-D velocity, or the paper's 64x64 normal flow "
    f"{_d('measure')}.",
)
@click.option(
    "--persistence",
    type=int,
    help="Report a region only if it overlaps flagged cells in each of the previous "
    f"N-1 frames; 1 is the detectors' raw output {_d('persistence')}.",
)
@click.option("--masks/--no-masks", default=None, help="Write masks/NNNNNN.png (0/255).")
@click.option("--video/--no-video", default=None, help="Write annotated.mp4 (default: on).")
@click.option(
    "--video-format",
    type=click.Choice(choices_of("video_format")),
    help="mp4: H.264, plays in browsers and players; webm: VP8; mkv: lossless FFV1, "
    f"for frame-exact review {_d('video_format')}.",
)
@click.option(
    "--work-size",
    type=int,
    help=(
        "Long side of the working resolution (of the picture inside any black bars), px, "
        f"never above the input's {_d('work_size')}."
    ),
)
@click.option(
    "--flow-preset",
    type=click.Choice(choices_of("flow_preset")),
    help=f"Dense-flow (DIS) preset of the velocity measurement {_d('flow_preset')}.",
)
@click.option(
    "--video-size",
    type=int,
    help=f"Long side of the annotated video, px {_d('video_size')}; an input narrower "
    "than 320 px is enlarged to 320 wide within it.",
)
@click.option(
    "--egomotion",
    type=click.Path(path_type=Path, exists=True, dir_okay=False),
    help="Known camera motion (motiondetect ego-motion JSON or NeRF transforms.json).",
)
@click.option(
    "--focal-share",
    type=float,
    help="The lens's focal length as a share of the frame's long side, its 35 mm-equivalent "
    "focal length over 36 (a phone's main camera: 26/36); 0 turns off the test that "
    f"drops near rigid objects {_d('focal_share')}.",
)
@click.option(
    "--rolling-shutter",
    type=float,
    metavar="GAIN",
    help="Take a rolling shutter's wobble (a vibrating phone, dashcam or action camera) out "
    "of the fitted camera motion where a function of the sensor line takes at least GAIN of "
    "what the motion leaves in each quarter of the frame; 0.15 measured on vibrating copies "
    f"of the shared clips, 0 off {_d('rolling_shutter')}.",
)
@click.option("-j", "--jobs", type=int, help="Inputs processed in parallel.")
@click.option(
    "--scheduler",
    metavar="local|tcp://HOST:PORT",
    help="Run the batch on Dask: a LocalCluster of --jobs workers, or an existing "
    "scheduler (needs the dask extra; the output folder must be shared by every worker).",
)
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
    "--include",
    multiple=True,
    metavar="GLOB",
    help="Only inputs whose path in a scanned folder matches (repeatable): '*.mp4'.",
)
@click.option(
    "--exclude",
    multiple=True,
    metavar="GLOB",
    help="Skip paths in a scanned folder that match (repeatable): 'Annotations'.",
)
@click.option(
    "--frames-fps",
    type=float,
    help="Frame rate of image-sequence inputs (default: 30, reported as assumed).",
)
@click.option(
    "--ego-model",
    type=click.Choice(choices_of("ego_model")),
    help=f"Constraint ray model {_d('ego_model')}.",
)
@click.option(
    "--arithmetic",
    type=click.Choice(choices_of("arithmetic")),
    help=f"Stage arithmetic {_d('arithmetic')}.",
)
@click.option("--pyramid/--no-pyramid", default=None, help="Coarse level for fast motion (on).")
@click.option(
    "--first-appearance",
    type=click.Choice(choices_of("first_appearance")),
    help=f"Animate detector: motion no footprint predicted {_d('first_appearance')}.",
)
@click.option(
    "--jitter-compensation/--no-jitter-compensation",
    default=None,
    help="Animate detector: remove the frame's global jitter shift (on).",
)
@click.option(
    "--frame-skip",
    metavar="N|auto",
    callback=_number_or_word,
    help="Judge one frame in N+1; the N after it carry its detections, marked held_from "
    "in frames.jsonl. About N+1 times faster, coarser in time; auto: one judged frame "
    f"about every 1/30 s, so 1 at 60 fps and 0 below 45 fps {_d('frame_skip')}.",
)
@click.option("--min-event-frames", type=int, help=f"Shortest event {_d('min_event_frames')}.")
@click.option("--merge-gap-frames", type=int, help=f"Gap bridged {_d('merge_gap_frames')}.")
@click.option("--pad-frames", type=int, help=f"Event padding {_d('pad_frames')}.")
@click.option(
    "--min-event", metavar="TIME", help="Shortest event as a time (1.5s, 00:00:01.5 or 45f)."
)
@click.option("--merge-gap", metavar="TIME", help="Gap bridged, as a time.")
@click.option("--pad", metavar="TIME", help="Event padding, as a time.")
@click.option(
    "--start", metavar="TIME", help="Start here: seconds (12.5), a timecode (00:00:12.5) or 45f."
)
@click.option("--end", metavar="TIME", help="Stop here (seconds end before it; frames include it).")
@click.option(
    "--thumbnails/--no-thumbnails",
    default=None,
    help="Write thumbnails/event_NNNN.jpg: each event's peak frame with its boxes.",
)
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
@click.option("--min-area", type=int, help="Drop detections smaller than this, px.")
@click.option("--timeline/--no-timeline", default=None, help="Write timeline.png (on).")
@click.option(
    "--config",
    "config_file",
    type=click.Path(path_type=Path, dir_okay=False),
    help="TOML file with the same keys as these options.",
)
@click.option(
    "--logfile",
    type=click.Path(path_type=Path, dir_okay=False),
    help="Also write the log here, debug messages included.",
)
@click.option(
    "--print-events",
    is_flag=True,
    help="Print the events as CSV on stdout (with -q, nothing else is printed there).",
)
@click.option("-q", "--quiet", is_flag=True, help="No progress bars or tables.")
@click.option("-v", "--verbose", is_flag=True, help="Debug logging and tracebacks.")
def detect(inputs, config_file, quiet, verbose, logfile, print_events, **options) -> None:
    """Detect independent motion in videos, frame folders or directories of videos."""
    _setup_logging(verbose, quiet, logfile)
    try:
        _detect(inputs, config_file, quiet, verbose, print_events, options)
    finally:
        close_log_files()


def _detect(inputs, config_file, quiet, verbose, print_events, options: dict) -> None:
    from motiondetect.app.runner import InputError, batch_events, run
    from motiondetect.io.report import write_events_csv

    with _guard(verbose):
        try:
            values = load_config_file(config_file) if config_file else {}
            values.update({k: v for k, v in options.items() if v is not None and v != ()})
            settings = make_settings(values)
        except SettingsError as exc:
            raise click.UsageError(str(exc)) from exc
        bars = _Bars(quiet)
        try:
            result = run(
                list(inputs),
                settings,
                on_start=bars.on_start if settings.jobs == 1 else None,
                on_done=bars.on_done,
                on_jobs=bars.on_jobs,
            )
        except InputError as exc:
            _fail(str(exc))
        finally:
            bars.close()
        if print_events:
            rows = batch_events(settings.output, result.results)
            write_events_csv(sys.stdout, rows, with_input=len(result.results) > 1)
        elif not quiet:
            _print_summary(result)
        if result.failed:
            click.echo(f"{len(result.failed)} of {len(result.results)} inputs failed:", err=True)
            for failure in result.failed:
                click.echo(f"  {failure.message}", err=True)
        sys.exit(result.exit_code)


class _Bars:
    """Progress bars: one per input (frames) and one for the batch (inputs),
    drawn only on a terminal (``disable=None``): redirected to a log file,
    each bar's redraws would fill it.

    A failure is logged as it happens unless ``quiet``; the closing list
    names every failure once more, so ``-q`` prints each exactly once.
    """

    def __init__(self, quiet: bool) -> None:
        self.quiet = quiet
        self.frame: tqdm | None = None
        self.overall: tqdm | None = None

    def on_start(self, job, expected):
        if self.quiet:
            return None
        bar = tqdm(
            desc=str(job.name)[-30:], unit="frame", leave=False, dynamic_ncols=True, disable=None
        )
        self.frame = bar

        def progress(done, total):
            if total and bar.total != total:
                bar.total = total
            bar.update(done - bar.n)

        return progress

    def on_jobs(self, count: int) -> None:
        if count > 1 and not self.quiet:
            self.overall = tqdm(
                total=count, desc="inputs", unit="input", dynamic_ncols=True, disable=None
            )

    def on_done(self, result) -> None:
        if self.frame is not None:
            self.frame.close()
            self.frame = None
        if self.overall is not None:
            self.overall.update(1)
        if result.status == "failed" and not self.quiet:
            log.error("%s", result.message)

    def close(self) -> None:
        if self.overall is not None:
            self.overall.close()


def _unreliable(counts: dict) -> str:
    """The summary line's tail naming the frames that could not be judged,
    such as ``; 6 frames unreliable (2 cut, 4 motion beyond the band)``; empty when none."""
    if not counts:
        return ""
    reasons = ", ".join(f"{n} {reason}" for reason, n in counts.items())
    return f"; {sum(counts.values())} frames unreliable ({reasons})"


def _overlay(frames: int) -> str:
    """The printed line's note of a burnt-in caption or logo left unflagged."""
    return f"; a caption or logo fixed to the screen left out on {frames} frames" if frames else ""


def _repeated(frames: int) -> str:
    """The printed line's note of frames that repeated the one before."""
    return f"; {frames} frames repeated the one before (their results held)" if frames else ""


def _picture(box: list[int] | None) -> str:
    """The printed line's note of black bars left out."""
    if not box:
        return ""
    x, y, w, h = box
    return f"; black bars or side panels left out, picture {w}x{h} at ({x}, {y})"


def _plural(count: int, word: str) -> str:
    return f"{count} {word}{'s' * (count != 1)}"


def _tracks(count: int | None) -> str:
    """The number of movers tracked (tracks.csv), where tracks are kept."""
    return "" if not count else f" of {_plural(count, 'tracked object')}"


def _judged(totals: dict) -> str:
    """The printed line's note of frames skipped by ``--frame-skip``."""
    skipped = totals["frames"] - totals["frames_judged"] - totals.get("frames_repeated", 0)
    return f"; {totals['frames_judged']} judged, {skipped} held (--frame-skip)" if skipped else ""


def _print_summary(result) -> None:
    for r in result.results:
        if r.status == "done":
            s = r.summary
            click.echo(
                f"{r.job.name}: {_plural(s['totals']['frames'], 'frame')}, "
                f"{_plural(s['totals']['detections'], 'detection')}"
                f"{_tracks(s['totals'].get('tracks'))}, {_plural(s['totals']['events'], 'event')}, "
                f"{s['speed']['frames_per_s']} fps"
                + (" (partial input)" if s["status"] == "partial" else "")
                + _judged(s["totals"])
                + _unreliable(s["totals"].get("frames_unreliable", {}))
                + _overlay(s["totals"].get("frames_overlay", 0))
                + _repeated(s["totals"].get("frames_repeated", 0))
                + _picture(s["totals"].get("picture"))
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
