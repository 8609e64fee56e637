"""Video through PyAV: each row of issue 14's table, on files the tests write."""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from fractions import Fraction
from pathlib import Path

import av
import numpy as np
import pytest
from click.testing import CliRunner
from motiondetect_cli.main import main

from motiondetect.io.decode import STREAM_PROBE
from motiondetect.io.video import open_source

from .cli_outputs import times_of
from .media import corrupt, encode, has_encoder, pts_times, stream_info
from .scenes import scene

N = 24


def run(*args):
    return CliRunner().invoke(
        main, [os.fsdecode(a) if isinstance(a, bytes) else str(a) for a in args]
    )


@pytest.fixture(scope="module")
def frames():
    return [fr.image for fr in scene("pan", ("smooth",), frames=N)]


def summary_of(out: Path) -> dict:
    return json.loads((out / "summary.json").read_text(encoding="utf-8"))


def test_interlaced_h264_is_deinterlaced_into_real_pictures(tmp_path, frames):
    path = encode(tmp_path / "i.mp4", frames, options={"x264-params": "interlaced=1:tff=1"})
    with open_source(path) as source:
        images = [f.image.astype(np.int16) for f in source]
        assert source.info.interlaced
    assert len(images) == N
    steps = [np.abs(a - b).mean() for a, b in zip(images, images[1:])]
    assert min(steps) > 0  # no byte-identical frames
    assert np.abs(images[0] - frames[0]).mean() < 8  # the picture, not garbage
    result = run("detect", path, "-o", tmp_path / "o", "-q", "--no-video")
    assert result.exit_code == 0, result.output
    assert summary_of(tmp_path / "o" / "i")["status"] == "complete"


@pytest.mark.parametrize("codec", ["libx264", "mpeg4"])
def test_damaged_start_processes_the_decodable_frames(tmp_path, codec):
    many = [fr.image for fr in scene("pan", ("smooth",), frames=90)]
    path = encode(tmp_path / "d.mp4", many, codec, options={"g": "15"})
    corrupt(path, 0.0, 0.25)
    result = run("detect", path, "-o", tmp_path / "o", "--no-video")
    assert result.exit_code == 0, result.output
    summary = summary_of(tmp_path / "o" / "d")
    assert summary["status"] == "partial"
    assert summary["decode_errors"] > 0
    assert 30 <= summary["totals"]["frames"] < 90
    assert "damaged" in result.output


def test_non_utf8_file_name_is_processed(tmp_path, frames):
    name = os.fsdecode(b"cl\xffip.mp4")
    path = encode(tmp_path / name, frames[:12])
    other = encode(tmp_path / "other.mp4", frames[:12])
    result = run("detect", path, other, "-o", tmp_path / "o", "--no-video")
    assert result.exit_code == 0, result.output
    assert "Traceback" not in result.output
    summary = summary_of(tmp_path / "o" / os.fsdecode(b"cl\xffip"))
    assert summary["status"] == "complete" and "cl\\xffip.mp4" in summary["input"]["path"]
    assert summary_of(tmp_path / "o" / "other")["totals"]["frames"] == 12
    events = (tmp_path / "o" / "events.csv").read_text(encoding="utf-8")
    assert "cl\\xffip.mp4" in events


@pytest.mark.parametrize("real_fps", [10000, 30])
def test_fps_header_of_10000_times_come_from_pts(tmp_path, frames, real_fps):
    """Rate 10000 in the header; the timestamps say either 10000 or 30 fps."""
    step = 10000 // real_fps
    path = encode(
        tmp_path / "f.mp4", frames, rate=10000, time_base=Fraction(1, 10000), pts_step=step
    )
    result = run("detect", path, "-o", tmp_path / "o", "-q", "--no-video")
    assert result.exit_code == 0, result.output
    times = times_of(tmp_path / "o" / "f")
    np.testing.assert_allclose(times, pts_times(path), atol=1e-6)
    np.testing.assert_allclose(np.diff(times), step / 10000, rtol=1e-3)
    fps = summary_of(tmp_path / "o" / "f")["input"]["fps"]
    assert abs(fps * np.median(np.diff(times)) - 1) < 0.05  # the summary agrees with the times


def test_pts_going_backwards_stays_complete_and_monotonic(tmp_path, frames):
    """Two MPEG-TS files concatenated: the second's timestamps start again."""
    a = encode(tmp_path / "a.ts", frames, fmt="mpegts")
    b = encode(tmp_path / "b.ts", frames, fmt="mpegts")
    both = tmp_path / "both.ts"
    both.write_bytes(a.read_bytes() + b.read_bytes())
    result = run("detect", both, "-o", tmp_path / "o", "--no-video")
    assert result.exit_code == 0, result.output
    assert "timestamps go back" in result.output
    summary = summary_of(tmp_path / "o" / "both")
    assert summary["status"] == "complete" and summary["totals"]["frames"] == 2 * N
    times = times_of(tmp_path / "o" / "both")
    assert np.all(np.diff(times) > 0)
    np.testing.assert_allclose(np.diff(times), 1 / 30, atol=1e-3)


def test_mp4_with_its_index_at_the_end_cut_short(tmp_path, frames):
    path = encode(tmp_path / "c.mp4", frames)
    data = path.read_bytes()
    assert data.find(b"moov") > data.find(b"mdat")  # the index is at the end
    path.write_bytes(data[: len(data) // 2])
    result = run("detect", path, "-o", tmp_path / "o", "-q")
    assert result.exit_code == 1
    lines = [line for line in result.output.splitlines() if line.strip()]
    assert any("index (moov atom) is missing" in line for line in lines)
    assert "Traceback" not in result.output


@pytest.mark.parametrize("text_first", [True, False])
def test_each_unreadable_file_is_named_for_its_own_fault(tmp_path, frames, text_first):
    """A cut MP4 and a text file named .mp4 both make FFmpeg say "moov atom
    not found", and FFmpeg does not log the same line twice running: each
    still gets its own message, in either order."""
    cut = encode(tmp_path / "cut.mp4", frames)
    cut.write_bytes(cut.read_bytes()[: cut.stat().st_size // 2])
    text = tmp_path / "notes.mp4"
    text.write_text("not a video\n")
    inputs = [text, cut] if text_first else [cut, text]
    result = run("detect", *inputs, "-o", tmp_path / "o", "-q")
    assert result.exit_code == 1
    lines = [line.strip() for line in result.output.splitlines() if line.startswith("  ")]
    assert f"{text}: not a video FFmpeg can read" in lines
    assert any(line.startswith(f"{cut}: the MP4 index (moov atom) is missing") for line in lines)


def test_av1_is_decoded_or_named(tmp_path, frames):
    encoder = next((c for c in ("libsvtav1", "libaom-av1") if has_encoder(c)), None)
    if encoder is None:
        pytest.skip("this PyAV build has no AV1 encoder to write the test file")
    path = encode(tmp_path / "a.mkv", frames[:12], encoder, options={"preset": "12"})
    result = run("detect", path, "-o", tmp_path / "o", "-q", "--no-video")
    if any(c in av.codecs_available for c in ("libdav1d", "av1")):
        assert result.exit_code == 0, result.output
        assert summary_of(tmp_path / "o" / "a")["totals"]["frames"] == 12
    else:
        assert result.exit_code == 1 and "codec" in result.output


def test_url_is_kept_whole(tmp_path):
    url = "rtsp://127.0.0.1:9/x"
    result = run("detect", url, "-o", tmp_path / "o", "-q")
    assert result.exit_code == 1
    assert url in result.output and "no such file" not in result.output
    assert "Traceback" not in result.output


def test_http_url_is_processed(tmp_path, frames):
    import functools
    import http.server
    import threading

    encode(tmp_path / "web.ts", frames, fmt="mpegts")
    handler = functools.partial(http.server.SimpleHTTPRequestHandler, directory=str(tmp_path))
    handler.log_message = lambda *a: None
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    try:
        url = f"http://127.0.0.1:{server.server_port}/web.ts"
        result = run("detect", url, "-o", tmp_path / "o", "-q", "--no-video")
    finally:
        server.shutdown()
        server.server_close()
    assert result.exit_code == 0, result.output
    summary = summary_of(tmp_path / "o" / f"127.0.0.1_{server.server_port}_web.ts")
    assert summary["input"]["kind"] == "stream" and summary["totals"]["frames"] == N


def _cli(*args) -> list[str]:
    return [sys.executable, "-m", "motiondetect_cli.main", *args]


def test_standard_input_is_processed_as_a_stream(tmp_path, frames):
    ts = encode(tmp_path / "s.ts", frames, fmt="mpegts").read_bytes()
    done = subprocess.run(
        _cli("detect", "-", "-o", str(tmp_path / "o"), "-q"), input=ts, capture_output=True,
        timeout=120,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr.decode()
    summary = summary_of(tmp_path / "o" / "stdin")
    assert summary["status"] == "complete" and summary["input"]["kind"] == "stream"
    assert summary["totals"]["frames"] == N
    assert stream_info(tmp_path / "o" / "stdin" / "annotated.mp4")["frames"] == N


@pytest.mark.parametrize("faststart", [False, True])
def test_piped_mp4_is_read_when_its_index_comes_first(tmp_path, faststart):
    # Noise, so the file outgrows what FFmpeg buffers while probing a pipe.
    noise = np.random.default_rng(0).integers(0, 256, (N, 240, 320, 3), np.uint8)
    options = {"movflags": "+faststart"} if faststart else {}
    mp4 = encode(tmp_path / "p.mp4", noise, options={"qp": "0"}, container_options=options)
    mp4 = mp4.read_bytes()
    assert len(mp4) > 2 * int(STREAM_PROBE["probesize"])
    done = subprocess.run(
        _cli("detect", "-", "-o", str(tmp_path / "o"), "-q", "--no-video"), input=mp4,
        capture_output=True, timeout=120,
    )  # fmt: skip
    said = done.stderr.decode()
    if faststart:
        assert done.returncode == 0, said
        assert summary_of(tmp_path / "o" / "stdin")["totals"]["frames"] == N
    else:  # the index follows the frames: a pipe cannot seek back to them
        assert done.returncode == 1 and "Traceback" not in said
        assert "moov atom" in said and "faststart" in said


PRODUCER = """
import sys, time, av, numpy as np
out = av.open(sys.stdout.buffer, "w", format="mpegts")
s = out.add_stream("libx264", rate=30, options={"tune": "zerolatency"})
s.width, s.height, s.pix_fmt = 160, 128, "yuv420p"
y, x = np.mgrid[0:128, 0:160]
for i in range(3000):
    img = ((x * 3 + y * 2 + i * 4) % 256).astype(np.uint8)
    out.mux(s.encode(av.VideoFrame.from_ndarray(np.dstack([img] * 3), format="bgr24")))
    sys.stdout.buffer.flush()
    time.sleep(0.02)
"""


def test_ctrl_c_closes_a_live_stream_with_complete_outputs(tmp_path):
    producer = subprocess.Popen(
        [sys.executable, "-c", PRODUCER], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL
    )
    detect = subprocess.Popen(
        _cli("detect", "-", "-o", str(tmp_path / "o"), "-q"), stdin=producer.stdout,
        stderr=subprocess.PIPE,
    )  # fmt: skip
    producer.stdout.close()
    jsonl = tmp_path / "o" / "stdin" / "frames.jsonl"
    try:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and (not jsonl.exists() or jsonl.stat().st_size < 2000):
            time.sleep(0.1)  # frames are being processed as they arrive
        assert jsonl.exists(), "no frame was processed while the stream was live"
        detect.send_signal(signal.SIGINT)
        code = detect.wait(60)
        said = detect.stderr.read().decode()
    finally:
        for process in (producer, detect):
            process.kill()
            process.wait()
        detect.stderr.close()
    assert code == 130, said
    out = tmp_path / "o" / "stdin"
    summary = summary_of(out)
    assert summary["status"] == "stopped"
    frames = summary["totals"]["frames"]
    assert 0 < frames < 3000 and len(times_of(out)) == frames
    assert stream_info(out / "annotated.mp4")["frames"] == frames


def test_default_annotated_video_is_h264_mp4_with_faststart(tmp_path, frames):
    path = encode(tmp_path / "v.mp4", frames)
    result = run("detect", path, "-o", tmp_path / "o", "-q")
    assert result.exit_code == 0, result.output
    video = tmp_path / "o" / "v" / "annotated.mp4"
    info = stream_info(video)
    assert (info["codec"], info["pix_fmt"], info["frames"]) == ("h264", "yuv420p", N)
    data = video.read_bytes()
    assert data.find(b"moov") < data.find(b"mdat")  # plays before it has fully loaded


def test_annotated_video_keeps_variable_frame_times(tmp_path, frames):
    steps = [1000, 1000, 3000, 1000, 2000] * 4  # in 1/30000 s: 1, 3 and 2 periods
    pts = np.concatenate([[0], np.cumsum(steps)])[: len(frames) - 4]
    path = tmp_path / "vfr.mp4"
    with av.open(str(path), "w") as out:
        s = out.add_stream("libx264", rate=30)
        s.width, s.height, s.pix_fmt = frames[0].shape[1], frames[0].shape[0], "yuv420p"
        s.time_base = Fraction(1, 30000)
        for p, image in zip(pts, frames):
            frame = av.VideoFrame.from_ndarray(image, format="bgr24")
            frame.pts, frame.time_base = int(p), s.time_base
            out.mux(s.encode(frame))
        out.mux(s.encode(None))
    result = run("detect", path, "-o", tmp_path / "o", "-q")
    assert result.exit_code == 0, result.output
    np.testing.assert_allclose(pts_times(tmp_path / "o" / "vfr" / "annotated.mp4"), pts_times(path),
                               atol=2e-3)  # fmt: skip


@pytest.mark.skipif(shutil.which("chromium") is None, reason="Debian's chromium is not installed")
def test_annotated_video_plays_in_headless_chromium(tmp_path, frames):
    path = encode(tmp_path / "v.mp4", frames)
    assert run("detect", path, "-o", tmp_path / "o", "-q").exit_code == 0
    page = tmp_path / "o" / "v" / "play.html"
    page.write_text(
        "<video id=v src='annotated.mp4' muted></video><script>"
        "const v=document.getElementById('v');"
        "v.addEventListener('loadedmetadata',()=>{document.title='duration='+v.duration;});"
        "v.addEventListener('error',()=>{document.title='error='+v.error.code;});"
        "</script>"
    )
    done = subprocess.run(
        ["chromium", "--headless", "--no-sandbox", "--disable-gpu",
         "--allow-file-access-from-files", "--virtual-time-budget=10000", "--dump-dom",
         page.as_uri()],
        capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert "duration=" in done.stdout, done.stdout[-500:] + done.stderr[-500:]
    duration = float(done.stdout.split("duration=")[1].split("<")[0])
    assert abs(duration - N / 30) < 0.1
