"""The command line (issue 5), events/ROI/clips (issue 9), bad input (issue 8)."""

from __future__ import annotations

import csv
import json
import shutil
import subprocess
import sys
from pathlib import Path

import cv2
import jsonschema
import numpy as np
import pytest
from click.testing import CliRunner
from motiondetect_cli.main import main
from skimage import data

from motiondetect.detection.base import DETECTOR_SETS
from motiondetect.io.report import TRACK_COLUMNS
from motiondetect.io.video import count_decodable_frames

from .scenes import scene

DOCS = Path(__file__).resolve().parents[1] / "docs" / "schemas"
FRAME_SCHEMA = json.loads((DOCS / "frames.schema.json").read_text())
SUMMARY_SCHEMA = json.loads((DOCS / "summary.schema.json").read_text())


def write_video(path: Path, frames, fourcc: str = "mp4v", fps: float = 30.0) -> Path:
    h, w = frames[0].shape[:2]
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*fourcc), fps, (w, h))
    assert writer.isOpened()
    for f in frames:
        writer.write(f)
    writer.release()
    return path


@pytest.fixture(scope="session")
def clip_frames():
    """16 frames of a panning camera with a smooth mover (exact ground truth)."""
    return [fr.image for fr in scene("pan", ("smooth",), frames=16)]


@pytest.fixture(scope="session")
def clip(tmp_path_factory, clip_frames) -> Path:
    return write_video(tmp_path_factory.mktemp("clip") / "pan.mp4", clip_frames)


def decode_count(path: Path) -> int:
    return count_decodable_frames(path)


def invoke(*args: str) -> object:
    return CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)


def check_outputs(out: Path, frames: int, video: bool = True, timeline: bool = True) -> dict:
    summary = json.loads((out / "summary.json").read_text())
    jsonschema.validate(summary, SUMMARY_SCHEMA)
    lines = (out / "frames.jsonl").read_text().splitlines()
    assert len(lines) == frames == summary["totals"]["frames"]
    for i, line in enumerate(lines):
        record = json.loads(line)
        jsonschema.validate(record, FRAME_SCHEMA)
        assert record["frame"] == i
    rows = list(csv.reader((out / "detections.csv").read_text().splitlines()))
    assert rows[0] == [
        "frame", "time_s", "detectors", "x", "y", "w", "h", "area_px", "score", "track",
    ]  # fmt: skip
    assert len(rows) - 1 == summary["totals"]["detections"]
    tracks = [str(d.get("track", "")) for r in map(json.loads, lines) for d in r["detections"]]
    assert [row[-1] for row in rows[1:]] == tracks
    assert (out / "events.csv").exists()
    check_tracks(out, rows[1:], summary)
    assert (out / "timeline.png").exists() == timeline
    if video:
        assert decode_count(out / "annotated.mp4") == frames
    return summary


def check_tracks(out: Path, detections: list[list[str]], summary: dict) -> list[dict]:
    """tracks.csv agrees with detections.csv: one row per track id, with its
    first and last frame, its count and its peak score."""
    tracks = list(csv.DictReader((out / "tracks.csv").read_text().splitlines()))
    assert len(tracks) == summary["totals"]["tracks"]
    by_id: dict[str, list] = {}
    for row in detections:
        if row[-1]:
            by_id.setdefault(row[-1], []).append(row)
    assert sorted(t["track"] for t in tracks) == sorted(by_id)
    for t in tracks:
        rows = by_id[t["track"]]
        frames = [int(r[0]) for r in rows]
        assert (int(t["start_frame"]), int(t["end_frame"])) == (min(frames), max(frames))
        assert int(t["frames"]) == len(rows)
        assert float(t["peak_score"]) == max(float(r[8]) for r in rows)
    return tracks


def test_tracks_csv_follows_the_mover(tmp_path, clip):
    """The clip's one smooth mover is one track over most of its frames, its
    centre moving the way the mover's truth does."""
    assert invoke("detect", clip, "-o", tmp_path, "-q", "--no-video").exit_code == 0
    out = tmp_path / "pan"
    tracks = list(csv.DictReader((out / "tracks.csv").read_text().splitlines()))
    longest = max(tracks, key=lambda t: int(t["frames"]))
    assert int(longest["frames"]) >= 10  # of 16, the first two frames warming up
    truth = [fr.mask == 255 for fr in scene("pan", ("smooth",), frames=16)]
    first, last = int(longest["start_frame"]), int(longest["end_frame"])
    (y0, x0), (y1, x1) = (np.argwhere(truth[i]).mean(axis=0) for i in (first, last))
    moved = float(longest["end_cx"]) - float(longest["start_cx"])
    assert abs(x1 - x0) > 5 and np.sign(moved) == np.sign(x1 - x0)
    assert abs(moved - (x1 - x0)) < 0.5 * abs(x1 - x0)


def test_detect_writes_every_output(tmp_path, clip):
    result = invoke("detect", clip, "-o", tmp_path, "--masks", "-q")
    assert result.exit_code == 0, result.output
    out = tmp_path / "pan"
    summary = check_outputs(out, 16)
    assert summary["input"]["fps"] == pytest.approx(30.0)
    assert summary["totals"]["detections"] > 0
    masks = sorted((out / "masks").glob("*.png"))
    assert [m.name for m in masks] == [f"{i:06d}.png" for i in range(16)]
    mask = cv2.imread(str(masks[5]), cv2.IMREAD_UNCHANGED)
    assert mask.shape == (120 * 2, 160 * 2) and set(np.unique(mask)) <= {0, 255}


def test_frame_skip_reports_every_frame_with_the_judged_ones_results(tmp_path, clip):
    result = invoke("detect", clip, "-o", tmp_path, "--frame-skip", "1", "--masks", "-q")
    assert result.exit_code == 0, result.output
    out = tmp_path / "pan"
    summary = check_outputs(out, 16)  # every frame reported and in the video
    assert summary["totals"]["frames_judged"] == 8
    records = [json.loads(line) for line in (out / "frames.jsonl").read_text().splitlines()]
    for record in records:
        judged = record["frame"] - record["frame"] % 2
        assert record.get("held_from") == (None if judged == record["frame"] else judged)
        assert record["detections"] == records[judged]["detections"]
    assert sum(bool(r["detections"]) for r in records) >= 8
    masks = sorted((out / "masks").glob("*.png"))
    assert len(masks) == 16
    assert np.array_equal(cv2.imread(str(masks[7]), 0), cv2.imread(str(masks[6]), 0))


def test_frame_skip_with_known_egomotion_is_one_line_error(tmp_path, clip):
    scene_json = Path(__file__).resolve().parents[1] / "sample_videos/uniform_rigid/scene.json"
    result = invoke("detect", clip, "-o", tmp_path, "--frame-skip", "2", "--egomotion", scene_json)
    assert result.exit_code == 2
    assert "--frame-skip cannot be combined with --egomotion" in result.output
    assert "Traceback" not in result.output and not (tmp_path / "pan").exists()


def test_finished_inputs_are_skipped_unless_overwrite(tmp_path, clip):
    assert invoke("detect", clip, "-o", tmp_path, "--no-video", "-q").exit_code == 0
    stamp = (tmp_path / "pan" / "summary.json").stat().st_mtime_ns
    result = invoke("detect", clip, "-o", tmp_path, "--no-video")
    assert "skipped" in result.output
    assert (tmp_path / "pan" / "summary.json").stat().st_mtime_ns == stamp
    assert invoke("detect", clip, "-o", tmp_path, "--no-video", "--overwrite", "-q").exit_code == 0
    assert (tmp_path / "pan" / "summary.json").stat().st_mtime_ns != stamp


@pytest.mark.parametrize(
    "options",
    [
        ["--detector", "constraint-ray"],
        ["--detector", "constraint-ray", "--measure", "normal"],
        [
            "--detector",
            "animate",
            "--measure",
            "normal",
            "--first-appearance",
            "flag",
            "--no-jitter-compensation",
        ],
        ["--measure", "normal", "--work-size", "256", "--arithmetic", "lut", "--no-pyramid"],
        ["--measure", "normal", "--ego-model", "paper", "--frames-fps", "25"],
        ["--min-event-frames", "1", "--merge-gap-frames", "0", "--pad-frames", "0"],
        ["--no-timeline", "-v"],
        ["--persistence", "1"],
        ["--video-format", "mp4"],
    ],
)
def test_options_reach_the_settings(tmp_path, clip, options):
    video = ["--no-video"] if "--video-format" not in options else []
    result = invoke("detect", clip, "-o", tmp_path, "-q", *video, *options)
    assert result.exit_code == 0, result.output
    if "--video-format" in options:
        assert count_decodable_frames(tmp_path / "pan" / "annotated.mp4") == 16
    summary = check_outputs(
        tmp_path / "pan", 16, video=False, timeline="--no-timeline" not in options
    )
    settings = summary["settings"]
    pairs = dict(zip(options[::2], options[1::2]))
    for flag, value in pairs.items():
        key = flag.lstrip("-").replace("-", "_")
        if key in settings and not value.startswith("-"):
            assert str(settings[key]) == value or float(settings[key]) == float(value)
    if "--no-timeline" in options:
        assert not (tmp_path / "pan" / "timeline.png").exists()
    if "--detector" in pairs:
        found = {
            d
            for line in (tmp_path / "pan" / "frames.jsonl").read_text().splitlines()
            for det in json.loads(line)["detections"]
            for d in det["detectors"]
        }
        measure = pairs.get("--measure", "velocity")
        assert found <= set(DETECTOR_SETS[measure][pairs["--detector"]])
        if pairs["--detector"] == "constraint-ray":  # the clip's smooth mover is off the ray
            assert found


def test_config_file_sets_the_same_keys(tmp_path, clip):
    config = tmp_path / "md.toml"
    config.write_text('detector = "animate"\nwork-size = 320\nvideo = false\n')
    result = invoke("detect", clip, "-o", tmp_path / "out", "--config", config, "-q")
    assert result.exit_code == 0, result.output
    settings = json.loads((tmp_path / "out" / "pan" / "summary.json").read_text())["settings"]
    assert settings["detector"] == "animate" and settings["work_size"] == 320
    assert not (tmp_path / "out" / "pan" / "annotated.mp4").exists()
    # The command line wins over the file.
    result = invoke(
        "detect", clip, "-o", tmp_path / "o2", "--config", config, "-q", "--detector", "both"
    )
    settings = json.loads((tmp_path / "o2" / "pan" / "summary.json").read_text())["settings"]
    assert settings["detector"] == "both"
    bad = tmp_path / "bad.toml"
    bad.write_text("colour = 3\n")
    result = invoke("detect", clip, "-o", tmp_path / "o3", "--config", bad)
    assert result.exit_code == 2 and "unknown key 'colour'" in result.output


def test_roi_and_min_area_drop_detections(tmp_path, clip):
    def detections(*extra):
        out = tmp_path / "-".join(extra or ("plain",)).replace(",", "_")
        assert invoke("detect", clip, "-o", out, "--no-video", "-q", *extra).exit_code == 0
        return [
            d
            for line in (out / "pan" / "frames.jsonl").read_text().splitlines()
            for d in json.loads(line)["detections"]
        ]

    everything = detections()
    assert everything
    largest = max(d["area_px"] for d in everything)
    big = detections("--min-area", str(largest))
    assert big and all(d["area_px"] >= largest for d in big)
    assert len(big) < len(everything)
    x, y, w, h = everything[0]["bbox"]
    roi = f"{x},{y},{max(w, 4)},{max(h, 4)}"
    kept = detections("--roi", roi)
    assert 0 < len(kept) < len(everything)
    for d in kept:
        bx, by, bw, bh = d["bbox"]
        assert bx < x + max(w, 4) and x < bx + bw and by < y + max(h, 4) and y < by + bh
    polygon = tmp_path / "roi.txt"
    polygon.write_text(
        f"# the same box\n{x},{y} {x + max(w, 4)},{y} {x + max(w, 4)},{y + max(h, 4)} "
        f"{x},{y + max(h, 4)}\n"
    )
    assert len(detections("--roi-file", str(polygon))) == len(kept)
    assert invoke("detect", clip, "-o", tmp_path, "--roi", "1,2,3").exit_code == 2


def test_extract_clips_are_frame_accurate(tmp_path, clip, clip_frames):
    result = invoke(
        "detect",
        clip,
        "-o",
        tmp_path,
        "--no-video",
        "-q",
        "--extract-clips",
        "--min-event-frames",
        "1",
        "--pad-frames",
        "1",
    )
    assert result.exit_code == 0, result.output
    summary = json.loads((tmp_path / "pan" / "summary.json").read_text())
    assert summary["events"]
    for ev in summary["events"]:
        path = tmp_path / "pan" / "events" / f"event_{ev['event']:04d}.mp4"
        assert decode_count(path) == ev["end_frame"] - ev["start_frame"] + 1
        cap = cv2.VideoCapture(str(path))
        ok, first = cap.read()
        cap.release()
        decoded = cv2.VideoCapture(str(clip))
        for _ in range(ev["start_frame"] + 1):
            _, expected = decoded.read()
        decoded.release()
        psnr = cv2.PSNR(first, expected)
        others = [cv2.PSNR(first, f) for i, f in enumerate(clip_frames) if i != ev["start_frame"]]
        assert psnr > 30 and psnr > max(others)  # the right frame, not a neighbour
    annotated = invoke(
        "detect",
        clip,
        "-o",
        tmp_path / "a",
        "--no-video",
        "-q",
        "--extract-clips",
        "--clips-annotated",
        "--min-event-frames",
        "1",
    )
    assert annotated.exit_code == 0
    events = json.loads((tmp_path / "a" / "pan" / "summary.json").read_text())["events"]
    clips = sorted((tmp_path / "a" / "pan" / "events").glob("event_*.mp4"))
    assert events and len(clips) == len(events)
    for ev, path in zip(events, clips):  # each clip holds exactly its event's frames
        assert decode_count(path) == ev["end_frame"] - ev["start_frame"] + 1
    plain = sorted((tmp_path / "pan" / "events").glob("event_*.mp4"))
    first_plain, first_annotated = cv2.VideoCapture(str(plain[0])), cv2.VideoCapture(str(clips[0]))
    a, b = first_plain.read()[1], first_annotated.read()[1]
    first_plain.release(), first_annotated.release()
    assert cv2.PSNR(a, b) < 40  # the detections are drawn on the annotated clip


def test_batch_with_bad_files(tmp_path, clip_frames):
    batch = tmp_path / "batch"
    (batch / "sub").mkdir(parents=True)
    for name in ("a.mp4", "b.avi", "sub/c.mkv"):
        fourcc = {".mp4": "mp4v", ".avi": "MJPG", ".mkv": "FFV1"}[Path(name).suffix]
        write_video(batch / name, clip_frames[:10], fourcc)
    good = (batch / "a.mp4").read_bytes()
    (batch / "corrupt.mp4").write_bytes(good[: len(good) // 8] + b"\0" * 500)
    (batch / "notes.txt").write_text("not a video")
    out = tmp_path / "out"
    result = invoke("detect", batch, "-o", out, "--recursive", "--jobs", "2")
    assert result.exit_code == 1
    assert "1 of 4 inputs failed" in result.output  # a non-video file is no input...
    assert "corrupt.mp4" in result.output
    assert "skipped 1 files that are not videos (e.g. notes.txt)" in result.output  # ...but said
    assert "Traceback" not in result.output
    for name in ("a", "b", "sub/c"):
        check_outputs(out / name, 10)
    rows = list(csv.reader((out / "events.csv").read_text().splitlines()))
    assert rows[0][0] == "input"
    # The batch's tracks.csv: each finished input's rows, led by that input.
    batch_tracks = list(csv.reader((out / "tracks.csv").read_text().splitlines()))
    assert batch_tracks[0] == ["input", *TRACK_COLUMNS]
    expected = []
    for name, file in (("a", "a.mp4"), ("b", "b.avi"), ("sub/c", "sub/c.mkv")):
        own = list(csv.reader((out / name / "tracks.csv").read_text().splitlines()))[1:]
        expected += [(str(batch / file), *row) for row in own]
    assert expected and sorted(map(tuple, batch_tracks[1:])) == sorted(expected)
    assert (batch / "a.mp4").read_bytes() == good  # inputs are never written to


def test_image_sequence_and_lossless_video_give_identical_results(tmp_path, clip_frames):
    frames_dir = tmp_path / "seq"
    frames_dir.mkdir()
    for i, f in enumerate(clip_frames[:10]):
        cv2.imwrite(str(frames_dir / f"frame_{i + 1}.png"), f)
    lossless = write_video(tmp_path / "seq.mkv", clip_frames[:10], "FFV1")
    for src, out in ((frames_dir, "a"), (lossless, "b")):
        assert invoke("detect", src, "-o", tmp_path / out, "--no-video", "-q").exit_code == 0
    a = [json.loads(x) for x in (tmp_path / "a" / "seq" / "frames.jsonl").read_text().splitlines()]
    b = [json.loads(x) for x in (tmp_path / "b" / "seq" / "frames.jsonl").read_text().splitlines()]
    assert [r["detections"] for r in a] == [r["detections"] for r in b]
    assert [r["observer_motion"] for r in a] == [r["observer_motion"] for r in b]


def test_info_and_version(clip, tmp_path):
    result = invoke("info", clip)
    assert result.exit_code == 0
    assert (
        "320x240" in result.output
        and "30.000 fps" in result.output
        and "16 frames" in result.output
    )
    meta = json.loads(invoke("info", clip, "--json").output)
    assert meta["frame_count"] == 16 and meta["codec"]
    assert invoke("info", tmp_path / "missing.mp4").exit_code == 1
    from motiondetect import __version__

    assert __version__ in invoke("--version").output


def test_unwritable_output_is_one_clear_line(tmp_path, clip):
    blocker = tmp_path / "file"
    blocker.write_text("")
    result = invoke("detect", clip, "-o", blocker / "out")
    assert result.exit_code == 1
    assert result.output.count("\n") == 1 and "not writable" in result.output


def test_missing_input_fails_cleanly(tmp_path):
    result = invoke("detect", tmp_path / "nope.mp4", "-o", tmp_path / "o", "-q")
    assert result.exit_code == 1
    assert "no such file" in result.output and "Traceback" not in result.output


def test_synth_and_evaluate_commands(tmp_path):
    result = invoke(
        "synth",
        tmp_path / "s",
        "--camera",
        "uniform",
        "--mover",
        "smooth",
        "--frames",
        "12",
        "--width",
        "160",
        "--height",
        "120",
        "--supersample",
        "1",
    )
    assert result.exit_code == 0, result.output
    assert decode_count(tmp_path / "s" / "video.mp4") == 12
    assert len(list((tmp_path / "s" / "truth").glob("*.png"))) == 12
    assert (
        invoke(
            "detect",
            tmp_path / "s" / "video.mp4",
            "-o",
            tmp_path / "o",
            "--masks",
            "--no-video",
            "-q",
            "--egomotion",
            tmp_path / "s" / "scene.json",
        ).exit_code
        == 0
    )
    result = invoke(
        "evaluate", tmp_path / "o" / "video", tmp_path / "s", "-o", tmp_path / "table.json"
    )
    assert result.exit_code == 0, result.output
    rows = json.loads((tmp_path / "table.json").read_text())
    assert rows[0]["frames"] == 10 and rows[0]["object_recall"] >= 0.8


def test_installed_entry_point_runs(tmp_path, clip):
    exe = shutil.which("motiondetect") or str(Path(sys.executable).parent / "motiondetect")
    proc = subprocess.run(
        [exe, "detect", str(clip), "-o", str(tmp_path), "-q", "--no-video"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 0, proc.stderr
    check_outputs(tmp_path / "pan", 16, video=False)
    proc = subprocess.run([exe, "detect", "--roi", "x"], capture_output=True, text=True)
    assert proc.returncode == 2


def test_the_summary_counts_unreliable_frames_by_reason(tmp_path, clip_frames):
    """A cut away and back: two frames cannot be judged, and the summary and
    the printed line say so, by reason (frames.jsonl's)."""
    h, w = clip_frames[0].shape[:2]
    other = cv2.resize(cv2.cvtColor(data.astronaut(), cv2.COLOR_RGB2BGR), (w, h))
    folder = tmp_path / "cut"
    folder.mkdir()
    for i, image in enumerate([*clip_frames[:8], other, *clip_frames[8:]]):
        cv2.imwrite(str(folder / f"{i:03d}.png"), image)
    result = invoke("detect", folder, "-o", tmp_path / "out", "--no-video")
    assert result.exit_code == 0, result.output
    summary = check_outputs(tmp_path / "out" / "cut", 17, video=False)
    counts = summary["totals"]["frames_unreliable"]
    lines = (tmp_path / "out" / "cut" / "frames.jsonl").read_text().splitlines()
    records = [json.loads(line) for line in lines]
    reasons = [r["reason"] for r in records if "reason" in r]
    assert len(reasons) == sum(counts.values()) == 2
    assert counts == {reason: reasons.count(reason) for reason in reasons}
    assert "; 2 frames unreliable (" in result.output


def test_a_clean_clip_has_no_unreliable_frames(tmp_path, clip):
    result = invoke("detect", clip, "-o", tmp_path, "--no-video")
    assert result.exit_code == 0, result.output
    summary = check_outputs(tmp_path / "pan", 16, video=False)
    assert summary["totals"]["frames_unreliable"] == {}
    assert summary["totals"]["frames_overlay"] == 0  # nothing on this pan is screen-fixed
    assert "unreliable" not in result.output and "caption" not in result.output


def test_the_summary_counts_the_frames_with_a_caption_left_out(tmp_path, clip_frames):
    """A caption burnt into the pan, found after 5 frames of evidence (set
    in a config file): the summary counts the frames it was left out on,
    and the printed line says so."""
    folder = tmp_path / "captioned"
    folder.mkdir()
    for i, image in enumerate(clip_frames):
        image = image.copy()
        cv2.putText(image, "2026/11/26 14:03:10", (6, image.shape[0] - 8),
                    cv2.FONT_HERSHEY_SIMPLEX, 0.5, (255, 255, 255), 2)  # fmt: skip
        cv2.imwrite(str(folder / f"{i:03d}.png"), image)
    config = tmp_path / "md.toml"
    config.write_text("[track]\noverlay_frames = 5\n")
    result = invoke("detect", folder, "-o", tmp_path / "out", "--no-video", "--config", config)
    assert result.exit_code == 0, result.output
    summary = check_outputs(tmp_path / "out" / "captioned", 16, video=False)
    frames = summary["totals"]["frames_overlay"]
    # 15 judged frames, less the 4 before the 5th frame of evidence (measured: 11)
    assert 8 <= frames <= 11
    assert f"left out on {frames} frames" in result.output


def test_a_letterboxed_input_is_measured_inside_its_bars(tmp_path, clip_frames):
    """Black bars above and below the pan: the summary gives the picture
    measured, the printed line says so, and every box and mask lies in the
    picture (the bars hold nothing that moves)."""
    folder = tmp_path / "letterboxed"
    folder.mkdir()
    bar = 30
    for i, image in enumerate(clip_frames):
        boxed = cv2.copyMakeBorder(image, bar, bar, 0, 0, cv2.BORDER_CONSTANT, value=0)
        cv2.imwrite(str(folder / f"{i:03d}.png"), boxed)
    height, width = clip_frames[0].shape[:2]
    result = invoke("detect", folder, "-o", tmp_path / "out", "--no-video", "--masks")
    assert result.exit_code == 0, result.output
    out = tmp_path / "out" / "letterboxed"
    summary = check_outputs(out, 16, video=False)
    assert summary["totals"]["picture"] == [0, bar, width, height]
    assert summary["totals"]["detections"] > 0
    assert f"side panels left out, picture {width}x{height} at (0, {bar})" in result.output
    for line in (out / "frames.jsonl").read_text().splitlines():
        for det in json.loads(line)["detections"]:
            x, y, w, h = det["bbox"]
            assert bar <= y and y + h <= bar + height
    for path in (out / "masks").glob("*.png"):
        mask = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE)
        assert not mask[:bar].any() and not mask[-bar:].any()


def test_repeated_frames_are_counted_and_carry_the_last_result(tmp_path, clip_frames):
    """The pan with every 4th frame shown twice: the summary counts the 4
    repeats, the printed line says so, and each repeat's record carries the
    frame before's detections, marked."""
    folder = tmp_path / "repeated"
    folder.mkdir()
    shown = [image for i, image in enumerate(clip_frames) for _ in range(2 if i % 4 == 3 else 1)]
    for i, image in enumerate(shown):
        cv2.imwrite(str(folder / f"{i:03d}.png"), image)
    result = invoke("detect", folder, "-o", tmp_path / "out", "--no-video")
    assert result.exit_code == 0, result.output
    out = tmp_path / "out" / "repeated"
    summary = check_outputs(out, 20, video=False)
    assert summary["totals"]["frames_repeated"] == 4
    assert summary["totals"]["frames_judged"] == 16
    assert "4 frames repeated the one before" in result.output
    records = [json.loads(line) for line in (out / "frames.jsonl").read_text().splitlines()]
    repeats = [r for r in records if r.get("repeat")]
    assert [r["frame"] for r in repeats] == [4, 9, 14, 19]
    for r in repeats:
        assert r["held_from"] == r["frame"] - 1
        assert r["detections"] == records[r["frame"] - 1]["detections"]
