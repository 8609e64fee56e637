"""Bad input gets one clear line or a processed result plus a warning (issue 8)."""

from __future__ import annotations

import json

import cv2
import numpy as np
import pytest
from click.testing import CliRunner
from motiondetect_cli.main import main

from motiondetect.io.video import open_source

from .cli_outputs import check_outputs, write_video
from .logs import warnings_logged
from .media import encode, turned_quarter
from .scenes import scene


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


@pytest.fixture(scope="module")
def frames():
    return [fr.image for fr in scene("pan", ("smooth",), frames=16)]


def one_failure(result, text):
    assert result.exit_code == 1
    assert text in result.output
    assert "Traceback" not in result.output


def _read_with_warnings(folder):
    """(the frames read from ``folder``, whether it was partial, the warnings logged)."""
    with warnings_logged() as messages, open_source(folder) as source:
        read = list(source)
        partial = source.partial
    return read, partial, messages


def test_empty_file(tmp_path):
    (tmp_path / "empty.mp4").write_bytes(b"")
    one_failure(run("detect", tmp_path / "empty.mp4", "-o", tmp_path / "o", "-q"), "file is empty")


@pytest.mark.parametrize("content", [b"hello, not a video\n" * 50, None])
def test_text_or_image_named_mp4(tmp_path, content, frames):
    path = tmp_path / "fake.mp4"
    if content is None:
        ok, buf = cv2.imencode(".png", frames[0])
        content = buf.tobytes()
    path.write_bytes(content)
    result = run("detect", path, "-o", tmp_path / "o", "-q")
    assert result.exit_code == 1 and "fake.mp4" in result.output
    assert "Traceback" not in result.output


def write_gif(path, frames):
    return encode(path, frames, "gif", rate=10, pix_fmt="rgb8")


def test_an_animated_gif_is_a_video_and_a_one_frame_gif_a_still_image(tmp_path, frames):
    result = run("detect", write_gif(tmp_path / "anim.gif", frames), "-o", tmp_path / "o", "-q")
    assert result.exit_code == 0, result.output
    check_outputs(tmp_path / "o" / "anim", len(frames))
    result = run("detect", write_gif(tmp_path / "still.gif", frames[:1]), "-o", tmp_path / "o")
    one_failure(result, "still.gif: a still image, not a video")
    batch = tmp_path / "batch"
    batch.mkdir()
    write_gif(batch / "anim.gif", frames)
    write_gif(batch / "icon.gif", frames[:1])  # an image among the videos: skipped
    result = run("detect", batch, "-o", tmp_path / "b", "-q")
    assert result.exit_code == 0, result.output
    assert sorted(p.name for p in (tmp_path / "b").iterdir() if p.is_dir()) == ["anim"]


def test_truncated_video_is_processed_and_marked_partial(tmp_path, frames):
    full = write_video(tmp_path / "full.avi", frames, "MJPG")
    data = full.read_bytes()
    cut = tmp_path / "cut.avi"
    cut.write_bytes(data[: len(data) // 2])
    result = run("detect", cut, "-o", tmp_path / "o", "--no-video")
    assert result.exit_code == 0, result.output
    summary = json.loads((tmp_path / "o" / "cut" / "summary.json").read_text())
    assert summary["status"] == "partial"
    assert 2 <= summary["totals"]["frames"] < 16
    assert "truncated" in result.output or "stopped" in result.output


def test_one_frame_video(tmp_path, frames):
    path = write_video(tmp_path / "one.mp4", frames[:1])
    result = run("detect", path, "-o", tmp_path / "o", "-q")
    assert result.exit_code == 0, result.output
    check_outputs(tmp_path / "o" / "one", 1)


def test_frames_smaller_than_64(tmp_path, frames):
    path = write_video(tmp_path / "tiny.mp4", [cv2.resize(f, (48, 40)) for f in frames[:4]])
    one_failure(run("detect", path, "-o", tmp_path / "o", "-q"), "at least 64x64")


@pytest.mark.parametrize("size", [(65, 67), (333, 97)])
def test_odd_frame_sizes(tmp_path, frames, size):
    seq = tmp_path / "seq"
    seq.mkdir()
    for i, f in enumerate(frames[:6]):
        cv2.imwrite(str(seq / f"{i:03d}.png"), cv2.resize(f, size))
    assert run("detect", seq, "-o", tmp_path / "o", "-q").exit_code == 0
    check_outputs(tmp_path / "o" / "seq", 6)


@pytest.mark.parametrize("kind", ["grey16", "grey8"])
def test_16_bit_and_grey_sequences(tmp_path, frames, kind):
    seq = tmp_path / kind
    seq.mkdir()
    for i, f in enumerate(frames[:6]):
        g = cv2.cvtColor(f, cv2.COLOR_BGR2GRAY)
        cv2.imwrite(str(seq / f"{i:03d}.png"), g.astype(np.uint16) * 257 if kind == "grey16" else g)
    assert cv2.imread(str(seq / "000.png"), cv2.IMREAD_UNCHANGED).dtype == (
        np.uint16 if kind == "grey16" else np.uint8
    )
    assert run("detect", seq, "-o", tmp_path / "o", "-q").exit_code == 0
    check_outputs(tmp_path / "o" / kind, 6)


@pytest.mark.parametrize("suffix", [".pgm", ".ppm", ".webp"])
def test_netpbm_and_webp_frames_folders(tmp_path, frames, suffix):
    """PGM/PPM dumps (robot and lab cameras) and WebP frames are frames
    folders like JPEG and PNG ones; before, their files were not images and
    the folder was 'a directory with 0 images'."""
    seq = tmp_path / suffix[1:]
    seq.mkdir()
    for i, f in enumerate(frames[:6]):
        image = cv2.cvtColor(f, cv2.COLOR_BGR2GRAY) if suffix == ".pgm" else f
        assert cv2.imwrite(str(seq / f"{i:04d}{suffix}"), image)
    result = run("detect", seq, "-o", tmp_path / "o", "-q")
    assert result.exit_code == 0, result.output
    check_outputs(tmp_path / "o" / suffix[1:], 6)


def test_gap_and_stray_file_in_frames_folder(tmp_path, frames):
    seq = tmp_path / "seq"
    seq.mkdir()
    for n in (1, 2, 3, 7, 8, 10):
        cv2.imwrite(str(seq / f"frame_{n}.jpg"), frames[n])
    (seq / "notes.txt").write_text("stray")
    frames_read, _, messages = _read_with_warnings(seq)
    numbers = [f.number for f in frames_read]
    assert any("non-image" in m and "notes.txt" in m for m in messages), messages
    assert any("2 gaps" in m for m in messages), messages
    assert numbers == [1, 2, 3, 7, 8, 10]  # numeric, not lexicographic, order
    # the gaps are gaps in time (frames left out), at the assumed 30 fps
    assert [round(f.time_s * 30, 6) for f in frames_read] == [0, 1, 2, 6, 7, 9]
    result = run("detect", seq, "-o", tmp_path / "o", "-q")
    assert result.exit_code == 0
    check_outputs(tmp_path / "o" / "seq", 6)


@pytest.mark.parametrize("suffix", [".jpg", ".png"])  # FFmpeg's JPEG decoder, OpenCV's
def test_unreadable_frame_files_leave_gaps_and_the_rest_keep_their_places(tmp_path, frames, suffix):
    """A frames folder whose first file (or any other) is unreadable is
    processed as partial, not refused; every frame read keeps the index and
    time of its place among the files, so the masks stay numbered as the
    files (and as ground truth numbered like them)."""
    seq = tmp_path / "seq"
    seq.mkdir()
    for i, f in enumerate(frames[:8]):
        cv2.imwrite(str(seq / f"{i:05d}{suffix}"), f)
    (seq / f"00000{suffix}").write_bytes(b"")  # the first file: empty
    (seq / f"00004{suffix}").write_bytes(b"not an image\n" * 20)
    with open_source(seq) as source:
        read = list(source)
        assert source.partial
    assert [f.index for f in read] == [f.number for f in read] == [1, 2, 3, 5, 6, 7]
    assert [round(f.time_s * 30, 6) for f in read] == [1, 2, 3, 5, 6, 7]
    result = run("detect", seq, "-o", tmp_path / "o", "-q", "--masks")
    assert result.exit_code == 0, result.output
    out = tmp_path / "o" / "seq"
    assert json.loads((out / "summary.json").read_text())["status"] == "partial"
    records = [json.loads(line) for line in (out / "frames.jsonl").read_text().splitlines()]
    assert [r["frame"] for r in records] == [1, 2, 3, 5, 6, 7]
    assert [round(r["time_s"] * 30, 2) for r in records] == [1, 2, 3, 5, 6, 7]
    masks = sorted(p.name for p in (out / "masks").iterdir())
    assert masks == [f"{n:06d}.png" for n in (1, 2, 3, 5, 6, 7)]


def test_a_preview_or_a_first_frame_of_another_size_does_not_set_the_frames_size(tmp_path, frames):
    """An unnumbered image among numbered frames (a preview, a cover) is no
    frame: skipped with a warning, the sequence as it was. A numbered frame of
    another size is skipped even when it comes first: the frames' size is the
    one most of the first readable files share. Before, either set the size
    and every real frame was skipped as differently sized."""
    seq = tmp_path / "seq"
    seq.mkdir()
    for i, f in enumerate(frames[:6]):
        cv2.imwrite(str(seq / f"{i:03d}.png"), f)
    cv2.imwrite(str(seq / "preview.png"), cv2.resize(frames[0], None, fx=0.5, fy=0.5))
    cv2.imwrite(str(seq / "cover.jpg"), frames[0])
    read, partial, warnings = _read_with_warnings(seq)
    assert [f.index for f in read] == [f.number for f in read] == list(range(6))
    assert not partial
    assert any("without a frame number" in m and "cover.jpg" in m for m in warnings), warnings
    assert not any("differently sized" in m for m in warnings), warnings
    (seq / "preview.png").unlink()
    (seq / "cover.jpg").unlink()
    cv2.imwrite(str(seq / "000.png"), cv2.resize(frames[0], None, fx=2, fy=2))
    read, partial, warnings = _read_with_warnings(seq)
    assert [f.index for f in read] == [1, 2, 3, 4, 5]
    assert {f.image.shape for f in read} == {frames[0].shape} and partial
    assert any("000.png" in m and "differently sized" in m for m in warnings), warnings
    result = run("detect", seq, "-o", tmp_path / "o", "-q")
    assert result.exit_code == 0, result.output
    summary = json.loads((tmp_path / "o" / "seq" / "summary.json").read_text())
    assert (summary["input"]["width"], summary["input"]["height"]) == frames[0].shape[1::-1]


def test_repeated_frame_numbers_are_named_in_a_warning(tmp_path, frames):
    seq = tmp_path / "seq"
    seq.mkdir()
    for i, f in enumerate(frames[:3]):  # two cameras' frames, say, in one folder
        cv2.imwrite(str(seq / f"cam1_{i:03d}.png"), f)
        cv2.imwrite(str(seq / f"cam2_{i:03d}.png"), f)
    read, _, warnings = _read_with_warnings(seq)
    assert [f.number for f in read] == [0, 0, 1, 1, 2, 2]
    assert any("3 frame numbers repeat" in m and "cam2_000.png" in m for m in warnings), warnings


def test_a_frames_folder_without_numbers_is_taken_by_name(tmp_path, frames):
    seq = tmp_path / "seq"
    seq.mkdir()
    for name, f in zip(("a", "b", "c"), frames[:3], strict=True):
        cv2.imwrite(str(seq / f"{name}.png"), f)
    read, partial, warnings = _read_with_warnings(seq)
    assert len(read) == 3 and not partial and warnings == []
    assert [int(f.image.mean()) for f in read] == [int(f.mean()) for f in frames[:3]]


def test_a_frames_folder_with_no_readable_file_is_one_line(tmp_path):
    seq = tmp_path / "seq"
    seq.mkdir()
    for i in range(3):
        (seq / f"{i:03d}.png").write_bytes(b"not a png")
    one_failure(run("detect", seq, "-o", tmp_path / "o", "-q"), "no readable image frames")


def test_unicode_and_spaces_in_paths(tmp_path, frames):
    folder = tmp_path / "vidéos d'été"
    folder.mkdir()
    path = write_video(folder / "plage à midi.mp4", frames[:6])
    out = tmp_path / "sortie ü"
    assert run("detect", path, "-o", out, "-q").exit_code == 0
    check_outputs(out / "plage à midi", 6)


def test_output_never_inside_an_input(tmp_path, frames):
    seq = tmp_path / "seq"
    seq.mkdir()
    for i, f in enumerate(frames[:4]):
        cv2.imwrite(str(seq / f"{i}.png"), f)
    before = sorted(p.name for p in seq.iterdir())
    result = run("detect", seq, "-o", seq, "-q")
    one_failure(result, "inside the input")
    assert sorted(p.name for p in seq.iterdir() if not p.name.startswith(".")) == before


def test_interrupted_output_is_not_taken_as_finished(tmp_path, frames):
    path = write_video(tmp_path / "v.mp4", frames[:8])
    out = tmp_path / "o"
    (out / "v").mkdir(parents=True)
    (out / "v" / "frames.jsonl").write_text('{"frame": 0}\n{"frame": 1, "trunc')  # a kill
    result = run("detect", path, "-o", out, "-q", "--no-video")
    assert result.exit_code == 0
    check_outputs(out / "v", 8, video=False)  # redone, not skipped
    leftovers = [p.name for p in (out / "v").iterdir() if p.name.startswith(".")]
    assert leftovers == []


def test_variable_frame_rate_times_come_from_timestamps(tmp_path, frames):
    """Irregular presentation times survive: not index / fps."""
    av = pytest.importorskip("av")
    import fractions

    path = tmp_path / "vfr.mkv"
    times_ms = [0, 33, 66, 200, 233, 500, 533, 566]
    with av.open(str(path), "w") as out:
        stream = out.add_stream("ffv1", rate=1000)
        stream.width, stream.height, stream.pix_fmt = 160 * 2, 120 * 2, "yuv420p"
        stream.time_base = fractions.Fraction(1, 1000)
        for image, t in zip(frames, times_ms):
            frame = av.VideoFrame.from_ndarray(image[..., ::-1].copy(), format="rgb24")
            frame.pts, frame.time_base = t, fractions.Fraction(1, 1000)
            for packet in stream.encode(frame):
                out.mux(packet)
        for packet in stream.encode():
            out.mux(packet)
    result = run("detect", path, "-o", tmp_path / "o", "-q", "--no-video")
    assert result.exit_code == 0, result.output
    lines = (tmp_path / "o" / "vfr" / "frames.jsonl").read_text().splitlines()
    assert [json.loads(x)["time_s"] for x in lines] == [t / 1000 for t in times_ms]


def test_rotation_metadata_is_applied_and_reported(tmp_path, frames):
    """A 90-degree display matrix in the MP4 track header (as phones write it)."""
    path = write_video(tmp_path / "upright.mp4", frames[:6])
    rotated = turned_quarter(path, tmp_path / "phone.mp4")
    result = run("detect", rotated, "-o", tmp_path / "o", "-q")
    assert result.exit_code == 0, result.output
    summary = check_outputs(tmp_path / "o" / "phone", 6)
    h, w = frames[0].shape[:2]
    assert (summary["input"]["width"], summary["input"]["height"]) == (h, w)  # portrait now
    assert summary["input"]["rotation_deg"] in (90, 270)
