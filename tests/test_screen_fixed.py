"""Content fixed to the screen while the camera moves (captions, logos) is not a mover."""

from __future__ import annotations

import cv2
import numpy as np

from motiondetect.constraint_ray.camera_fit import fit_camera
from motiondetect.constraint_ray.fit_config import FitConfig
from motiondetect.detection.detector import MotionDetector
from motiondetect.detection.objects import TrackConfig
from motiondetect.detection.screen_fixed import ScreenFixed, without_overlay
from motiondetect.measurement.dense_flow import DenseFlow

from .velocity_scenes import H, W, background, pan_with_mover, paste

CAPTION_TOP = 205  # px: the caption's band, bottom of the 320x240 frame


def _captioned(image: np.ndarray, t: int) -> np.ndarray:
    """A dashcam's caption burnt in: white text outlined in black, its
    clock ticking every 30 frames."""
    out = image.copy()
    text = f"2026/11/26 14:03:{10 + t // 30:02d} 52 km/h"
    for colour, width in (((0, 0, 0), 3), ((255, 255, 255), 1)):
        cv2.putText(out, text, (8, 228), cv2.FONT_HERSHEY_SIMPLEX, 0.45, colour, width, cv2.LINE_AA)
    return out


def _run(clip, track: TrackConfig) -> tuple[list[int], list[bool]]:
    """Per frame: regions touching the caption band, and whether the mover is found."""
    md = MotionDetector("both", track)
    in_band, found = [], []
    for t, (image, mask) in enumerate(clip):
        result = md.process(_captioned(image, t), t, t / 30)
        in_band.append(sum(r.bbox[1] + r.bbox[3] > CAPTION_TOP for r in result.regions))
        found.append((result.input_mask(W, H) > 0)[mask].mean() >= 0.5)
    return in_band, found


def test_a_burnt_in_caption_is_taken_out_and_the_mover_kept():
    """Over a pan, the caption is flagged like any content the plane does
    not move (with the test off: on every frame from the 3rd); once it has
    been fixed to the screen for 30 frames of evidence it is not flagged
    again (measured: none from frame 30 on), while the mover above it is
    found on every frame, as before."""
    clip = pan_with_mover(lambda t: (60 + 3 * t, 60 + 0.5 * t), frames=60, pan=2.0)
    off_band, off_found = _run(clip, TrackConfig(overlay_frames=0))
    on_band, on_found = _run(clip, TrackConfig())
    assert all(n > 0 for n in off_band[3:])  # the problem
    assert sum(on_band[35:]) == 0
    assert np.mean(on_found[3:]) >= 0.95 and np.mean(on_found[3:]) >= np.mean(off_found[3:])


BONNET_TOP = 200  # px: a part of the vehicle fixed in the view, the bottom of the frame


def _bonneted(image: np.ndarray, fixed: np.ndarray, rng) -> np.ndarray:
    """A dashboard's dim texture over the bottom of the frame, the same on
    every frame, and sensor noise of 2 grey levels over the whole frame."""
    out = image.astype(np.float32)
    out[BONNET_TOP:] = fixed
    out += rng.normal(0.0, 2.0, out.shape)
    return np.clip(np.rint(out), 0, 255).astype(np.uint8)


def test_a_dim_part_of_the_vehicle_in_view_is_taken_out_and_the_mover_kept():
    """A dashboard at 40 % of the scene's contrast, fixed in the view of a
    panning camera, under sensor noise: it is flagged like any content the
    plane does not move until 30 frames of evidence are in, then not again,
    while the mover above it is found on every frame. (This clean synthetic
    pan leaves little difference noise, so the plane difference is evidence
    too; `test_realdata.py` shows a real pan, where only the velocity is.)"""
    rng = np.random.default_rng(3)
    source = background(0.0)[BONNET_TOP:, ::-1].astype(np.float32)
    fixed = (0.4 * (source - source.mean()) + 60).astype(np.uint8)
    clip = pan_with_mover(lambda t: (40 + 3 * t, 60 + 0.5 * t), frames=60, pan=2.0)
    md = MotionDetector("both")
    low, found = [], []
    for t, (image, mask) in enumerate(clip):
        result = md.process(_bonneted(image, fixed, rng), t, t / 30)
        low.append(sum(r.bbox[1] + r.bbox[3] > BONNET_TOP for r in result.regions))
        found.append((result.input_mask(W, H) > 0)[mask].mean() >= 0.5)
    assert all(n > 0 for n in low[3:20])  # flagged while the evidence builds up
    assert sum(low[40:]) == 0
    assert np.mean(found[3:]) >= 0.95


def test_a_mover_kept_on_the_same_pixels_is_taken_for_an_overlay():
    """The blind spot: a mover the camera follows to the pixel, unchanged
    in look, is screen-fixed by any measure. It is flagged until it has
    been so for ``overlay_frames`` frames of evidence, then no longer."""
    frames = [paste(background(2.5 * t), 200.0, 150.0) for t in range(40)]
    md = MotionDetector("both", TrackConfig(overlay_frames=10))
    flagged = []
    for t, (image, mask) in enumerate(frames):
        result = md.process(image, t, t / 30)
        flagged.append((result.input_mask(W, H) > 0)[mask].mean() >= 0.5)
    assert all(flagged[3:10])  # found while the evidence builds up
    assert not any(flagged[20:])  # then taken for an overlay


def test_without_a_moving_view_nothing_is_fixed():
    """A still camera predicts no change anywhere: no evidence, no overlay,
    even for content that never changes (the photograph) or a mover."""
    flow, fixed = DenseFlow(), ScreenFixed(frames=5)
    for t in range(20):
        image, _ = paste(background(0.0), 60.0 + 3 * t, 100.0)
        field = flow.process(_captioned(image, t))
        if field is not None:
            assert fixed.update(field, fit_camera(field, FitConfig()), 0.5) is None, t


def test_the_overlay_band_and_the_fringes_beside_it_are_cleared():
    """The band of one flow patch (8 px here) goes, and so does a group
    whose part outside it is no larger than its flagged band within a patch
    of that part (a fringe up to a patch deep); movers beside the band, far
    from it, crossing it, or touching a large overlay, keep what lies
    outside it."""
    overlay = np.zeros((100, 100), bool)
    overlay[90:92, 10:60] = True  # a caption's strokes
    flagged = np.zeros((100, 100), bool)
    flagged[76:100, 5:65] = True  # the caption's flags, a fringe above the band
    flagged[10:95, 80:95] = True  # a mover crossing the band's level, beside it
    flagged[20:40, 20:40] = True  # a mover far from it
    out = without_overlay(flagged, overlay, radius_px=8)
    assert not out[70:100, 5:65].any()  # its fringe (y 76-81) goes with it
    assert out[10:95, 80:95].all() and out[20:40, 20:40].all()
    bonnet = np.zeros((100, 100), bool)
    bonnet[70:, :] = True  # a large overlay, its top rows (mixed flow) left out of it
    touching = np.zeros((100, 100), bool)
    touching[62:, :] = True  # its flags, the mixed rows 62-69 in the band ...
    touching[30:62, 40:60] = True  # ... and a mover whose flags touch them
    kept = without_overlay(touching, bonnet, radius_px=8)
    assert kept[30:62, 40:60].all() and not kept[62:].any()
    crossing = np.zeros((100, 100), bool)
    crossing[40:100, 30:40] = True  # a mover crossing the band itself
    kept = without_overlay(crossing, overlay, radius_px=8)
    assert kept[40:82, 30:40].all() and not kept[82:, 30:40].any()
