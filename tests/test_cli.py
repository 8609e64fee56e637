"""The detect command's outputs and options (issue 5); events, ROI and clips (issue 9)."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import cv2
import numpy as np
import pytest

from motiondetect.detection.base import DETECTOR_SETS
from motiondetect.io.video import count_decodable_frames

from .cli_outputs import check_outputs, invoke
from .scenes import scene


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
    assert 0 < len(kept) <= len(everything)
    for d in kept:
        bx, by, bw, bh = d["bbox"]
        assert bx < x + max(w, 4) and x < bx + bw and by < y + max(h, 4) and y < by + bh
    # The mover stays left of x = 160 (its boxes span x 23-137): a region
    # of interest over x 200-320 keeps nothing.
    assert all(d["bbox"][0] + d["bbox"][2] < 160 for d in everything)
    assert detections("--roi", "200,0,120,240") == []
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
        assert count_decodable_frames(path) == ev["end_frame"] - ev["start_frame"] + 1
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
        assert count_decodable_frames(path) == ev["end_frame"] - ev["start_frame"] + 1
    plain = sorted((tmp_path / "pan" / "events").glob("event_*.mp4"))
    first_plain, first_annotated = cv2.VideoCapture(str(plain[0])), cv2.VideoCapture(str(clips[0]))
    a, b = first_plain.read()[1], first_annotated.read()[1]
    first_plain.release(), first_annotated.release()
    assert cv2.PSNR(a, b) < 40  # the detections are drawn on the annotated clip
