"""Events from per-frame activity (issue 9)."""

from __future__ import annotations

import numpy as np

from motiondetect.detection.events import EventRules, EventTimeline, find_runs, timecode


def test_runs_merge_gaps_drop_short_and_pad():
    active = np.zeros(40, bool)
    active[5:8] = True  # 3 frames
    active[10:12] = True  # gap of 2 -> merged with the first
    active[20] = True  # 1 frame -> too short
    active[30:36] = True
    rules = EventRules(min_frames=3, merge_gap=2, pad=1)
    assert find_runs(active, rules) == [(4, 12), (29, 36)]
    assert find_runs(active, EventRules(min_frames=1, merge_gap=0, pad=0)) == [
        (5, 7),
        (10, 11),
        (20, 20),
        (30, 35),
    ]
    assert find_runs(active, EventRules(min_frames=3, merge_gap=2, pad=10)) == [(0, 39)]


def test_timecodes_and_event_fields():
    assert timecode(0) == "00:00:00.000"
    assert timecode(72.4) == "00:01:12.400"
    assert timecode(3600 + 61.002) == "01:01:01.002"
    tl = EventTimeline()
    for i in range(10):
        dets = [{"bbox": [i, 2, 5, 5], "detectors": ["animate"]}] if 3 <= i <= 6 else []
        tl.add(i / 10, 0.5 if dets else 0.0, 0.1 if dets else 0.0, 1, dets)
    (ev,) = tl.events(EventRules(min_frames=2, merge_gap=0, pad=0), fps=10.0)
    assert (ev["start_frame"], ev["end_frame"]) == (3, 6)
    assert ev["start_timecode"] == "00:00:00.300" and ev["end_s"] == 0.7
    assert ev["bbox"] == [3, 2, 8, 5] and ev["detectors"] == ["animate"]
