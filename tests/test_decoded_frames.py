"""Decoded video frames are converted only as far as they are used: the
measurement reads the luma plane, the annotated video a picture converted at
its own size; both agree with the whole BGR image, turned alike."""

from __future__ import annotations

import av
import cv2
import numpy as np
import pytest
from click.testing import CliRunner
from motiondetect_cli.main import main

import motiondetect.io.decode as decode
from motiondetect.io.source import fitted
from motiondetect.io.video import open_source

from .cli_outputs import write_video
from .media import encode, turned_quarter
from .scenes import scene

N = 10


@pytest.fixture(scope="module")
def frames():
    return [fr.image for fr in scene("pan", ("smooth",), frames=N)]


def _first(path):
    with open_source(path) as source:
        return next(iter(source))


@pytest.mark.parametrize(
    ("codec", "pix_fmt"),
    [
        ("libx264", "yuv420p"),
        ("libx264", "yuvj420p"),
        ("libx265", "yuv420p10le"),
        ("libx264", "yuv444p"),  # the luma plane, through swscale's colour
        ("ffv1", "bgr0"),  # no luma plane: the BGR made grey
    ],
)
def test_grey_and_picture_agree_with_the_whole_image(tmp_path, frames, codec, pix_fmt):
    if codec not in av.codecs_available:
        pytest.skip(f"this PyAV build has no {codec} encoder")
    path = encode(tmp_path / "a.mkv", frames[:3], codec, pix_fmt=pix_fmt)
    frame = _first(path)
    assert frame.grey.dtype == np.uint8 and frame.grey.shape == frame.image.shape[:2]
    from_bgr = cv2.cvtColor(frame.image, cv2.COLOR_BGR2GRAY).astype(int)
    diff = np.abs(frame.grey.astype(int) - from_bgr)
    # equal but for rounding, and where BGR clips a saturated colour
    assert diff.mean() < 0.5 and np.percentile(diff, 99) <= 2
    h, w = frame.image.shape[:2]
    for size in ((w // 2, h // 2), (w // 3 * 2 // 2 * 2, h // 3 * 2 // 2 * 2), (w + 64, h + 48)):
        picture = frame.picture(size)
        assert picture.shape == (size[1], size[0], 3) and picture.dtype == np.uint8
        assert np.abs(picture.astype(int) - fitted(frame.image, size)).mean() < 1.5


def test_turned_frames_turn_grey_and_picture_alike(tmp_path, frames):
    path = turned_quarter(write_video(tmp_path / "upright.mp4", frames[:3]), tmp_path / "p.mp4")
    frame = _first(path)
    h, w = frames[0].shape[:2]
    assert frame.image.shape[:2] == frame.grey.shape == (w, h)  # portrait
    from_bgr = cv2.cvtColor(frame.image, cv2.COLOR_BGR2GRAY).astype(int)
    assert np.abs(frame.grey.astype(int) - from_bgr).mean() < 0.5
    size = (h // 2 // 2 * 2, w // 2 // 2 * 2)  # (width, height) of the portrait picture
    assert np.abs(frame.picture(size).astype(int) - fitted(frame.image, size)).mean() < 1.5


def _counted(monkeypatch) -> dict:
    """Count the whole-frame and the resized colour conversions of decoded frames."""
    calls = {"whole": 0, "resized": 0}

    def count(name, fn):
        def counted(*args):
            calls[name] += 1
            return fn(*args)

        return counted

    monkeypatch.setattr(decode, "frame_to_bgr", count("whole", decode.frame_to_bgr))
    monkeypatch.setattr(decode, "frame_to_bgr_at", count("resized", decode.frame_to_bgr_at))
    return calls


@pytest.mark.parametrize("kind", ["video", "jpeg folder"])
def test_detect_converts_no_whole_frame_to_colour(tmp_path, frames, monkeypatch, kind):
    if kind == "video":
        path = encode(tmp_path / "clip.mp4", frames)
    else:
        path = _jpeg_folder(tmp_path / "seq", frames)
    calls = _counted(monkeypatch)
    result = CliRunner().invoke(main, ["detect", str(path), "-o", str(tmp_path / "a"), "-q"])
    assert result.exit_code == 0, result.output
    assert calls == {"whole": 0, "resized": N}  # one picture per annotated frame
    calls["resized"] = 0
    args = ["detect", str(path), "-o", str(tmp_path / "b"), "-q", "--no-video"]
    result = CliRunner().invoke(main, args)
    assert result.exit_code == 0, result.output
    assert calls == {"whole": 0, "resized": 0}  # the luma alone was read


def _jpeg_folder(folder, frames, sampling=None):
    folder.mkdir()
    params = [] if sampling is None else [cv2.IMWRITE_JPEG_SAMPLING_FACTOR, sampling]
    for n, image in enumerate(frames):
        cv2.imwrite(str(folder / f"f_{n + 7}.jpg"), image, params)
    return folder


@pytest.mark.parametrize(
    "sampling", [None, cv2.IMWRITE_JPEG_SAMPLING_FACTOR_444, cv2.IMWRITE_JPEG_SAMPLING_FACTOR_422]
)
def test_a_colour_jpeg_folder_is_measured_on_its_luma_as_a_video_is(tmp_path, frames, sampling):
    folder = _jpeg_folder(tmp_path / "seq", frames[:3], sampling)
    with open_source(folder) as source:
        read = list(source)
    assert [f.number for f in read] == [7, 8, 9]
    for f, file in zip(read, sorted(folder.iterdir())):
        assert isinstance(f, decode.DecodedFrame)  # the luma read alone, colour only if drawn
        luma = cv2.imread(str(file), cv2.IMREAD_GRAYSCALE).astype(int)  # libjpeg's Y plane
        diff = np.abs(f.grey.astype(int) - luma)
        assert diff.max() <= 1 and diff.mean() < 0.05  # two IDCTs' rounding
        colour = cv2.imread(str(file))
        assert f.image.shape == colour.shape
        assert np.abs(f.image.astype(int) - colour).mean() < 1.5  # chroma upsampled otherwise
        h, w = colour.shape[:2]
        assert f.picture((w // 2, h // 2)).shape == (h // 2, w // 2, 3)


def test_images_ffmpeg_does_not_read_as_colour_jpegs_are_read_by_opencv(tmp_path, frames):
    folder = _jpeg_folder(tmp_path / "seq", frames[:2])
    grey = cv2.cvtColor(frames[2], cv2.COLOR_BGR2GRAY)
    cv2.imwrite(str(folder / "f_9.jpg"), grey)  # a grey JPEG
    cv2.imwrite(str(folder / "f_10.png"), frames[3])
    (folder / "f_11.jpg").write_bytes(cv2.imencode(".png", frames[4])[1].tobytes())  # misnamed
    cv2.imwrite(str(folder / "f_12.jpg"), frames[5])  # FFmpeg's again after its error
    with open_source(folder) as source:
        read = list(source)
    assert [type(f) is decode.DecodedFrame for f in read] == [True, True, False, False, False, True]
    assert read[2].image.shape == grey.shape
    assert np.abs(read[2].image.astype(int) - grey).mean() < 2
    assert np.array_equal(read[3].image, frames[3]) and np.array_equal(read[4].image, frames[4])
    assert not source.partial
