"""Footage above 30 frames/s is judged about every 1/30 s (``--frame-skip auto``)."""

from __future__ import annotations

import json

import pytest

import motiondetect
from motiondetect.app.settings import SettingsError, make_settings
from motiondetect.detection.events import EventRules
from motiondetect.detection.streaming import auto_frame_skip

from .cli_outputs import check_outputs, invoke, write_video
from .scenes import scene


@pytest.mark.parametrize(
    ("fps", "skip"),
    [(None, 0), (0.0, 0), (float("nan"), 0), (12.0, 0), (23.976, 0), (30.0, 0), (44.0, 0),
     (46.0, 1), (50.0, 1), (59.94, 1), (60.0, 1), (90.0, 2), (120.0, 3), (240.0, 7),
     (1000.0, 7), (10000.0, 7), (float("inf"), 0)],
)  # fmt: skip
def test_auto_frame_skip_judges_one_frame_about_every_thirtieth_of_a_second(fps, skip):
    assert auto_frame_skip(fps) == skip


def _hits(frames, results) -> tuple[int, int]:
    """(frames on which at least 10 % of the mover is flagged, frames scored)."""
    hits = scored = 0
    for fr, res in zip(frames, results):
        mover = fr.mask == 255
        if fr.index < 4 or mover.sum() < 50:
            continue
        h, w = fr.mask.shape
        scored += 1
        hits += (res.input_mask(w, h) > 0)[mover].mean() >= 0.1
    return hits, scored


def test_a_slow_mover_filmed_at_60_fps_is_found_when_judged_at_30():
    """The samples' uniform camera and smooth mover at 60 frames/s: half the
    motion a frame. Judged every 2nd frame (``auto`` at 60 fps), it moves as
    far as at 30 frames/s and is found. (Judged every frame it was found on
    at most half the frames until tracked movers stopped voting for the
    plane, issue 13's fifty-ninth session; now on 33 of 36 as well.)"""
    frames = scene("uniform", ("smooth",), frames=40, speed=0.35, fps=60.0, seed=107)
    images = [fr.image for fr in frames]
    auto = list(motiondetect.detect(images, fps=60.0))
    every = list(motiondetect.detect(images, fps=60.0, frame_skip=0))
    assert [r.held_from for r in auto[:4]] == [None, 0, None, 2]
    assert all(r.held_from is None for r in every)
    found, scored = _hits(frames, auto)
    assert scored >= 30 and found >= 0.75 * scored


def test_the_cli_judges_a_60_fps_video_every_2nd_frame_unless_told(tmp_path):
    images = [fr.image for fr in scene("pan", ("smooth",), frames=16)]
    video = write_video(tmp_path / "fast.mp4", images, fps=60.0)
    result = invoke("detect", video, "-o", tmp_path / "auto", "--no-video")
    assert result.exit_code == 0, result.output
    assert (
        "fast: 16 frames, " in result.output
        and "; 8 judged, 8 held (--frame-skip)" in result.output
    )
    summary = check_outputs(tmp_path / "auto" / "fast", 16, video=False)
    assert summary["totals"]["frames_judged"] == 8
    assert summary["settings"]["frame_skip"] == "auto"
    lines = (tmp_path / "auto/fast/frames.jsonl").read_text().splitlines()
    records = [json.loads(line) for line in lines]
    assert [r.get("held_from") for r in records[:4]] == [None, 0, None, 2]
    assert invoke("info", video).output.rstrip().endswith("; detect judges one frame in 2")
    result = invoke("detect", video, "-o", tmp_path / "all", "--frame-skip", "0", "-q")
    assert result.exit_code == 0, result.output
    summary = check_outputs(tmp_path / "all" / "fast", 16)
    assert summary["totals"]["frames_judged"] == 16


def test_a_frame_skip_that_is_not_a_number_or_auto_is_one_line_error(tmp_path):
    video = write_video(tmp_path / "v.mp4", [fr.image for fr in scene("pan", frames=4)])
    result = invoke("detect", video, "-o", tmp_path / "out", "--frame-skip", "fast")
    assert result.exit_code == 2
    assert "--frame-skip must be auto or a whole number, got 'fast'" in result.output
    assert "Traceback" not in result.output
    result = invoke("detect", video, "-o", tmp_path / "out", "--frame-skip", "-1")
    assert result.exit_code == 2
    assert "--frame-skip must be at least 0, but got -1" in result.output


def test_known_egomotion_judges_every_frame_at_any_rate(tmp_path):
    ego = tmp_path / "ego.json"
    ego.write_text("{}")
    settings = make_settings({"egomotion": str(ego)})
    assert settings.frame_skip == "auto" and settings.skipped_frames(60.0) == 0
    assert make_settings({}).skipped_frames(60.0) == 1
    assert make_settings({"frame_skip": 2}).skipped_frames(24.0) == 2
    with pytest.raises(SettingsError, match="cannot be combined"):
        make_settings({"frame_skip": 1, "egomotion": str(ego)})


def test_event_rules_in_frames_count_judged_frames_under_auto():
    """At 60 frames/s ``auto`` judges every 2nd frame, so rules given in frames
    span the time they span at 30; times, and a numeric ``frame_skip``, are
    as given."""
    assert make_settings({}).event_rules(60.0) == EventRules(6, 10, 10)
    assert make_settings({}).event_rules(30.0) == EventRules(3, 5, 5)
    assert make_settings({"min_event_frames": 4}).event_rules(120.0).min_frames == 16
    assert make_settings({"frame_skip": 1}).event_rules(60.0) == EventRules(3, 5, 5)
    timed = make_settings({"min_event": "0.5s", "pad": "10f"}).event_rules(60.0)
    assert (timed.min_frames, timed.merge_gap, timed.pad) == (30, 10, 10)
