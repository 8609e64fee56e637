"""Objects kept as tracks (issue 13, item 5): stable ids, persistence, cuts,
tracks predicted across missed frames.
"""

from __future__ import annotations

import cv2
import numpy as np
from skimage import data

from motiondetect.constraint_ray.fit_config import FitConfig
from motiondetect.constraint_ray.velocity_filter import VelocityRayConfig
from motiondetect.detection.detector import MotionDetector
from motiondetect.detection.objects import MovingObject, TrackConfig
from motiondetect.detection.tracking import Tracker

from .velocity_scenes import H, W, background, pan_with_mover


def _obj(x0: float, v: float = 5.0, width: float = 20.0) -> MovingObject:
    mask = np.zeros((10, 10), bool)
    return MovingObject(mask, (x0, 10.0, x0 + width, 40.0), (v, 0.0))


def test_tracker_keeps_ids_and_needs_persistence():
    tracker = Tracker(TrackConfig(persistence=2))
    assert tracker.update([_obj(0.0)]) == []  # seen once: not yet reported
    second = tracker.update([_obj(5.0), _obj(200.0)])
    assert [o.track for o in second] == [1]  # the new object at 200 waits a frame
    third = tracker.update([_obj(10.0), _obj(205.0)])
    assert sorted(o.track for o in third) == [1, 2]
    tracker.coast()  # an unreliable frame: tracks survive it
    fourth = tracker.update([_obj(20.0)])
    assert [o.track for o in fourth] == [1]


def test_a_cut_ends_every_track():
    """Across a cut nothing is predicted: the mover, seen again after a cut
    away and back, starts a new track and waits ``persistence`` frames, while
    a frame that merely cannot be judged is coasted through (above)."""
    clip = pan_with_mover(lambda t: (60 + 3 * t, 100 + 1.0 * t), frames=12)
    cut = cv2.resize(cv2.cvtColor(data.chelsea(), cv2.COLOR_RGB2BGR), (W, H))
    md = MotionDetector("constraint-ray")
    results = [md.process(image, t, t / 30) for t, (image, _) in enumerate(clip[:6])]
    before = {r.track for r in results[-1].regions}
    assert len(before) == 1  # the mover, confirmed
    md.process(cut, 6, 0.2)
    back = md.process(clip[6][0], 7, 0.23)
    assert back.reason == "cut" and not back.regions  # the cut back
    first = md.process(clip[7][0], 8, 0.27)
    assert first.reliable and first.regions == []  # a new track, not yet confirmed
    second = md.process(clip[8][0], 9, 0.3)
    after = {r.track for r in second.regions}
    assert len(after) == 1 and after.isdisjoint(before)


def _box(x0: float, x1: float) -> MovingObject:
    """A still object spanning ``x0`` to ``x1``."""
    return _obj(x0, v=0.0, width=x1 - x0)


def test_an_established_track_keeps_its_id_when_a_young_one_joins_it():
    """When a young track (a part found beside a mover: a head, a swinging
    limb) joins the mover's, the joined object keeps the id the mover has
    had for frames, though it overlaps the part's box more (tracks choose
    in order of age, as where the objects are merged)."""
    tracker = Tracker(TrackConfig(persistence=2, min_iou=0.2))
    for _ in range(4):
        tracker.update([_box(0.0, 40.0)])
    for _ in range(2):
        beside = tracker.update([_box(0.0, 40.0), _box(38.0, 60.0)])
    assert [o.track for o in beside] == [1, 2]
    # IoU 0.24 with track 1's box, 0.59 with track 2's
    assert [o.track for o in tracker.update([_box(25.0, 62.0)])] == [1]


def test_a_part_split_from_a_confirmed_track_is_reported_at_once():
    """A part that leaves a confirmed mover has been seen within it: its new
    track is reported on the frame it starts, while a new object elsewhere
    still waits ``persistence`` frames."""
    tracker = Tracker(TrackConfig(persistence=3, min_iou=0.2))
    for _ in range(3):
        tracker.update([_box(0.0, 40.0)])
    found = tracker.update([_box(0.0, 30.0), _box(25.0, 40.0), _box(200.0, 240.0)])
    assert [o.track for o in found] == [1, 2]  # the part at 200 px is new


def test_a_missed_track_is_predicted_as_far_as_it_moved_meanwhile():
    """A mover missed for a few frames is looked for where its velocity has
    carried it since it was last seen, not one frame's motion ahead."""
    tracker = Tracker(TrackConfig(persistence=2, max_missed=5))
    tracker.update([_obj(0.0, v=10.0)])
    assert [o.track for o in tracker.update([_obj(10.0, v=10.0)])] == [1]
    for _ in range(3):
        assert tracker.update([]) == []  # missed: still moving at 10 px a frame
    assert [o.track for o in tracker.update([_obj(50.0, v=10.0)])] == [1]


def test_most_of_the_frame_off_the_fit_can_mark_a_frame_unreliable():
    """With ``max_flagged_share`` set, a frame flagged nearly whole is not judged;
    by default (off) the same frames are judged."""

    other = cv2.resize(cv2.cvtColor(data.coffee(), cv2.COLOR_RGB2BGR), (W, H))
    frames = [background(2.0 * t) for t in range(4)]
    for t in range(5):  # a second picture sliding the other way across the whole view
        frames.append(cv2.addWeighted(frames[3], 0.4, np.roll(other, 8 * t, axis=1), 0.6, 0))
    reason = "most of the frame off the fitted motion"
    # A picture covering the frame also inflates the frame's residual spread, which
    # then tolerates it (VelocityRayConfig.spread_sigmas); the share test is about
    # what is flagged, so the spread term is off on both sides here.
    # The fit takes the blend's stronger picture as the plane; what is flagged
    # off it covers 0.23-0.40 of the frame.
    ray = VelocityRayConfig(spread_sigmas=0.0)
    strict = MotionDetector("both", FitConfig(max_flagged_share=0.2), ray)
    default = MotionDetector("both", ray)
    strict_reasons = [strict.process(f, i, i / 30).reason for i, f in enumerate(frames)]
    default_reasons = [default.process(f, i, i / 30).reason for i, f in enumerate(frames)]
    assert strict_reasons[:4] == [""] * 4 and reason in strict_reasons[5:]
    assert reason not in default_reasons


def _seen(x0: float, v: float = 5.0) -> MovingObject:
    mask = np.zeros((60, 120), bool)
    mask[20:30, int(x0) : int(x0) + 10] = True
    return MovingObject(mask, (int(x0), 20, int(x0) + 10, 30), (v, 0.0))


def test_an_established_track_missed_on_a_frame_is_held_where_it_moved():
    """A track seen on ``hold_age`` frames and then missed is reported for
    ``hold_frames`` frames more, its last mask moved on by its velocity and
    marked held; a younger track is not, and neither is one missed longer."""
    tracker = Tracker(TrackConfig(persistence=2, hold_frames=1, hold_age=4))
    for t in range(4):
        seen = tracker.update([_seen(5.0 * t)])
    last = seen[0]
    assert not last.held and last.age == 4
    held = tracker.update([])
    assert [o.track for o in held] == [last.track] and held[0].held
    np.testing.assert_array_equal(held[0].mask, np.roll(last.mask, 5, axis=1))
    assert held[0].box == (20, 20, 30, 30)
    assert tracker.update([]) == []  # held for one frame only
    young = Tracker(TrackConfig(persistence=2, hold_frames=1, hold_age=4))
    for t in range(3):
        young.update([_seen(5.0 * t)])
    assert young.update([]) == []  # seen on 3 frames: not established
    unconfirmed = Tracker(TrackConfig(persistence=3, hold_frames=1, hold_age=1))
    for t in range(2):
        assert unconfirmed.update([_seen(5.0 * t)]) == []
    assert unconfirmed.update([]) == []  # never reported, so never held


def _plane(step: float) -> np.ndarray:
    """The fitted plane of a camera that shifts the scene ``step`` px to the
    right: a homography from this frame's pixels to the last frame's."""
    return np.array([[1.0, 0.0, -step], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])


def test_a_held_track_goes_where_the_camera_takes_it_when_the_camera_turns_back():
    """The scene moves 4 px/frame right, the object 2 px/frame faster (its
    image velocity 6); then the camera turns back and the detectors miss
    the object. Its held mask goes where this frame's plane (-4) and its own
    2 px/frame take it, 2 px left; by its last image velocity it would be
    put 6 px right, 8 px from the object. Without the plane, as before."""
    for plane, shift in ((_plane(-4.0), -2), (None, 6)):
        tracker = Tracker(TrackConfig(persistence=2, hold_frames=1, hold_age=4))
        for t in range(4):
            seen = tracker.update([_seen(40.0 + 6.0 * t, v=6.0)], _plane(4.0))
        held = tracker.update([], plane)
        assert [o.track for o in held] == [seen[0].track] and held[0].held
        np.testing.assert_array_equal(held[0].mask, np.roll(seen[0].mask, shift, axis=1))


def test_the_tracks_own_pixels_are_predicted_moved_on_and_grown():
    """What the fit leaves out where a track's box would leave too little:
    a confirmed track's last mask moved on by its velocity (as far as it
    moved while missed) and dilated; nothing before it is confirmed."""
    tracker = Tracker(TrackConfig(persistence=2, max_missed=3))
    tracker.update([_seen(0.0)])
    assert tracker.predicted_pixels((60, 120), 2) is None  # not yet confirmed
    last = tracker.update([_seen(5.0)])[0]
    grown = cv2.dilate(np.roll(last.mask, 5, axis=1).view(np.uint8), np.ones((5, 5), np.uint8))
    np.testing.assert_array_equal(tracker.predicted_pixels((60, 120), 2), grown > 0)
    tracker.update([])  # missed: predicted two frames' motion on
    moved = tracker.predicted_pixels((60, 120), 0)
    np.testing.assert_array_equal(moved, np.roll(last.mask, 10, axis=1))
    assert tracker.predicted_pixels((30, 60), 0) is None  # masks of another size


def test_a_mover_that_stops_moving_is_held_for_one_frame():
    """The patch moves across the pan, then rides with the background (rigid
    from frame 14): its track, once missed, is reported held on that one
    frame, where its motion puts it, naming the detectors that found it."""

    def path(t):
        return (60 + 3 * min(t, 14) - 2 * max(t - 14, 0), 100.0)

    clip = pan_with_mover(path, frames=32)
    md = MotionDetector("both")
    results = [md.process(image, t, t / 30) for t, (image, _) in enumerate(clip)]
    found = {t: {r.track: r for r in res.regions} for t, res in enumerate(results)}
    held = [(t, r) for t, regions in found.items() for r in regions.values() if r.held]
    assert held and all(t > 14 for t, _ in held)  # the moving patch is never missed
    for t, region in held:
        before = found[t - 1].get(region.track)
        assert before is not None and not before.held  # seen on the frame before
        assert region.track not in found[t + 1]  # then no more
        assert region.detectors == before.detectors
        record = region.to_json()
        assert record["held"] is True and record["track"] == region.track
        x, y, w, h = region.bbox
        px, py = path(t)
        assert abs(x + w / 2 - (px + 24)) < 16 and abs(y + h / 2 - (py + 24)) < 16
