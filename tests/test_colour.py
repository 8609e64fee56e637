"""OpenCV's 4:2:0 colour conversion agrees with FFmpeg's, at both ranges and 8 or 10 bits."""

import av
import numpy as np
import pytest

from motiondetect.io.colour import (
    FULL_RANGE,
    GREY_SCALE,
    bgr_to_frame,
    frame_to_bgr,
    frame_to_grey,
)


def _picture(h: int = 64, w: int = 96) -> np.ndarray:
    """Smooth colour ramps (4:2:0 keeps them): (h, w, 3) uint8 BGR."""
    y, x = np.mgrid[0:h, 0:w].astype(np.float32)
    return np.dstack([x / w * 255, y / h * 255, (x + y) / (w + h) * 255]).astype(np.uint8)


@pytest.mark.parametrize("pix_fmt", ["yuv420p", "yuvj420p", "yuv420p10le"])
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


def _flat(pix_fmt: str, luma: int, chroma: int, full: bool) -> av.VideoFrame:
    """A 64x64 frame of one grey: every luma sample ``luma``, chroma ``chroma``."""
    planes = np.full((96, 64), chroma, np.uint16 if "10" in pix_fmt else np.uint8)
    planes[:64] = luma
    frame = av.VideoFrame.from_ndarray(planes, format=pix_fmt)
    frame.color_range = FULL_RANGE if full else 0
    return frame


@pytest.mark.parametrize(
    ("pix_fmt", "luma", "chroma", "full", "grey"),
    [
        ("yuv420p10le", 64, 512, False, 0),  # video range, 10 bits: 64-940
        ("yuv420p10le", 256, 512, False, 56),  # 8-bit 64 at video range
        ("yuv420p10le", 940, 512, False, 255),
        ("yuv420p10le", 256, 512, True, 64),  # full range, flagged
        ("yuv420p", 64, 128, True, 64),  # HEVC's full range: yuv420p, flagged
        ("yuv420p", 192, 128, True, 192),
    ],
)
def test_ten_bits_and_flagged_full_range(pix_fmt, luma, chroma, full, grey):
    frame = _flat(pix_fmt, luma, chroma, full)
    ours = frame_to_bgr(frame).astype(int)
    assert ours.dtype == int and np.abs(ours - grey).max() <= 1
    # swscale's 10-bit path rounds its own way (940, white, to 253)
    assert np.abs(ours - frame.to_ndarray(format="bgr24").astype(int)).max() <= 2


def test_odd_sizes_and_other_formats_still_convert():
    odd = av.VideoFrame(33, 17, "yuv420p")
    assert frame_to_bgr(odd).shape == (17, 33, 3)
    rgb = av.VideoFrame.from_ndarray(_picture()[..., ::-1].copy(), format="rgb24")
    assert np.array_equal(frame_to_bgr(rgb), _picture())


def test_encoder_frames_round_trip():
    frame = bgr_to_frame(_picture())
    assert frame.format.name == "yuv420p" and (frame.width, frame.height) == (96, 64)
    assert np.abs(frame_to_bgr(frame).astype(int) - _picture()).mean() < 1.5


def test_luma_to_grey_is_the_rounded_clipped_scale():
    """Every luma level, in a row as wide as 4K, maps to round((Y - 16) * 255 / 219), clipped."""
    levels = np.tile(np.arange(256, dtype=np.uint8), 15)[None, :3840].repeat(4, axis=0)
    frame = av.VideoFrame.from_ndarray(
        np.vstack([levels, np.full((2, 3840), 128, np.uint8)]), format="yuv420p"
    )
    expected = np.clip(np.rint((levels.astype(float) - 16) * GREY_SCALE), 0, 255)
    assert np.array_equal(frame_to_grey(frame), expected.astype(np.uint8))
