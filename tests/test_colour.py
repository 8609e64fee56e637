"""OpenCV's 4:2:0 colour conversion agrees with FFmpeg's, at both ranges."""

import av
import numpy as np
import pytest

from motiondetect.io.colour import bgr_to_frame, frame_to_bgr


def _picture(h: int = 64, w: int = 96) -> np.ndarray:
    """Smooth colour ramps (4:2:0 keeps them): (h, w, 3) uint8 BGR."""
    y, x = np.mgrid[0:h, 0:w].astype(np.float32)
    return np.dstack([x / w * 255, y / h * 255, (x + y) / (w + h) * 255]).astype(np.uint8)


@pytest.mark.parametrize("pix_fmt", ["yuv420p", "yuvj420p"])
def test_four_two_zero_matches_swscale(pix_fmt):
    frame = av.VideoFrame.from_ndarray(_picture(), format="bgr24").reformat(format=pix_fmt)
    ours = frame_to_bgr(frame).astype(int)
    theirs = frame.to_ndarray(format="bgr24").astype(int)
    assert ours.shape == theirs.shape == (64, 96, 3)
    assert np.abs(ours - theirs).mean() < 1.5 and np.abs(ours - theirs).max() <= 8


@pytest.mark.parametrize(
    ("pix_fmt", "luma", "grey"),
    [
        ("yuv420p", 16, 0),
        ("yuv420p", 64, 56),  # video range: (64 - 16) * 255 / 219
        ("yuv420p", 235, 255),
        ("yuvj420p", 0, 0),
        ("yuvj420p", 64, 64),  # full range: as it is
        ("yuvj420p", 192, 192),
    ],
)
def test_grey_levels_at_each_range(pix_fmt, luma, grey):
    planes = np.full((96, 64), 128, np.uint8)  # chroma 128: no colour
    planes[:64] = luma
    frame = av.VideoFrame.from_ndarray(planes, format=pix_fmt)
    assert np.abs(frame_to_bgr(frame).astype(int) - grey).max() <= 1


def test_odd_sizes_and_other_formats_still_convert():
    odd = av.VideoFrame(33, 17, "yuv420p")
    assert frame_to_bgr(odd).shape == (17, 33, 3)
    rgb = av.VideoFrame.from_ndarray(_picture()[..., ::-1].copy(), format="rgb24")
    assert np.array_equal(frame_to_bgr(rgb), _picture())


def test_encoder_frames_round_trip():
    frame = bgr_to_frame(_picture())
    assert frame.format.name == "yuv420p" and (frame.width, frame.height) == (96, 64)
    assert np.abs(frame_to_bgr(frame).astype(int) - _picture()).mean() < 1.5
