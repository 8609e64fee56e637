"""End-to-end throughput, memory and batch scaling (issue 7).

    python benchmarks/throughput.py                 # speed, 512x512 and 1920x1080
    python benchmarks/throughput.py --memory        # peak RSS, long vs short 1080p video
    python benchmarks/throughput.py --batch         # --jobs 2 against --jobs 1
    python benchmarks/throughput.py --encode        # writing the annotated video, per preset
    python benchmarks/throughput.py --ahead         # measuring ahead on a 2nd thread vs serial
    python benchmarks/throughput.py --real          # whole processes on real clips, MOG2, dvr-scan
    python benchmarks/throughput.py --sizes --frames 150   # the same from 512 px to 4K

Speed: ``detect`` end to end (decode included) in several variants, and in
the same run on the same file decode-only and OpenCV MOG2 per frame. Each
variant runs once with one thread (``cv2.setNumThreads(1)``,
``OMP_NUM_THREADS=1``) and once with OpenCV's default threads.
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import cv2

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from common import SHARED_DATA, decode_only, make_pan_clip, mog2_on, on_frames, on_grey  # noqa: E402
from peers import DenseResidual  # noqa: E402

from motiondetect.app.inputs import InputJob  # noqa: E402
from motiondetect.app.process import process_input  # noqa: E402
from motiondetect.app.settings import make_settings  # noqa: E402
from motiondetect.io.video import open_source  # noqa: E402
from motiondetect.measurement.dense_flow import DenseFlow  # noqa: E402
from motiondetect.measurement.flow_config import DenseFlowConfig  # noqa: E402
from motiondetect.measurement.normal_flow import NormalFlowPipeline  # noqa: E402

VARIANTS = {
    "detect both, reports, no video": dict(detector="both", video=False, timeline=False),
    "detect both, reports + annotated H.264 mp4": dict(
        detector="both", video=True, video_format="mp4", timeline=False
    ),
    "detect both, reports + annotated VP8 webm": dict(
        detector="both", video=True, video_format="webm", timeline=False
    ),
    "detect both --measure normal, no video": dict(
        detector="both", measure="normal", video=False, timeline=False
    ),
    "detect both --frame-skip 1, no video": dict(frame_skip=1, video=False, timeline=False),
    "detect both --frame-skip 2, no video": dict(frame_skip=2, video=False, timeline=False),
    "detect both --frame-skip 1, annotated H.264": dict(
        frame_skip=1, video=True, video_format="mp4", timeline=False
    ),
    "detect constraint-ray only": dict(detector="constraint-ray", video=False, timeline=False),
    "detect animate only": dict(detector="animate", video=False, timeline=False),
}


def decode_pyav(path: Path, colour: bool = False) -> int:
    """What the tool's own reader does: PyAV decode to the grey the
    measurement reads (the luma plane), or with ``colour`` to whole BGR arrays."""
    with open_source(path) as source:
        return sum(1 for f in source if (f.image if colour else f.grey) is not None)


def decode_pyav_swscale(path: Path) -> int:
    """PyAV decode to BGR through FFmpeg's swscale (the tool's conversion before)."""
    import av

    with av.open(str(path)) as container:
        stream = container.streams.video[0]
        stream.thread_type = "AUTO"
        return sum(1 for f in container.decode(stream) if f.to_ndarray(format="bgr24") is not None)


def encode_cost(clip: Path, tmp: Path) -> None:
    """Writing the annotated video alone: ms per frame and size, per format and x264 preset."""
    from motiondetect.io import encode as enc

    with open_source(clip) as source:
        frames = [f.image for f in source]
    h, w = frames[0].shape[:2]
    size_in = clip.stat().st_size
    print(f"\nwriting {len(frames)} frames of {w}x{h} (input {size_in / 1e6:.2f} MB):")
    presets = ["ultrafast", "superfast", "veryfast", "faster", "medium"]
    default = dict(enc.FORMATS[".mp4"][2])
    try:
        for suffix, preset in [(".mp4", p) for p in presets] + [(".webm", None), (".mkv", None)]:
            if preset is not None:
                enc.FORMATS[".mp4"][2]["preset"] = preset
            out = tmp / f"enc{suffix}"
            t = time.perf_counter()
            with enc.VideoSink(out, 30.0, (w, h)) as sink:
                for f in frames:
                    sink.write(f)
            ms = 1000 * (time.perf_counter() - t) / len(frames)
            label = f"{suffix[1:]} {preset or ''}".strip()
            print(f"  {label:18s} {ms:6.2f} ms/frame  {out.stat().st_size / 1e6:6.2f} MB")
    finally:
        enc.FORMATS[".mp4"][2].update(default)


def run_detect(path: Path, out: Path, **options) -> int:
    settings = make_settings({"output": out, "overwrite": True, **options})
    result = process_input(InputJob(path, path.stem), settings)
    assert result.status == "done", result.message
    return result.summary["totals"]["frames"]


def best_rate(run, repeat: int) -> float:
    """Frames per second of the fastest of ``repeat`` calls of ``run`` (which returns frames)."""
    times, frames = [], 0
    for _ in range(repeat):
        start = time.perf_counter()
        frames = run()
        times.append(time.perf_counter() - start)
    return frames / min(times)


def speed(clip: Path, tmp: Path, repeat: int) -> list[tuple[str, float]]:
    rows = []

    def best(fn) -> float:
        return best_rate(fn, repeat)

    rows.append(("decode only, OpenCV", best(lambda: decode_only(clip))))
    rows.append(("decode only, PyAV to grey (the tool)", best(lambda: decode_pyav(clip))))
    rows.append(("decode only, PyAV, to BGR by OpenCV", best(lambda: decode_pyav(clip, True))))
    rows.append(("decode only, PyAV, BGR by swscale", best(lambda: decode_pyav_swscale(clip))))
    rows.append(("OpenCV MOG2 (decode + apply)", best(lambda: mog2_on(clip))))
    # What judging builds on: the paper's stages, or the tool's flow (DIS and
    # the check's), and the forward flow alone: the least the velocity path needs.
    forward = DenseFlowConfig(check_preset="off")
    for name, measurement in (
        ("stage pipeline only (decode + stages)", NormalFlowPipeline),
        ("flow only (decode + the tool's DIS)", DenseFlow),
        ("forward flow alone (no check's flow)", lambda: DenseFlow(forward)),
    ):
        rows.append((name, best(lambda m=measurement: on_grey(clip, m().process))))
    peer = "dense residual peer (issue 13's 5 steps)"
    rows.append((peer, best(lambda: on_frames(clip, DenseResidual()))))
    for name, options in VARIANTS.items():
        rows.append((name, best(lambda o=options: run_detect(clip, tmp / "out", **o))))
    return rows


def print_rows(title: str, rows: list[tuple[str, float]]) -> None:
    mog = dict(rows)["OpenCV MOG2 (decode + apply)"]
    print(f"\n{title}")
    print(f"  {'':42s} {'frames/s':>9s} {'x MOG2':>7s} {'x 30 Hz':>8s}")
    for name, fps in rows:
        print(f"  {name:42s} {fps:9.1f} {fps / mog:7.2f} {fps / 30:8.1f}")


def memory(tmp: Path, long_s: float, short_s: float) -> None:
    """Peak RSS of detect on a long and a short 1080p video, in fresh processes."""
    code = (
        "import resource,sys;from pathlib import Path;"
        "from motiondetect.app.inputs import InputJob;"
        "from motiondetect.app.process import process_input;"
        "from motiondetect.app.settings import make_settings;"
        "p=Path(sys.argv[1]);s=make_settings({'output':sys.argv[2],'overwrite':True});"
        "r=process_input(InputJob(p,p.stem),s);assert r.status=='done',r.message;"
        "print(r.summary['totals']['frames'],resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)"
    )
    results = {}
    for label, seconds in (("short", short_s), ("long", long_s)):
        clip = make_pan_clip(tmp / f"{label}.mp4", (1920, 1080), int(30 * seconds), speed_px=2.0)
        proc = subprocess.run(
            [sys.executable, "-c", code, str(clip), str(tmp / label)],
            capture_output=True,
            text=True,
            check=True,
        )
        frames, rss_kb = proc.stdout.split()
        results[label] = (int(frames), int(rss_kb) / 1024)
        clip.unlink()
    (fs, rs), (fl, rl) = results["short"], results["long"]
    print("\npeak RSS, 1080p, detect with annotated video and reports:")
    print(f"  short: {fs} frames ({short_s:.0f} s): {rs:.0f} MB")
    print(f"  long:  {fl} frames ({long_s:.0f} s): {rl:.0f} MB")
    print(f"  ratio long/short: {rl / rs:.3f}")


def batch(tmp: Path, videos: int, frames: int) -> None:
    folder = tmp / "batch"
    folder.mkdir()
    for i in range(videos):
        make_pan_clip(folder / f"v{i}.mp4", (512, 512), frames, speed_px=2.0 + 0.5 * i)
    times = {}
    variants = {
        "--jobs 1": ["--jobs", "1"],
        "--jobs 2": ["--jobs", "2"],
        "--scheduler local (2 workers)": ["--jobs", "2", "--scheduler", "local"],
    }
    for label, extra in variants.items():
        out = tmp / label.split()[0].strip("-") / str(len(times))
        t = time.perf_counter()
        subprocess.run(
            [sys.executable, "-m", "motiondetect_cli.main", "detect", str(folder), "-o",
             str(out), "-q", "--no-video", *extra],
            check=True,
        )  # fmt: skip
        times[label] = time.perf_counter() - t
    print(f"\nbatch of {videos} videos x {frames} frames (512x512):")
    for label, seconds in times.items():
        print(f"  {label:32s} {seconds:7.2f} s")
    startup = _cluster_startup_s()
    dask, jobs2 = times["--scheduler local (2 workers)"], times["--jobs 2"]
    per_input = (dask - startup - jobs2) / jobs2
    print(f"  LocalCluster start and stop alone: {startup:.2f} s (once per batch)")
    print(
        f"  Dask against --jobs 2: {100 * (dask / jobs2 - 1):+.1f} % for this batch; "
        f"{100 * per_input:+.1f} % per input once the cluster is up"
    )


def _cluster_startup_s() -> float:
    code = (
        "from dask.distributed import Client, LocalCluster\n"
        "c = LocalCluster(n_workers=2, threads_per_worker=1, dashboard_address=None)\n"
        "Client(c).close(); c.close()\n"
    )
    t = time.perf_counter()
    subprocess.run([sys.executable, "-c", code], check=True, capture_output=True)
    return time.perf_counter() - t


def real_clips(tmp: Path) -> list[Path]:
    """woman.mp4 (352x288), two 854x480 DAVIS clips (dog; motocross-bumps, where
    the plane explains under half of the samples and RANSAC runs all its draws)
    and the fox clip's phone frames (1080x1920), each folder re-encoded to
    MPEG-4, when present."""
    clips = []
    if (SHARED_DATA / "woman" / "woman.mp4").exists():
        clips.append(SHARED_DATA / "woman" / "woman.mp4")
    for folder, name in ((SHARED_DATA / "davis" / "dog" / "JPEGImages", "davis_dog.mp4"),
                         (SHARED_DATA / "davis" / "motocross-bumps" / "JPEGImages",
                          "davis_motocross-bumps.mp4"),
                         (SHARED_DATA / "fox" / "images", "fox_1080x1920.mp4")):  # fmt: skip
        frames = sorted(folder.glob("*.jpg"))
        if frames:
            clips.append(_encoded(frames, tmp / name))
    return clips


def _encoded(frames: list[Path], path: Path) -> Path:
    """Image files written as one MPEG-4 video at 30 frames/s."""
    h, w = cv2.imread(str(frames[0])).shape[:2]
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), 30.0, (w, h))
    for f in frames:
        writer.write(cv2.imread(str(f)))
    writer.release()
    return path


def whole_process(cmd: list[str]) -> float:
    t = time.perf_counter()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - t


#: Frame sizes of ``--sizes``: the issues' 512x512 clip, then what cameras record.
SIZES = ((512, 512), (1280, 720), (1920, 1080), (3840, 2160))


def whole_processes(clip: Path, tmp: Path, dvr: str | None) -> str:
    """One line: detect (and detect --frame-skip 1) against MOG2 (default
    threads) and dvr-scan -so on ``clip``, each a whole process."""
    out = tmp / "real"
    detect = [sys.executable, "-m", "motiondetect_cli.main", "detect", str(clip), "-o",
              str(out), "-q", "--no-video", "--overwrite"]  # fmt: skip
    ours = whole_process(detect)
    skip = whole_process([*detect, "--frame-skip", "1"])
    mog_code = f"import sys;sys.path.insert(0,{str(HERE)!r});from common import mog2_on;"
    mog = whole_process([sys.executable, "-c", mog_code + f"mog2_on({str(clip)!r})"])
    line = f"  {clip.name}: motiondetect {ours:.2f} s, MOG2 {mog:.2f} s ({mog / ours:.2f}x)"
    scan = whole_process([dvr, "-i", str(clip), "-so", "-q"]) if dvr else None
    line += f", dvr-scan -so {scan:.2f} s ({scan / ours:.2f}x)" if scan else ", no dvr-scan"
    line += f"; --frame-skip 1 {skip:.2f} s ({mog / skip:.2f}x MOG2"
    return line + (f", {scan / skip:.2f}x dvr-scan)" if scan else ")")


def real(tmp: Path) -> None:
    """Whole processes on real clips (:func:`whole_processes`)."""
    dvr = shutil.which("dvr-scan")
    for clip in real_clips(tmp):
        print(whole_processes(clip, tmp, dvr))


def sizes(tmp: Path, frames: int) -> None:
    """Whole processes on the synthetic pan at each of :data:`SIZES`. detect
    works at 320 px whatever the input, where MOG2 and dvr-scan work on
    every pixel, so the ratios grow with the frame."""
    dvr = shutil.which("dvr-scan")
    for w, h in SIZES:
        print(whole_processes(make_pan_clip(tmp / f"pan{w}x{h}.mp4", (w, h), frames), tmp, dvr))


def ahead(clip: Path, tmp: Path, repeat: int) -> None:
    """Default threads: detect with the next frame measured on a second thread
    (``MotionDetector.stream``) against the serial loop, and MOG2, same run."""
    from motiondetect.detection.detector import MotionDetector

    threaded = MotionDetector.stream

    def serial(self, frames):
        for f in frames:
            yield f, self.process(f.image, f.index, f.time_s)

    print(f"{clip.name}, default threads (cv2 threads = {cv2.getNumThreads()}), frames/s:")
    for _ in range(repeat):
        t = time.perf_counter()
        mog = mog2_on(clip) / (time.perf_counter() - t)
        line = f"  MOG2 {mog:.1f}"
        for label, stream in (("serial", serial), ("ahead", threaded)):
            MotionDetector.stream = stream
            try:
                for video in (False, True):
                    t = time.perf_counter()
                    n = run_detect(clip, tmp / "ahead", video=video, timeline=False)
                    fps = n / (time.perf_counter() - t)
                    line += f" | {label}{', H.264' if video else ''} {fps:.1f} ({fps / mog:.2f}x)"
            finally:
                MotionDetector.stream = threaded
        print(line)


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--frames", type=int, default=300)
    parser.add_argument("--repeat", type=int, default=2)
    parser.add_argument("--memory", action="store_true")
    parser.add_argument("--long-s", type=float, default=600.0)
    parser.add_argument("--short-s", type=float, default=10.0)
    parser.add_argument("--batch", action="store_true")
    parser.add_argument("--videos", type=int, default=4, help="inputs of the --batch run")
    parser.add_argument("--real", action="store_true", help="whole processes on real clips")
    parser.add_argument("--sizes", action="store_true", help="whole processes, 512 px to 4K")
    parser.add_argument("--quick", action="store_true", help="512x512 only")
    parser.add_argument("--encode", action="store_true", help="video writing cost per preset")
    parser.add_argument("--ahead", action="store_true", help="measuring ahead against serial")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        if args.memory:
            memory(tmp, args.long_s, args.short_s)
            return
        if args.batch:
            batch(tmp, videos=args.videos, frames=args.frames)
            return
        if args.real:
            real(tmp)
            return
        if args.sizes:
            sizes(tmp, args.frames)
            return
        if args.ahead:
            clips = [make_pan_clip(tmp / "clip512.mp4", (512, 512), args.frames)]
            for clip in clips + real_clips(tmp)[:1]:
                ahead(clip, tmp, args.repeat)
            return
        if args.encode:
            encode_cost(make_pan_clip(tmp / "clip512.mp4", (512, 512), args.frames), tmp)
            return
        for size in ((512, 512),) if args.quick else ((512, 512), (1920, 1080)):
            clip = make_pan_clip(tmp / f"clip{size[0]}.mp4", size, args.frames)
            for threads in ("one thread", "default threads"):
                if threads == "one thread":
                    os.environ["OMP_NUM_THREADS"] = "1"
                    cv2.setNumThreads(1)
                else:
                    cv2.setNumThreads(-1)
                rows = speed(clip, tmp, args.repeat)
                print_rows(
                    f"{size[0]}x{size[1]}, {args.frames} frames, {threads} "
                    f"(cv2 threads = {cv2.getNumThreads()})",
                    rows,
                )


if __name__ == "__main__":
    main()
