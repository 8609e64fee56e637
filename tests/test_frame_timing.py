"""Frame timing: repeated frames carry the last result; dropped frames are gaps in time."""

from __future__ import annotations

import numpy as np

from motiondetect.detection.detector import MotionDetector
from motiondetect.measurement.dense_flow import DenseFlowConfig
from motiondetect.measurement.repeats import RepeatedFrames

from .velocity_scenes import H, W, background, pan_with_mover, paste


def test_a_repeat_is_a_drop_to_codec_noise_from_the_usual_difference():
    rng = np.random.default_rng(0)
    frames = [rng.integers(0, 256, (H, W), np.uint8) for _ in range(4)]
    repeats = RepeatedFrames(1.0)
    assert not repeats.repeats(frames[0], frames[0])  # no usual difference known yet
    assert not repeats.repeats(frames[1], frames[0])
    assert not repeats.repeats(frames[2], frames[1])
    noisy = np.clip(frames[2].astype(int) + rng.integers(-1, 2, (H, W)), 0, 255).astype(np.uint8)
    assert repeats.repeats(noisy, frames[2])  # re-encoded: within a grey level
    assert not repeats.repeats(frames[3], frames[2])


def test_a_clean_still_view_is_never_taken_for_repeats():
    """Frames that all differ by less than the level (a still camera, a
    clean picture) differ as usual: none is a repeat."""
    rng = np.random.default_rng(1)
    base = rng.integers(0, 256, (H, W)).astype(int)
    frames = [
        np.clip(base + rng.integers(-1, 2, (H, W)), 0, 255).astype(np.uint8) for _ in range(30)
    ]
    repeats = RepeatedFrames(1.0)
    assert not any(repeats.repeats(b, a) for a, b in zip(frames, frames[1:], strict=False))
    assert not any(RepeatedFrames(0.0).repeats(f, f) for f in frames)  # 0: off


def test_a_repeated_frame_carries_the_last_result_and_changes_nothing_after():
    """A pan with a mover, every 4th frame shown twice (24 fps as 30): each
    repeat carries the last frame's result, marked, and every other frame's
    result is that of the clip without repeats, pixel for pixel. Measured as
    frames of their own (``repeat_level`` 0), the repeats show no motion
    and the detectors lose the mover on them (its track at most held)."""
    clip = [image for image, _ in pan_with_mover(lambda t: (60 + 3 * t, 100 + t), frames=16)]
    shown = [i for i in range(16) for _ in range(2 if i % 4 == 3 else 1)]
    once = MotionDetector("both")
    plain = [once.process(clip[i], i, 0.0) for i in range(16)]
    held = MotionDetector("both")
    measured = MotionDetector("both", DenseFlowConfig(repeat_level=0))
    lost = 0
    for n, i in enumerate(shown):
        result = held.process(clip[i], n, n / 30)
        other = measured.process(clip[i], n, n / 30)
        again = n > 0 and shown[n - 1] == i
        assert result.repeat == again
        if again:
            assert result.held_from == n - 1
            lost += all(r.held for r in other.regions)  # none found, at most held
        assert np.array_equal(result.input_mask(W, H), plain[i].input_mask(W, H))
        assert [r.bbox for r in result.regions] == [r.bbox for r in plain[i].regions]
    assert lost == 4  # every repeat, measured as a frame


def test_dropped_frames_are_gaps_in_time_for_the_animate_test():
    """A pan with a mover at a steady 3 px a frame, one frame in three or
    four dropped: given the frames' times, the mover covers twice the
    ground over a gap and the animate detector sees its motion continue
    (never flagged); without times every gap looks like a jump in speed,
    and it is flagged from the first gap on."""
    kept = [0, 1, 2, 3, 5, 6, 7, 9, 10, 11, 13, 14, 16, 17, 18, 20, 21, 23, 24, 25]

    def flagged(timed: bool) -> list[bool]:
        md = MotionDetector("animate")
        out = []
        for n, i in enumerate(kept):
            image, mask = paste(background(2.0 * i), 40 + 3.0 * i, 100 + 1.0 * i)
            result = md.process(image, n, i / 30 if timed else 0.0)
            out.append((result.input_mask(W, H) > 0)[mask].mean() >= 0.5)
        return out

    assert not any(flagged(timed=True))
    assert all(flagged(timed=False)[5:])


def test_no_time_passes_in_a_repeated_frame():
    """24 fps shown at 30 by repeating every 4th frame, each frame timed as
    shown: the frame after a repeat moved one step of the film from the
    frame repeated, so the animate detector sees a steady mover continue."""
    shown = [i for i in range(20) for _ in range(2 if i % 4 == 3 else 1)]
    md = MotionDetector("animate")
    flagged = []
    for n, i in enumerate(shown):
        image, mask = paste(background(2.0 * i), 40 + 3.0 * i, 100 + 1.0 * i)
        result = md.process(image, n, n / 30)
        flagged.append((result.input_mask(W, H) > 0)[mask].mean() >= 0.5)
    assert not any(flagged)
