"""Letterboxed and pillarboxed video: only the picture inside the black bars is measured."""

from __future__ import annotations

import cv2
import numpy as np

from motiondetect.detection.detector import MotionDetector
from motiondetect.measurement.dense_flow import DenseFlowConfig
from motiondetect.measurement.picture import BLEED_PX, PictureArea, content_bounds

from .velocity_scenes import H, W, background, pan_with_mover

BAR = 40  # px: each pillarbox bar around the 320x240 synthetic frames


def _pillarboxed(image: np.ndarray) -> np.ndarray:
    return cv2.copyMakeBorder(image, 0, 0, BAR, BAR, cv2.BORDER_CONSTANT, value=0)


def _panelled(image: np.ndarray, bar: int = BAR) -> np.ndarray:
    """``image`` between social media's side panels: itself enlarged to the
    whole width, blurred (a Gaussian of 5 % of the width) and darkened."""
    h, w = image.shape[:2]
    width = w + 2 * bar
    big = cv2.resize(image, (width, round(h * width / w)))
    top = (big.shape[0] - h) // 2
    out = (cv2.GaussianBlur(big[top : top + h], (0, 0), 0.05 * width) * 0.6).astype(np.uint8)
    out[:, bar : bar + w] = image
    return out


def test_content_bounds_are_the_box_of_everything_above_the_limit():
    frame = np.zeros((100, 200, 3), np.uint8)
    frame[10:90, 30:170] = 25  # just above cropdetect's 24
    frame[50, 20, 2] = 200  # one bright red pixel widens the box
    assert content_bounds(frame) == (20, 10, 170, 90)
    frame[10:90, 30:170] = 24
    frame[50, 20] = 0
    assert content_bounds(frame) is None  # dark throughout
    deep = np.zeros((100, 200), np.uint16)
    deep[5:95, 40:160] = 25 * 257  # 16-bit frames: the same limit, scaled
    assert content_bounds(deep) == (40, 5, 160, 95)


def test_the_picture_is_found_after_dark_frames_and_opens_where_a_bar_lights():
    area = PictureArea()
    dark = np.zeros((240, 400, 3), np.uint8)
    assert area.update(dark) is None  # a fade from black: nothing known yet
    frame = _pillarboxed(background(0.0))
    assert area.update(frame).box == (BAR, 0, W, H)
    bleed = frame.copy()
    bleed[:, BAR - BLEED_PX : BAR] = 120  # a codec's ringing next to the picture
    assert area.update(bleed).box == (BAR, 0, W, H)
    lit = frame.copy()
    lit[100:110, 5:15] = 200  # content well inside the left bar: no centred pair left
    assert area.update(lit) is None  # the whole frame, for good
    assert area.update(frame) is None


def test_a_title_on_black_gives_way_to_a_letterboxed_film():
    """Centred titles on black look like pictures inside bars; when the
    film starts, the picture grows to the film's letterbox, not to the
    frame's edges. Opening a third time gives up on bars."""
    area = PictureArea()
    title = np.zeros((240, 400, 3), np.uint8)
    title[80:160, 120:280] = 255
    assert area.update(title).box == (120, 80, 160, 80)
    title[60:180, 80:320] = 255  # a larger title: the first opening
    assert area.update(title).box == (80, 60, 240, 120)
    film = np.zeros((240, 400, 3), np.uint8)
    film[30:210] = cv2.resize(background(0.0), (400, 180))
    assert area.update(film).box == (0, 30, 400, 180)  # the second
    assert area.update(film).box == (0, 30, 400, 180)
    whole = cv2.resize(background(0.0), (400, 240))
    assert area.update(whole) is None  # a third: the whole frame, for good
    assert area.update(film) is None


def test_blurred_panels_beside_the_picture_are_bars():
    """The panels are bright, but show no detail: the picture between them
    is found (within the reduced frame's pixel), and a panel that keeps
    moving with the video does not light up."""
    area = PictureArea()
    for t in range(10):
        picture = area.update(_panelled(background(2.0 * t)))
        x, y, w, h = picture.box
        assert abs(x - BAR) <= 1 and abs(w - W) <= 2 and (y, h) == (0, H)
    sharp = _panelled(background(0.0))
    sharp[:, 5:15] = background(0.0)[:, :10]  # detail in a panel: the picture opens
    assert area.update(sharp) is None


def test_a_thin_dark_edge_is_no_bar():
    """An encoder's dark column (under 1 % of the side) is left to the
    frame-edge band; the picture is the whole frame."""
    frame = background(0.0)
    frame[:, :2] = 0
    assert PictureArea().update(frame) is None


def test_a_pillarboxed_pan_gives_the_unboxed_results_in_place():
    """The picture of a pillarboxed pan is the unboxed clip, so every mask
    and box is the unboxed clip's, moved by the bar's width, and nothing is
    flagged in the bars. Measuring the whole frame instead (``bar_limit``
    0), the picture's edges, where content enters the view, are flagged
    on every frame (measured: 2-3 regions)."""
    clip = pan_with_mover(lambda t: (60 + 3 * t, 100 + 1.0 * t), frames=20)
    plain = MotionDetector("both")
    boxed = MotionDetector("both")
    whole = MotionDetector("both", DenseFlowConfig(bar_limit=0))
    at_edges, found = [], []
    for t, (image, _) in enumerate(clip):
        expected = plain.process(image, t, 0.0)
        wide = _pillarboxed(image)
        got = boxed.process(wide, t, 0.0)
        mask = got.input_mask(W + 2 * BAR, H)
        assert np.array_equal(mask[:, BAR:-BAR], expected.input_mask(W, H))
        assert not mask[:, :BAR].any() and not mask[:, -BAR:].any()
        shifted = [[x + BAR, y, w, h] for x, y, w, h in (r.bbox for r in expected.regions)]
        assert [r.bbox for r in got.regions] == shifted
        found.append(bool(shifted))
        edges = (r.bbox for r in whole.process(wide, t, 0.0).regions)
        at_edges.append(sum(x < BAR + 12 or x + w > W + BAR - 12 for x, _, w, _ in edges))
    assert all(found[3:])  # the mover, on every frame once warm
    assert min(at_edges[3:]) >= 1


def test_known_ego_motion_measures_the_whole_frame():
    """Known poses describe the whole recorded frame, so bars are not cut
    off under ``--egomotion``; without it they are."""
    frames = [_pillarboxed(background(2.0 * t)) for t in range(2)]
    for egomotion, size in ((None, (W, H)), (lambda i, g: None, (W + 2 * BAR, H))):
        md = MotionDetector("both", egomotion=egomotion)
        md.measure_frame(frames[0])
        assert md.measure_frame(frames[1]).geometry.input_size == size


def test_a_dark_band_on_one_side_only_is_no_bar():
    """A night sky above a lit road is dark along the top alone: bars come
    in pairs of one thickness, so the frame is measured whole."""
    frame = background(0.0)
    frame[:50] = 0
    assert PictureArea().update(frame) is None
    frame[-50 + BLEED_PX + 1 :] = (
        0  # a bar below, thinner than the one above by more than the bleed
    )
    assert PictureArea().update(frame) is None
    frame[-50:] = 0
    assert PictureArea().update(frame).box == (0, 50, W, H - 100)


def test_a_panelled_pan_is_measured_between_its_panels():
    """Social media's blurred panels beside a pan: measured between them,
    the mover is found on every frame and nothing is flagged at the
    picture's edges; measuring the whole frame (``bar_limit`` 0), the
    picture's edges are flagged, where content enters it."""
    clip = pan_with_mover(lambda t: (60 + 3 * t, 100 + 1.0 * t), frames=20)

    def run(config: DenseFlowConfig) -> tuple[list[int], list[bool]]:
        md = MotionDetector("both", config)
        at_edges, found = [], []
        for t, (image, mask) in enumerate(clip):
            result = md.process(_panelled(image), t, t / 30)
            boxes = [r.bbox for r in result.regions]
            at_edges.append(sum(x < BAR + 12 or x + w > W + BAR - 12 for x, _, w, _ in boxes))
            flagged = result.input_mask(W + 2 * BAR, H)[:, BAR:-BAR] > 0
            found.append(flagged[mask].mean() >= 0.5)
        return at_edges[3:], found[3:]

    edges, found = run(DenseFlowConfig())
    assert sum(edges) == 0 and all(found)
    whole_edges, _ = run(DenseFlowConfig(bar_limit=0))
    assert sum(whole_edges) >= len(whole_edges)


def test_a_fade_to_black_says_nothing_of_the_bars():
    """A picture gone dark and plain (a fade, a cut to black) shows no
    detail, so faint noise in the bars does not open them."""
    area = PictureArea()
    assert area.update(_pillarboxed(background(0.0))).box == (BAR, 0, W, H)
    faded = np.full((H, W + 2 * BAR, 3), 30, np.uint8)
    faded[:, :BAR] = faded[:, -BAR:] = 0
    faded[::2, 5:15] = 3  # a codec's faint noise in the left bar
    for _ in range(3):  # (each opening counts; the third would give up on bars)
        assert area.update(faded).box == (BAR, 0, W, H)
    assert area.update(_pillarboxed(background(0.0))).box == (BAR, 0, W, H)


def test_a_grey_pillarboxed_picture_at_working_size_is_measured():
    """Grey frames whose picture needs no reduction (320x240 inside its bars,
    at most the working size) are measured on a crop of the frame, a view
    DIS cannot take as it is; the results are the unboxed clip's."""
    clip = pan_with_mover(lambda t: (60 + 3 * t, 100 + 1.0 * t), frames=8)
    plain, boxed = MotionDetector("both"), MotionDetector("both")
    for t, (image, _) in enumerate(clip):
        grey = cv2.cvtColor(image, cv2.COLOR_BGR2GRAY) if image.ndim == 3 else image
        expected = plain.process(grey, t, 0.0)
        got = boxed.process(_pillarboxed(grey), t, 0.0)
        assert got.field is None or got.field.picture is not None
        assert np.array_equal(
            got.input_mask(W + 2 * BAR, H)[:, BAR:-BAR], expected.input_mask(W, H)
        )
    assert got.regions  # the mover
