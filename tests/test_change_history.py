"""Object support over a longer baseline (slow movers' plain bodies) and the
remembered background (the ghost a mover leaves) (issue 13)."""

from __future__ import annotations

from types import SimpleNamespace

import cv2
import numpy as np
import pytest

from motiondetect.detection.change_history import BackgroundMemory, ChangeHistory, slow_parts
from motiondetect.detection.objects import TrackConfig
from motiondetect.detection.shaping import trimmed
from motiondetect.measurement.image_change import (
    chained_difference,
    difference_noise,
    matched_exposure,
)


def texture(shape, sigma, contrast, seed):
    """Smooth random texture: blurred noise stretched to ``contrast`` grey levels."""
    noise = np.random.default_rng(seed).random(shape).astype(np.float32)
    smooth = cv2.GaussianBlur(noise, (0, 0), sigma)
    smooth = (smooth - smooth.min()) / (smooth.max() - smooth.min())
    return smooth * contrast


def shifted(image, dx, dy):
    """``image`` moved by (dx, dy) px, bilinear."""
    m = np.float32([[1, 0, dx], [0, 1, dy]])
    return cv2.warpAffine(image, m, image.shape[::-1], borderMode=cv2.BORDER_REFLECT)


def plane_from_motion(dx, dy):
    """The homography from current pixels to where they were: ``p - (dx, dy)``."""
    return np.array([[1, 0, -dx], [0, 1, -dy], [0, 0, 1]], float)


def test_the_chained_planes_register_a_moving_view_over_several_frames():
    world = texture((140, 180), 2.0, 200, seed=1) + 20
    step = (1.3, -0.7)  # the view's motion, px/frame
    frames = [
        np.clip(shifted(world, step[0] * i, step[1] * i), 0, 255).astype(np.uint8) for i in range(4)
    ]
    planes = [plane_from_motion(*step)] * 3
    inner = (slice(10, -10), slice(10, -10))
    registered = chained_difference(frames[0], planes, frames[3])[inner]
    unregistered = chained_difference(frames[0], [np.eye(3)] * 3, frames[3])[inner]
    assert registered.mean() < 2.0  # interpolation only
    assert unregistered.mean() > 5 * registered.mean()


def test_an_exposure_drift_is_matched_before_comparing_over_several_frames():
    """A phone's exposure rising 4 % a frame: over three frames every pixel
    of the registered view differs by about 12 % of its grey level; matched,
    only interpolation is left, as without the drift."""
    world = texture((140, 180), 2.0, 160, seed=1) + 40
    step = (1.3, -0.7)
    frames = [
        np.clip(shifted(world, step[0] * i, step[1] * i) * 1.04**i, 0, 255).astype(np.uint8)
        for i in range(4)
    ]
    inner = (slice(10, -10), slice(10, -10))
    matched = chained_difference(frames[0], [plane_from_motion(*step)] * 3, frames[3])[inner]
    assert matched.mean() < 2.0  # interpolation only
    unmatched = cv2.absdiff(shifted(frames[0], *(3 * np.array(step))), frames[3])[inner]
    assert unmatched.mean() > 5 * matched.mean()
    older = frames[0]
    scaled = matched_exposure(older, np.clip(older * 1.1, 0, 255).astype(np.uint8))
    unclipped = older < 200
    assert abs(scaled[unclipped].mean() / older[unclipped].mean() - 1.1) < 0.01
    assert matched_exposure(older, older) is older  # the same exposure: untouched


def slow_mover_clip(speed, frames=4, seed=0):
    """A still camera; a textured square moving ``speed`` px/frame over a
    static texture, with 1.5 grey levels of sensor noise. Its texture changes
    the image by about 7 grey levels a frame at 0.5 px/frame, under three
    robust sigmas of the frame's difference (12), and by about 19 over three."""
    rng = np.random.default_rng(seed)
    background = texture((120, 160), 1.0, 160, seed=2) + 40
    body = texture((120, 160), 1.0, 200, seed=3) + 10
    out = []
    for i in range(frames):
        moved = shifted(body, speed * i, 0)
        image = background.copy()
        image[40:80, 50:90] = moved[40:80, 50:90]
        image = image + rng.normal(0, 1.5, image.shape)
        out.append(np.clip(image, 0, 255).astype(np.uint8))
    return out


@pytest.mark.parametrize("speed", [0.5])
def test_a_slow_mover_changes_the_image_over_three_frames_not_one(speed):
    frames = slow_mover_clip(speed)
    history = ChangeHistory(3)
    fit = SimpleNamespace(reliable=True, homography=np.eye(3))
    for previous, grey in zip(frames, frames[1:]):
        assert history.changed(3.0, 3) is None  # not enough frames held yet
        history.update(SimpleNamespace(grey=grey, previous_grey=previous, shape=grey.shape), fit)
    one = cv2.absdiff(frames[-1], frames[-2])
    one_frame = cv2.blur(one, (3, 3)) > 3.0 * difference_noise(one)
    longer = history.changed(3.0, 3)
    body = (slice(44, 76), slice(54, 86))  # inside the square, off its edges
    outside = np.ones(one.shape, bool)
    outside[35:85, 45:95] = False
    assert one_frame[body].mean() < 0.2  # measured 0.09
    assert longer[body].mean() > 0.7  # measured 0.85
    assert longer[outside].mean() < 0.01
    history.update(SimpleNamespace(grey=frames[0], previous_grey=frames[0], shape=one.shape),
                   SimpleNamespace(reliable=False, homography=None))  # fmt: skip
    assert history.changed(3.0, 3) is None  # an unknown plane breaks the chain


def test_what_entered_the_view_over_three_frames_is_no_change():
    """A camera panning 12 px/frame past a slow mover: over three frames a
    strip 36 px wide enters at the right, with nothing three frames back to
    compare with. It is not called changed, and the noise is taken over what
    both frames see, so the slow mover's body is found as on a still view."""
    rng = np.random.default_rng(0)
    pan, width = 12, 160
    world = texture((120, width + 3 * pan), 1.0, 160, seed=2) + 40
    body = texture((120, width + 3 * pan), 1.0, 200, seed=3) + 10
    frames = []
    for i in range(4):
        canvas = world.copy()
        canvas[40:80, 50:90] = shifted(body, 0.5 * i, 0)[40:80, 50:90]
        view = canvas[:, pan * i : pan * i + width] + rng.normal(0, 1.5, (120, width))
        frames.append(np.clip(view, 0, 255).astype(np.uint8))
    history = ChangeHistory(3)
    fit = SimpleNamespace(reliable=True, homography=plane_from_motion(-pan, 0))
    for previous, grey in zip(frames, frames[1:]):
        history.update(SimpleNamespace(grey=grey, previous_grey=previous, shape=grey.shape), fit)
    longer = history.changed(3.0, 3)
    entered = (slice(None), slice(width - 3 * pan, None))
    inside = (slice(44, 76), slice(54 - 3 * pan, 86 - 3 * pan))  # the body, off its edges
    still = np.ones(longer.shape, bool)
    still[35:85, 45 - 3 * pan : 95 - 3 * pan] = False
    still[entered] = False
    assert not longer[entered].any()
    assert longer[inside].mean() > 0.7
    assert longer[still].mean() < 0.01


def test_only_slow_flagged_parts_take_the_longer_baseline():
    flagged = np.zeros((40, 60), bool)
    flagged[5:15, 5:15] = True  # a slow part
    flagged[25:35, 30:50] = True  # a fast part
    speed = np.zeros((40, 60), np.float32)
    speed[5:15, 5:15] = 0.4
    speed[25:35, 30:50] = 3.0
    slow = slow_parts(flagged, speed, frames=3, px=2)
    assert slow[5:15, 5:15].all() and not slow[25:35, 30:50].any() and not slow[~flagged].any()


def ghost_clip(frames=13, pan=1.0, speed=6, side=40):
    """A view panning ``pan`` px/frame; a textured square moving ``speed``
    px/frame to the right, from x = 20, over it. Frames and the square's masks."""
    world = texture((120, 240), 2.0, 200, seed=1) + 20
    body = texture((120, 240), 1.0, 200, seed=3) + 10
    images, masks = [], []
    for t in range(frames):
        image = shifted(world, pan * t, 0)
        x = 20 + speed * t
        image[40 : 40 + side, x : x + side] = body[40 : 40 + side, x : x + side]
        mask = np.zeros(image.shape, bool)
        mask[40 : 40 + side, x : x + side] = True
        images.append(np.clip(image, 0, 255).astype(np.uint8))
        masks.append(mask)
    return images, masks


@pytest.mark.parametrize("rate", [0.25, 1.0])  # a running mean; the last look (the default)
def test_the_remembered_background_takes_out_the_ghost_a_mover_leaves(rate):
    images, masks = ghost_clip()
    plane = plane_from_motion(1.0, 0)
    memory = BackgroundMemory(rate, 2)
    fit = SimpleNamespace(reliable=True, homography=plane)
    for t in range(1, len(images)):
        field = SimpleNamespace(grey=images[t], previous_grey=images[t - 1], shape=images[t].shape)
        differs = memory.differs(field, fit, 3.0, 3)
        warped = cv2.warpPerspective(images[t - 1], plane, images[t].shape[::-1],
                                     flags=cv2.WARP_INVERSE_MAP)  # fmt: skip
        one = cv2.absdiff(images[t], warped)
        changed = cv2.blur(one, (3, 3)) > 3.0 * difference_noise(one)
        memory.learn(masks[t], changed)  # as if the detectors flagged the square
    ghost = masks[-2] & ~masks[-1]  # seen before the square came: known
    ghost[:, :-1] &= ghost[:, 1:]  # off the square's new edge by a pixel
    square = cv2.erode(masks[-1].astype(np.uint8), np.ones((5, 5), np.uint8)) > 0
    path = np.logical_or.reduce(masks).astype(np.uint8)
    still = cv2.dilate(path, np.ones((9, 9), np.uint8)) == 0  # never under the square
    still[:, :16] = still[:, -4:] = False  # the reflected border (16): not the pan
    left_behind = np.zeros_like(still)
    left_behind[44:76, 40:70] = True  # under the square at the start; uncovered 4+ frames ago
    assert changed[ghost].mean() > 0.8  # the one-frame change shows the ghost
    assert differs[ghost].mean() < 0.2  # the memory does not
    assert differs[square].mean() > 0.9
    assert differs[still].mean() < 0.05
    assert differs[left_behind].mean() < 0.05  # seen twice since: known
    assert differs[:, 0].all()  # content that just entered the view is unknown
    unknown = SimpleNamespace(reliable=False, homography=None)
    assert memory.differs(field, unknown, 3.0, 3) is None  # an unknown plane: start afresh
    assert memory.differs(field, fit, 3.0, 3) is None


def test_an_object_is_trimmed_to_its_largest_kept_part_unless_that_cuts_too_much():
    own = np.zeros((40, 60), np.uint8)
    own[10:30, 10:50] = 1
    kept = own.copy()
    kept[10:30, 10:18] = 0  # its trailing ghost
    kept[12, 5:9] = 1  # a speck of its own
    out = trimmed(own, kept, None, 0.7)
    assert out.sum() == 20 * 32 and not out[10:30, 10:18].any()
    kept[10:30, 10:40] = 0  # would keep a quarter
    assert (trimmed(own, kept, None, 0.7) == own).all()
    with pytest.raises(ValueError, match="background_rate"):
        TrackConfig(background_rate=1.5)
