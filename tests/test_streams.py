"""Which file is a video, and which of its streams is read: thumbnails and
cover pictures, audio files, raw streams and MJPEG dumps (issue 14's
bad-input table, docs/robustness.md)."""

from __future__ import annotations

from fractions import Fraction

import av
import cv2
import numpy as np
import pytest

from motiondetect.app.inputs import discover_inputs
from motiondetect.io.video import open_source

from .cli_outputs import invoke, times_of
from .media import encode
from .scenes import scene

N = 12


@pytest.fixture(scope="module")
def frames():
    return [fr.image for fr in scene("pan", ("smooth",), frames=N)]


def test_a_thumbnail_stream_before_the_video_is_not_read_as_the_video(tmp_path, frames):
    """A file storing a one-picture stream (a thumbnail, a cover) before its
    video: the video is read, as FFmpeg's own choice of stream has it."""
    path = tmp_path / "thumb_first.mkv"
    with av.open(str(path), "w") as container:
        thumb = container.add_stream("mjpeg", rate=1)
        thumb.width, thumb.height, thumb.pix_fmt = 96, 64, "yuvj420p"
        main = container.add_stream("libx264", rate=30)
        h, w = frames[0].shape[:2]
        main.width, main.height, main.pix_fmt = w, h, "yuv420p"
        small = np.ascontiguousarray(frames[0][:64, :96])
        for stream, images in ((thumb, [small]), (main, frames)):
            for image in images:
                container.mux(stream.encode(av.VideoFrame.from_ndarray(image, format="bgr24")))
            container.mux(stream.encode())
    with open_source(path) as source:
        assert (source.info.width, source.info.height, source.info.codec) == (w, h, "h264")
        assert sum(1 for _ in source) == N
    result = invoke("detect", path, "-o", tmp_path / "o", "-q", "--no-video")
    assert result.exit_code == 0, result.output
    assert len(times_of(tmp_path / "o" / "thumb_first")) == N


def test_a_cover_picture_is_never_the_video_while_a_video_exists():
    from types import SimpleNamespace

    from motiondetect.io.decode import main_video_stream

    cover = SimpleNamespace(disposition=av.stream.Disposition.attached_pic)
    video, other = SimpleNamespace(disposition=0), SimpleNamespace(disposition=0)

    def container(streams, best):
        return SimpleNamespace(streams=SimpleNamespace(video=streams, best=lambda kind: best))

    assert main_video_stream(container([cover, video], cover)) is video
    assert main_video_stream(container([cover, video, other], other)) is other
    assert main_video_stream(container([cover], cover)) is None  # an audio file's cover


def test_an_audio_file_with_a_cover_picture_is_one_line(tmp_path):
    path = tmp_path / "song.m4a"
    with av.open(str(path), "w", format="mp4") as container:
        audio = container.add_stream("aac", rate=44100)
        cover = container.add_stream("mjpeg", rate=1)
        cover.width, cover.height, cover.pix_fmt = 64, 64, "yuvj420p"
        cover.disposition = av.stream.Disposition.attached_pic
        picture = av.VideoFrame.from_ndarray(np.zeros((64, 64, 3), np.uint8), format="rgb24")
        container.mux(cover.encode(picture))
        container.mux(cover.encode())
        sound = av.AudioFrame.from_ndarray(np.zeros((1, 4410), np.float32), "fltp", "mono")
        sound.sample_rate = 44100
        container.mux(audio.encode(sound))
        container.mux(audio.encode())
    result = invoke("detect", path, "-o", tmp_path / "o", "-q")
    assert result.exit_code == 1 and "Traceback" not in result.output
    assert "song.m4a: no video stream, only a cover picture" in result.output


def test_raw_streams_and_mjpeg_are_videos_a_batch_finds(tmp_path, frames):
    """H.264 and H.265 elementary streams, IVF and MJPEG (JPEGs one after
    another, as IP cameras dump them) are videos: a batch finds them and
    each is processed whole. Before, a batch skipped them as not videos, and
    an MJPEG file named on the command line was 'a still image' (it starts
    as a JPEG does); a single JPEG so named still is."""
    folder = tmp_path / "dump"
    folder.mkdir()
    encode(folder / "cam.h264", frames, fmt="h264", rate=25)
    encode(folder / "cam.ivf", frames, "libvpx", fmt="ivf", rate=25)
    encode(folder / "ip.mjpeg", frames, "mjpeg", fmt="mjpeg", rate=25, pix_fmt="yuvj420p")
    jobs = discover_inputs([folder], recursive=False)
    assert sorted(j.path.name for j in jobs) == ["cam.h264", "cam.ivf", "ip.mjpeg"]
    result = invoke("detect", folder, "-o", tmp_path / "o", "-q", "--no-video")
    assert result.exit_code == 0, result.output
    for name in ("cam.h264", "cam.ivf", "ip"):  # a shared name keeps its extension
        assert len(times_of(tmp_path / "o" / name)) == N, name
    still = tmp_path / "still.mjpeg"
    ok, buffer = cv2.imencode(".jpg", frames[0])
    still.write_bytes(buffer.tobytes())
    result = invoke("detect", still, "-o", tmp_path / "o2", "-q")
    assert result.exit_code == 1 and "still.mjpeg: a still image, not a video" in result.output


def test_camcorder_and_action_camera_files_are_videos_a_batch_finds(tmp_path, frames):
    """DV (a tape camcorder's stream), MPEG-2 in a camcorder's .mod, and
    GoPro's .lrv proxy (an MP4 by another name): a batch finds each and
    reads every frame. Before, all three were 'not videos'."""
    folder = tmp_path / "card"
    folder.mkdir()
    ntsc = [cv2.resize(f, (720, 480)) for f in frames]  # the sizes DV allows
    encode(
        folder / "tape.dv", ntsc, "dvvideo", fmt="dv", rate=Fraction(30000, 1001), pix_fmt="yuv411p"
    )
    encode(folder / "MOV001.MOD", frames, "mpeg2video", fmt="vob")
    encode(folder / "GL010001.LRV", frames, fmt="mp4")
    jobs = discover_inputs([folder], recursive=False)
    assert sorted(j.path.name for j in jobs) == ["GL010001.LRV", "MOV001.MOD", "tape.dv"]
    result = invoke("detect", folder, "-o", tmp_path / "o", "-q", "--no-video")
    assert result.exit_code == 0, result.output
    for name in ("tape", "MOV001", "GL010001"):
        assert len(times_of(tmp_path / "o" / name)) == N, name
