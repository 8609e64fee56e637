"""A plain mover's interior (``[track] interior_px``, ``shaping.interior_grown``;
docs/detectors.md, "A plain mover's interior").

The support gate keeps flagged pixels near an image change; a plain
surface that moves barely changes the image, so only its outline is kept.
Flagged pixels well inside their region, inside the hull of its supported
pixels and looking like them rather than like the ring round the region,
are put back; DIS's smear over the background beside a mover is not.
"""

from __future__ import annotations

import cv2
import numpy as np
import pytest
from skimage import data

from motiondetect.detection.detector import MotionDetector
from motiondetect.detection.objects import TrackConfig, group_objects
from motiondetect.detection.shaping import RING_PX, InteriorMotion, interior_grown
from motiondetect.measurement.aperture import structure_tensor

from .velocity_scenes import H, W

INSET = TrackConfig().interior_px


def _textured(shape, low=40, high=140, seed=0):
    return np.random.default_rng(seed).integers(low, high, shape).astype(np.uint8)


def _plain_square(x1: int):
    """A plain bright square (220), rows 30-90 and columns 40 to ``x1``, on a
    dark texture; flagged: the square and a smear band of ``INSET`` px round it."""
    grey = _textured((120, 160))
    mover = np.zeros(grey.shape, bool)
    mover[30:90, 40:x1] = True
    grey[mover] = 220
    flagged = np.zeros(grey.shape, bool)
    flagged[30 - INSET : 90 + INSET, 40 - INSET : x1 + INSET] = True
    return grey, mover, flagged


def _square_scene():
    """:func:`_plain_square` to column 120; supported: 2 px each side of its edge."""
    grey, mover, flagged = _plain_square(120)
    edge = np.zeros(grey.shape, bool)
    edge[28:92, 38:122] = True
    edge[32:88, 42:118] = False
    return grey, mover, flagged, (edge & flagged).astype(np.uint8)


def test_a_plain_movers_interior_is_put_back_and_the_smear_is_not():
    grey, mover, flagged, supported = _square_scene()
    grown = interior_grown(supported, flagged, grey, INSET) > 0
    assert grown[mover].mean() > 0.99
    added = grown & ~(supported > 0)
    assert not (added & ~mover).any()  # nothing of the band round it
    assert supported[mover].mean() < 0.25  # what the gate left


def test_nothing_is_grown_when_turned_off_or_nothing_is_supported():
    grey, _, flagged, supported = _square_scene()
    assert np.array_equal(interior_grown(supported, flagged, grey, 0), supported)
    none = np.zeros_like(supported)
    assert not interior_grown(none, flagged, grey, INSET).any()


def test_smear_that_looks_like_the_background_is_not_added():
    """A textured U (grey levels 40-140) whose inside is flagged smear over a
    plain background of 220, the background round it too: the inside lies
    within the U's hull and deep inside the flagged region, but it looks
    like the ring, so it stays out. The same inside painted like the U joins."""
    grey = np.full((120, 160), 220, np.uint8)
    u = np.zeros(grey.shape, bool)
    u[20:100, 30:130] = True
    u[20:80, 55:105] = False  # the U's inside, open at the top
    grey[u] = _textured(grey.shape)[u]
    flagged = np.zeros(grey.shape, bool)
    flagged[20:100, 30:130] = True  # the U and its inside
    inside = flagged & ~u
    deep = np.zeros(grey.shape, bool)
    deep[20 + INSET : 80 - INSET, 55 + INSET : 105 - INSET] = True
    grown = interior_grown(u.astype(np.uint8), flagged, grey, INSET) > 0
    assert not (grown & inside).any()
    grey[inside] = _textured(grey.shape, seed=1)[inside]
    grown = interior_grown(u.astype(np.uint8), flagged, grey, INSET) > 0
    assert grown[deep & inside].mean() > 0.9
    assert RING_PX >= INSET  # the ring reaches past the smear band


def _open_sided_mover():
    """:func:`_plain_square` to column 100, whose image changed only in a C:
    thick bands on its left, top and bottom (the right third of it shows no
    change, as a plain side does not)."""
    grey, mover, flagged = _plain_square(100)
    changed = np.zeros(grey.shape, bool)
    changed[26:94, 36:56] = True
    changed[26:46, 36:104] = True
    changed[74:94, 36:104] = True
    velocity = np.zeros((*grey.shape, 2), np.float32)
    velocity[mover] = (3.0, 0.0)
    return grey, mover, flagged, changed, velocity


@pytest.mark.parametrize("memory", ["none", "unknown", "differs"])
def test_the_interior_put_back_is_neither_outlined_nor_trimmed_away(memory):
    """The gate keeps the C (0.69 of the square); the interior step puts
    back the plain side. No change can outline that side, and with the
    remembered background unknown or unlike it, the trim keeps it: the
    whole square. (Before the step's pixels joined the outline and the
    trim, both cut it back to the C, 0.69.) Without the interior step, the C."""
    grey, mover, flagged, changed, velocity = _open_sided_mover()
    background = {"none": None, "unknown": np.ones(grey.shape, bool)}.get(memory, mover.copy())
    for inset, low, high in ((INSET, 0.99, 1.0), (0, 0.6, 0.75)):
        config = TrackConfig(interior_px=inset)
        (obj,) = group_objects(flagged, velocity, config, changed, background, grey)
        assert low <= obj.mask[mover].mean() <= high
        assert (obj.mask & ~flagged).sum() == 0


def test_the_interior_put_back_is_trimmed_where_the_memory_knows_it_as_background():
    """The same square with the remembered background matching its plain
    side (only the C differs from it): that side is background the mover
    uncovered, and the trim cuts the object back to the C."""
    grey, mover, flagged, changed, velocity = _open_sided_mover()
    background = changed.copy()
    (obj,) = group_objects(flagged, velocity, TrackConfig(), changed, background, grey)
    assert 0.6 <= obj.mask[mover].mean() <= 0.75


GRASS = data.grass()


def _followed_plain_block(share: float, frames: int = 30):
    """A camera panning 3 px/frame over grass follows a plain block (grey
    220) of ``share`` of the view, which wobbles 2 px about the centre. The
    grass's own texture sets the change noise, as the ground does on a real
    clip, so only the block's left and right edges pass the support gate."""
    mw, mh = int(W * np.sqrt(share)), int(H * np.sqrt(share))
    for t in range(frames):
        shift = np.float32([[1, 0, -3.0 * t - 40], [0, 1, -100]])
        ground = cv2.warpAffine(GRASS, shift, (W, H), flags=cv2.INTER_CUBIC)
        frame = cv2.cvtColor(ground, cv2.COLOR_GRAY2BGR)
        x, y = int(round((W - mw) / 2 + 2 * np.sin(t / 3))), (H - mh) // 2
        frame[y : y + mh, x : x + mw] = 220
        mask = np.zeros((H, W), bool)
        mask[y : y + mh, x : x + mw] = True
        yield frame, mask


@pytest.mark.parametrize("inset", [INSET, 0])
def test_a_followed_plain_block_is_covered_not_just_outlined(inset):
    """Measured from frame 8, at 30 % of the view: covered 0.77 on average
    (at least 0.73) with a median 669 background pixels flagged of 76800,
    against 0.04 and 758 with ``interior_px = 0`` (at 10 %, 20 % and 40 %:
    0.36, 0.66, 0.83 against 0.10, 0.05, 0.03: DIS fills a plain interior
    from its edges, and the farther from them, the nearer the plane's
    motion its fill, which the motion test then refuses)."""
    md = MotionDetector("both", TrackConfig(interior_px=inset))
    covered, background_px = [], []
    for t, (frame, mask) in enumerate(_followed_plain_block(0.3)):
        flagged = md.process(frame, t, t / 30).input_mask(W, H) > 0
        if t >= 8:
            covered.append(flagged[mask].mean())
            background_px.append(int(flagged[~mask].sum()))
    assert np.median(background_px) < 2000
    if inset:
        assert np.mean(covered) > 0.6
        assert min(covered) > 0.5
    else:
        assert np.mean(covered) < 0.2


def test_the_motion_keeps_out_what_would_have_changed_or_moves_with_the_plane():
    """On the plain square of the first test, with a residual of (3, 0)
    px/frame on the square: its interior joins. Where the interior is given
    a texture instead (so that moving it would have changed the image
    beyond the gate's level), or a residual nearer zero than the square's
    supported pixels' (it moves with the plane), it does not."""
    grey, mover, flagged, supported = _square_scene()
    residual = np.zeros(grey.shape + (2,), np.float32)
    residual[flagged] = (3.0, 0.0)
    tensor = structure_tensor(grey, 9)
    motion = InteriorMotion(residual, tensor, seen_level=10.0)
    added = (interior_grown(supported, flagged, grey, INSET, motion) > 0) & (supported == 0)
    assert added[mover].mean() > 0.7
    slow = residual.copy()
    slow[mover & (supported == 0)] = (1.0, 0.0)
    still = InteriorMotion(slow, tensor, seen_level=10.0)
    assert not (
        (interior_grown(supported, flagged, grey, INSET, still) > 0) & ~(supported > 0)
    ).any()
    textured = grey.copy()
    textured[mover] = np.random.default_rng(2).integers(140, 255, mover.sum())
    appearance_alone = interior_grown(supported, flagged, textured, INSET) > 0
    assert appearance_alone[mover].mean() > 0.9  # so the motion test is what refuses it
    rough = InteriorMotion(residual, structure_tensor(textured, 9), seen_level=10.0)
    grown = interior_grown(supported, flagged, textured, INSET, rough) > 0
    assert not (grown & ~(supported > 0)).any()
