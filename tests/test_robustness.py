"""Interruption, resume, fuzzing, huge frames and a full disk (issue 8)."""

from __future__ import annotations

import errno
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import cv2
import numpy as np
import pytest

from motiondetect.app import process, runner
from motiondetect.app.inputs import InputJob
from motiondetect.app.process import process_input
from motiondetect.app.settings import make_settings

from .cli_outputs import check_outputs, write_video
from .scenes import scene

EXE = [sys.executable, "-m", "motiondetect_cli.main"]


@pytest.fixture(scope="module")
def frames():
    return [fr.image for fr in scene("pan", ("smooth",), frames=16)]


def test_kill_mid_run_leaves_nothing_that_looks_finished_and_resume_redoes_it(tmp_path, frames):
    long = write_video(tmp_path / "long.avi", frames * 15, "MJPG")  # 240 frames
    out = tmp_path / "out"
    proc = subprocess.Popen(
        [*EXE, "detect", str(long), "-o", str(out), "-q"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    jsonl = out / "long" / "frames.jsonl"
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        if jsonl.exists() and jsonl.read_text().count("\n") >= 20:
            break
        time.sleep(0.05)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    assert not (out / "long" / "summary.json").exists()
    assert not (out / "long" / "annotated.mp4").exists()  # only its hidden temporary
    lines = jsonl.read_text().split("\n")
    complete = [json.loads(x) for x in lines[:-1]]  # every finished frame parses
    assert [r["frame"] for r in complete] == list(range(len(complete)))
    result = subprocess.run(
        [*EXE, "detect", str(long), "-o", str(out), "-q"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert result.returncode == 0, result.stderr
    check_outputs(out / "long", 240)
    assert not [p for p in (out / "long").iterdir() if p.name.startswith(".")]


def test_seeded_fuzz_corrupted_videos_process_or_fail_cleanly(tmp_path, frames):
    """Bounded: 10 cases, each in its own process with a timeout."""
    good = write_video(tmp_path / "good.mp4", frames[:10]).read_bytes()
    rng = np.random.default_rng(1234)
    outcomes = []
    for case in range(10):
        data = bytearray(good)
        for _ in range(int(rng.integers(1, 40))):
            data[int(rng.integers(0, len(data)))] = int(rng.integers(0, 256))
        if case % 3 == 2:
            data = data[: int(rng.integers(16, len(data)))]
        path = tmp_path / f"fuzz{case}.mp4"
        path.write_bytes(bytes(data))
        proc = subprocess.run(
            [*EXE, "detect", str(path), "-o", str(tmp_path / "o"), "-q", "--no-video"],
            capture_output=True,
            text=True,
            timeout=120,
        )
        assert proc.returncode in (0, 1), proc.stderr
        assert "Traceback" not in proc.stderr
        out = tmp_path / "o" / path.stem
        if proc.returncode == 1:  # one line naming the input, and nothing that looks finished
            errors = [x for x in proc.stderr.splitlines() if path.name in x]
            assert len(errors) == 1, proc.stderr
            assert not (out / "summary.json").exists()
        else:  # processed: complete outputs whose frame count matches the summary
            summary = json.loads((out / "summary.json").read_text())
            lines = (out / "frames.jsonl").read_text().splitlines()
            assert len(lines) == summary["totals"]["frames"] >= 1
        outcomes.append(proc.returncode)
    assert set(outcomes) == {0, 1}  # the seed damages some files beyond use and not others


def test_8k_frames_are_processed_at_the_working_resolution(tmp_path):
    seq = tmp_path / "eight_k"
    seq.mkdir()
    x = np.arange(7680, dtype=np.float32)
    rows = np.cos(np.arange(4320, dtype=np.float32) / 53.0)[:, None]
    for i in range(3):  # float32 rows times a column: no 8K index grids in memory
        img = (127 + 60 * np.sin((x + 4 * i) / 37.0)[None, :] * rows).astype(np.uint8)
        cv2.imwrite(str(seq / f"{i}.png"), img)
    settings = make_settings({"output": tmp_path / "o", "video": False})
    result = process_input(InputJob(seq, "eight_k"), settings)
    assert result.status == "done", result.message
    assert result.summary["input"]["width"] == 7680
    assert result.summary["totals"]["frames"] == 3


def test_full_disk_errors_and_leaves_no_complete_looking_output(tmp_path, frames, monkeypatch):
    clip = write_video(tmp_path / "v.mp4", frames[:8])
    real = process.write_json

    def full(fp, doc):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(process, "write_json", full)
    settings = make_settings({"output": tmp_path / "o", "video": False})
    result = process_input(InputJob(clip, "v"), settings)
    assert result.status == "failed"
    assert "No space left on device" in result.message
    assert not (tmp_path / "o" / "v" / "summary.json").exists()
    assert not [p for p in (tmp_path / "o" / "v").iterdir() if p.name.startswith(".")]
    monkeypatch.setattr(process, "write_json", real)
    assert process_input(InputJob(clip, "v"), settings).status == "done"


@pytest.mark.skipif(shutil.which("mount") is None or os.geteuid() != 0, reason="needs root")
def test_really_full_disk(tmp_path, frames):
    """A 1 MB tmpfs: the annotated video cannot fit."""
    mnt = tmp_path / "small"
    mnt.mkdir()
    if (
        subprocess.run(
            ["mount", "-t", "tmpfs", "-o", "size=1m", "tmpfs", str(mnt)], capture_output=True
        ).returncode
        != 0
    ):
        pytest.skip("cannot mount a tmpfs here")
    try:
        rng = np.random.default_rng(0)  # noise: no codec makes this small
        noisy = [rng.integers(0, 256, f.shape, np.uint8) for f in frames * 4]
        clip = write_video(tmp_path / "v.mp4", noisy)
        settings = make_settings({"output": mnt, "masks": True})
        result = process_input(InputJob(clip, "v"), settings)
        assert result.status == "failed"
        assert not (mnt / "v" / "summary.json").exists()
    finally:
        subprocess.run(["umount", str(mnt)], capture_output=True)


def test_batch_input_order_and_names_are_stable(tmp_path, frames):
    for name in ("b.mp4", "a.mp4", "a.avi"):
        write_video(tmp_path / name, frames[:3], "MJPG" if name.endswith("avi") else "mp4v")
    jobs = runner.discover_inputs([tmp_path], recursive=False)
    assert [j.name for j in jobs] == ["a.avi", "a.mp4", "b"]  # shared stems keep the suffix
    assert [Path(j.path).name for j in jobs] == ["a.avi", "a.mp4", "b.mp4"]
