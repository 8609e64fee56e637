"""Streaming frames through the detector: measuring ahead on a second thread,
judging one frame in N, and errors while judging.
"""

from __future__ import annotations

import threading
import time
from pathlib import Path

import cv2
import numpy as np
import pytest

from motiondetect.constraint_ray.egomotion import EgoMotion
from motiondetect.detection.detector import MotionDetector
from motiondetect.io.source import SourceFrame


@pytest.mark.parametrize("measure", ["velocity", "normal"])
def test_measuring_ahead_on_a_second_thread_changes_no_result(monkeypatch, measure):
    from .scenes import scene

    frames = scene("pan", ("smooth", "animate"), frames=16)
    serial = MotionDetector("both", measure=measure)
    expected = [serial.process(fr.image, fr.index, fr.index / 30) for fr in frames]
    threads, prepared = set(), []
    ahead = MotionDetector("both", measure=measure)
    measure, prepare, judge = ahead.measure_frame, ahead.prepare, ahead.judge

    def measure_and_note(image):
        threads.add(threading.current_thread().name)
        return measure(image)

    def prepare_and_note(flow, stop=None):
        prepared.append(threading.current_thread().name)
        return prepare(flow, stop)

    def slow_judge(*args):  # the judging half the slower: the measuring thread prepares
        time.sleep(0.05)  # 0.02 s let a loaded machine's judge catch up (14 of 16 prepared)
        return judge(*args)

    monkeypatch.setattr(ahead, "measure_frame", measure_and_note)
    monkeypatch.setattr(ahead, "prepare", prepare_and_note)
    monkeypatch.setattr(ahead, "judge", slow_judge)
    before = cv2.getNumThreads()
    cv2.setNumThreads(2)
    try:
        source = (SourceFrame(fr.index, fr.index / 30, fr.image) for fr in frames)
        streamed = list(ahead.stream(source))
    finally:
        cv2.setNumThreads(before)
    assert threads and all(name.startswith("measure") for name in threads)
    assert len(prepared) >= len(frames) - 1  # all but perhaps the first, ahead
    assert all(name.startswith("measure") for name in prepared)
    assert [f.index for f, _ in streamed] == [fr.index for fr in frames]
    assert sum(len(r.regions) for r in expected) > 0
    for want, (_, got) in zip(expected, streamed, strict=True):
        assert [r.bbox for r in got.regions] == [r.bbox for r in want.regions]
        assert [r.track for r in got.regions] == [r.track for r in want.regions]
        assert got.reason == want.reason
        assert np.array_equal(got.flagged, want.flagged)
        if want.mask is not None:
            assert np.array_equal(got.mask, want.mask)


@pytest.mark.parametrize("threads", [1, 2])
def test_frame_skip_judges_one_frame_in_three_and_holds_its_result(threads):
    from .scenes import scene

    frames = scene("pan", ("smooth",), frames=16)
    alone = MotionDetector("both")  # the judged frames only, one at a time
    expected = {
        fr.index: alone.process(fr.image, fr.index, fr.index / 30)
        for fr in frames
        if fr.index % 3 == 0
    }
    before = cv2.getNumThreads()
    cv2.setNumThreads(threads)
    try:
        source = (SourceFrame(fr.index, fr.index / 30, fr.image) for fr in frames)
        streamed = list(MotionDetector("both").stream(source, frame_skip=2))
    finally:
        cv2.setNumThreads(before)
    assert [f.index for f, _ in streamed] == [fr.index for fr in frames]
    for frame, result in streamed:
        judged = frame.index - frame.index % 3
        want = expected[judged]
        assert (result.index, result.time_s) == (frame.index, frame.index / 30)
        assert result.held_from == (None if judged == frame.index else judged)
        assert [r.bbox for r in result.regions] == [r.bbox for r in want.regions]
        assert np.array_equal(result.mask, want.mask)
    boxed = [i for i, r in expected.items() if r.regions]
    assert len(boxed) >= 3  # frames 0 and 3 are warm-up and the first sighting
    for i in boxed:  # velocities over three frames still find the mover
        x, y, w, h = expected[i].regions[0].bbox
        assert frames[i].mask[y : y + h, x : x + w].any()


def test_frame_skip_below_zero_or_with_known_egomotion_is_refused():
    with pytest.raises(ValueError, match="frame_skip"):
        next(MotionDetector("both").stream([], frame_skip=-1))
    folder = Path(__file__).resolve().parents[1] / "sample_videos" / "uniform_rigid"
    known = MotionDetector("constraint-ray", egomotion=EgoMotion.load(folder / "scene.json"))
    with pytest.raises(ValueError, match="known ego-motion"):
        next(known.stream([], frame_skip=1))


def test_an_error_while_judging_stops_the_reading_thread_before_it_propagates(monkeypatch):
    """The caller closes its source when an error comes out of ``stream``; the
    second thread must not be reading it then (PyAV crashed on a closed
    container)."""
    image = (np.indices((120, 160)).sum(axis=0) % 7 * 30).astype(np.uint8)
    md = MotionDetector("both")
    judge = md.judge

    def fail_on_the_third(flow, index, time_s):
        if index == 2:
            raise RuntimeError("boom")
        return judge(flow, index, time_s)

    monkeypatch.setattr(md, "judge", fail_on_the_third)
    before = cv2.getNumThreads()
    cv2.setNumThreads(2)
    try:
        frames = (SourceFrame(i, i / 30, np.roll(image, i, axis=1)) for i in range(8))
        with pytest.raises(RuntimeError, match="boom") as caught:
            for _ in md.stream(frames, frame_skip=0):
                pass
        # while the error (and its traceback, holding the stream's frame) lives,
        # as when process_input's source closes during its propagation
        readers = [t for t in threading.enumerate() if t.name.startswith("measure")]
        assert caught.traceback
    finally:
        cv2.setNumThreads(before)
    assert readers == []


def test_work_prepared_ahead_falls_to_whichever_thread_has_time():
    """``prepare`` runs on the measuring thread while the user is busy with
    the group before, and is left to the user when it already waits."""
    from motiondetect.detection.streaming import measured_ahead

    def run(measure_s: float, use_s: float) -> list[str]:
        prepared = []

        def measure(picture):
            time.sleep(measure_s)
            return picture

        def prepare(flow, stop):
            assert not stop()  # the user is busy
            prepared.append(threading.current_thread().name)
            return flow

        groups = [([], SourceFrame(i, i / 30, np.zeros((8, 8), np.uint8))) for i in range(6)]
        for _ in measured_ahead(groups, measure, prepare):
            time.sleep(use_s)
        return prepared

    busy = run(0.0, 0.05)  # the user the slower: prepared ahead
    assert len(busy) >= 5 and all(name.startswith("measure") for name in busy)
    assert run(0.05, 0.0) == []  # the user waits: measurements go to it at once
