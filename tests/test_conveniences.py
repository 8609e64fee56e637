"""What users of motion-detection tools expect (issue 16): time ranges, event
times, thumbnails, a log file, events on stdout, readable timelines, info."""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path

import cv2
import numpy as np
import pytest
from click.testing import CliRunner
from motiondetect_cli.main import main

from motiondetect.app.times import TimeSpec, parse_time
from motiondetect.io.report import EVENT_COLUMNS
from motiondetect.io.timeline import tick_label, tick_step
from motiondetect.io.video import open_source

SAMPLE = Path(__file__).resolve().parents[1] / "sample_videos" / "uniform_mixed" / "video.mp4"


def run(*args, **kw):
    return CliRunner(**kw).invoke(main, [str(a) for a in args], catch_exceptions=False)


def records(out: Path) -> list[dict]:
    return [json.loads(x) for x in (out / "video" / "frames.jsonl").read_text().splitlines()]


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("1", TimeSpec(1.0, "s")),
        ("2.5s", TimeSpec(2.5, "s")),
        ("00:01:02.5", TimeSpec(62.5, "s")),
        ("01:02", TimeSpec(62.0, "s")),
        ("45f", TimeSpec(45.0, "f")),
    ],
)
def test_time_grammar(text, expected):
    assert parse_time(text) == expected


@pytest.mark.parametrize("text", ["-1", "abc", "1:75", "nan", "12x", "f"])
def test_bad_times_are_refused(text):
    with pytest.raises(ValueError, match="must be seconds"):
        parse_time(text, "--start")


def test_start_and_end_select_one_second_with_the_sources_times(tmp_path):
    result = run("detect", SAMPLE, "-o", tmp_path, "-q", "--no-video", "--start", "1", "--end", "2")
    assert result.exit_code == 0, result.output
    frames = records(tmp_path)
    with open_source(SAMPLE) as source:
        times = {f.index: round(f.time_s, 4) for f in source}
    assert [r["frame"] for r in frames] == list(range(30, 60))
    assert all(r["time_s"] == times[r["frame"]] for r in frames)
    assert all(1.0 <= r["time_s"] < 2.0 for r in frames)
    by_frames = tmp_path / "f"
    run("detect", SAMPLE, "-o", by_frames, "-q", "--no-video", "--start", "30f", "--end", "35f")
    assert [r["frame"] for r in records(by_frames)] == list(range(30, 36))
    assert run("detect", SAMPLE, "-o", tmp_path, "--start", "2", "--end", "1").exit_code == 2
    assert run("detect", SAMPLE, "-o", tmp_path, "--start", "1", "--end", "1").exit_code == 2
    one = tmp_path / "one"  # an end frame is included: 33f to 33f is frame 33
    result = run("detect", SAMPLE, "-o", one, "-q", "--no-video", "--start", "33f", "--end", "33f")
    assert result.exit_code == 0, result.output
    assert [r["frame"] for r in records(one)] == [33]
    assert run("detect", SAMPLE, "-o", tmp_path, "--start", "34f", "--end", "33f").exit_code == 2


def test_a_start_past_the_end_says_where_the_input_ends(tmp_path):
    with open_source(SAMPLE) as source:
        last = list(source)[-1]
    result = run("detect", SAMPLE, "-o", tmp_path, "--no-video", "--start", "1000")
    assert result.exit_code == 1 and "Traceback" not in result.output
    said = f"no frame lies between --start and --end: the input ends at frame {last.index} "
    assert said + f"({last.time_s:.2f} s)" in result.output


def test_event_times_in_seconds_equal_their_frames(tmp_path):
    common = ("detect", SAMPLE, "-q", "--no-video", "--print-events")
    in_frames = run(*common, "-o", tmp_path / "a", "--min-event-frames", "15", "--pad-frames", "0")
    in_time = run(*common, "-o", tmp_path / "b", "--min-event", "0.5s", "--pad", "00:00:00")
    assert in_frames.exit_code == in_time.exit_code == 0
    assert in_frames.stdout == in_time.stdout and in_frames.stdout.count("\n") >= 2


def test_print_events_with_q_prints_csv_and_nothing_else(tmp_path):
    result = run("detect", SAMPLE, "-o", tmp_path, "-q", "--no-video", "--print-events")
    assert result.exit_code == 0 and result.stderr == ""
    rows = list(csv.reader(io.StringIO(result.stdout)))
    assert rows[0] == EVENT_COLUMNS
    events = json.loads((tmp_path / "video" / "summary.json").read_text())["events"]
    assert len(rows) - 1 == len(events) >= 1
    assert [int(r[0]) for r in rows[1:]] == [e["event"] for e in events]


def test_thumbnails_one_jpeg_per_event_at_its_peak_with_boxes(tmp_path):
    result = run("detect", SAMPLE, "-o", tmp_path, "-q", "--no-video", "--thumbnails")
    assert result.exit_code == 0
    events = json.loads((tmp_path / "video" / "summary.json").read_text())["events"]
    thumbs = sorted((tmp_path / "video" / "thumbnails").glob("event_*.jpg"))
    assert events and len(thumbs) == len(events)
    with open_source(SAMPLE) as source:
        frames = {f.index: f.image for f in source}
    for ev, path in zip(events, thumbs):
        image = cv2.imread(str(path))
        raw = frames[ev["peak_frame"]]
        assert image.shape == raw.shape
        scores = {i: cv2.PSNR(image, f) for i, f in frames.items()}
        assert max(scores, key=scores.get) == ev["peak_frame"]  # the right frame
        assert scores[ev["peak_frame"]] < 40  # with its boxes drawn


def test_logfile_gets_the_debug_log(tmp_path):
    log = tmp_path / "run.log"
    result = run("detect", SAMPLE, "-o", tmp_path, "-q", "--no-video", "--logfile", log)
    assert result.exit_code == 0
    text = log.read_text()
    assert "processing into" in text and "done, 60 frames" in text
    assert run("detect", SAMPLE, "-o", tmp_path, "--logfile", tmp_path).exit_code == 2


def test_timeline_ticks_are_round():
    assert tick_step(2.0) == 0.2 and tick_step(24.0) == 5 and tick_step(3600.0) == 600
    assert tick_label(1.5, 0.5) == "1.5 s" and tick_label(20, 5) == "20 s"
    assert tick_label(90, 30) == "1:30" and tick_label(3900, 600) == "1:05:00"


def test_info_marks_an_assumed_frame_rate(tmp_path):
    folder = tmp_path / "frames"
    folder.mkdir()
    for i in range(3):
        cv2.imwrite(str(folder / f"{i}.png"), np.full((80, 80), 40 * i, np.uint8))
    assert "(assumed)" in run("info", folder).stdout
    assert "(assumed)" not in run("info", SAMPLE).stdout
    assert "files numbered 0-2" in run("info", folder).stdout
    (folder / "1.png").rename(folder / "7.png")  # a sub-sampled sequence: 0, 2, 7
    assert "3 frames, 0.27 s, " in run("info", folder).stdout  # timed by number: 8 steps
    assert "files numbered 0-7 with 2 gaps" in run("info", folder).stdout
    meta = json.loads(run("info", folder, "--json").stdout)
    assert meta["numbering"] == {"first": 0, "last": 7, "gaps": 2}
    assert "numbering" not in json.loads(run("info", SAMPLE, "--json").stdout)


def test_evaluate_help_explains_every_column():
    from motiondetect.tools.evaluate import format_table

    heads = format_table([]).split()
    text = run("evaluate", "--help").stdout
    for head in heads[1:]:  # every column the table prints, "sequence" aside
        assert f"\n  {head} " in text, head
