"""The command line over batches and frame folders, its other commands
(info, synth, evaluate), clear errors, and what the summary counts.
"""

from __future__ import annotations

import csv
import json
import shutil
import subprocess
import sys
from pathlib import Path

import cv2
import pytest
from skimage import data

from motiondetect.io.report import TRACK_COLUMNS
from motiondetect.io.video import count_decodable_frames

from .cli_outputs import check_outputs, invoke, write_video


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
    # Velocities are per second of each input's own times: the folder's are
    # 1/30 s apart, the Matroska file's rounded to its 1 ms time base (33,
    # 34, 33 ms ...), which moves them by up to 1/33 of their value.
    speeds = ("velocity_px_s", "own_velocity_px_s", "view_velocity_px_s")

    def apart(records: list[dict]) -> tuple[list[dict], list[list]]:
        """The records without their velocities, and the velocities."""
        rest = [{k: v for k, v in r.items() if k not in speeds} for r in records]
        return rest, [r[k] for r in records for k in speeds if k in r]

    for x, y in zip(a, b):
        for key in ("detections", "observer_motion"):
            (rest_x, speeds_x), (rest_y, speeds_y) = (
                apart(r[key] if key == "detections" else [r[key]]) for r in (x, y)
            )
            assert rest_x == rest_y
            assert len(speeds_x) == len(speeds_y)
            for u, v in zip(speeds_x, speeds_y):
                assert u == pytest.approx(v, rel=1 / 30, abs=0.2)


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
    assert result.output.count("\n") == 1
    assert f"lies inside {blocker}, which is a file, not a folder" in result.output
    result = invoke("detect", clip, "-o", blocker)
    assert result.exit_code == 1 and result.output.count("\n") == 1
    assert f"output folder {blocker} is a file, not a folder" in result.output


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
    assert count_decodable_frames(tmp_path / "s" / "video.mp4") == 12
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


def test_the_batch_tracks_csv_takes_inputs_an_earlier_version_finished(tmp_path, clip_frames):
    """An input finished by a version that wrote fewer tracks.csv columns
    (before the own velocities) is skipped on the next run, and its rows in
    the batch's tracks.csv have today's columns, the new ones empty."""
    batch = tmp_path / "batch"
    batch.mkdir()
    for name in ("a.mp4", "b.mp4"):
        write_video(batch / name, clip_frames[:10])
    out = tmp_path / "out"
    assert invoke("detect", batch, "-o", out, "--no-video", "-q").exit_code == 0
    old = out / "a" / "tracks.csv"
    rows = list(csv.reader(old.read_text().splitlines()))
    assert len(rows) > 1  # the clip's mover is tracked
    old.write_text("\n".join(",".join(row[:-2]) for row in rows) + "\n")  # the earlier columns
    result = invoke("detect", batch, "-o", out, "--no-video", "-q")
    assert result.exit_code == 0
    batch_rows = list(csv.DictReader((out / "tracks.csv").read_text().splitlines()))
    assert {row["input"] for row in batch_rows} == {str(batch / "a.mp4"), str(batch / "b.mp4")}
    for row in batch_rows:
        assert None not in row.values() and None not in row  # every row as long as the header
        assert (row["own_vx_px_s"] == "") == (row["input"] == str(batch / "a.mp4"))
