"""One real clip in the pixel formats and codecs cameras and editors write.

    python benchmarks/formats.py            # DAVIS dog's first 30 frames
    python benchmarks/formats.py --keep /tmp/formats

Each encoding (10-bit HEVC as phones record HDR, ProRes 4444 with alpha,
FFV1 16-bit grey and 48-bit RGB, VP9 4:4:4, MJPEG, MPEG-2 TS, 10-bit AV1,
odd-sized H.264 4:4:4, H.264 4:2:2 10-bit, DNxHD, grey H.264) is run through
``motiondetect detect`` as a whole process. Each must process (exit 0, the
annotated video written) and find the dog as the others do: printed per
format, the exit code, the first event and its peak score. Encoders this
PyAV build lacks are skipped.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
from pathlib import Path

import av
import cv2
from common import SHARED_DATA

#: (file, encoder, pixel format, frame size or None for the clip's, encoder options)
FORMATS = (
    ("hevc10.mov", "libx265", "yuv420p10le", None, {}),
    ("prores4444a.mov", "prores_ks", "yuva444p10le", None, {"profile": "4"}),
    ("ffv1gray16.mkv", "ffv1", "gray16le", None, {}),
    ("ffv1rgb48.mkv", "ffv1", "rgb48le", None, {}),
    ("vp9_444.webm", "libvpx-vp9", "yuv444p", None, {}),
    ("mjpeg.avi", "mjpeg", "yuvj422p", None, {}),
    ("mpeg2.ts", "mpeg2video", "yuv420p", None, {}),
    ("av1_10.mp4", "libsvtav1", "yuv420p10le", None, {}),
    ("h264_444_odd.mp4", "libx264", "yuv444p", (853, 479), {}),
    ("h264_422_10.mkv", "libx264", "yuv422p10le", None, {}),
    ("dnxhd.mov", "dnxhd", "yuv422p", (1920, 1080), {"b": "36M"}),
    ("gray8_h264.mp4", "libx264", "gray", None, {}),
)


def encoded(images: list, path: Path, codec: str, pix_fmt: str, size, options: dict) -> Path:
    """``images`` (BGR) written at 25 frames/s by ``codec`` in ``pix_fmt``."""
    h, w = images[0].shape[:2]
    w, h = size or (w, h)
    with av.open(str(path), "w") as out:
        stream = out.add_stream(codec, rate=25)
        stream.width, stream.height, stream.pix_fmt = w, h, pix_fmt
        if "b" in options:
            stream.bit_rate = int(options["b"].rstrip("M")) * 1_000_000
        stream.options = {k: v for k, v in options.items() if k != "b"}
        for image in images:
            frame = av.VideoFrame.from_ndarray(cv2.resize(image, (w, h)), format="bgr24")
            out.mux(stream.encode(frame.reformat(format=pix_fmt)))
        out.mux(stream.encode(None))
    return path


def first_event(path: Path, out: Path) -> str:
    """``detect``'s exit code and first event line, as a whole process."""
    cmd = [sys.executable, "-m", "motiondetect_cli.main", "detect", str(path), "-o", str(out)]
    run = subprocess.run(cmd, capture_output=True, text=True)
    event = next((line.strip() for line in run.stdout.splitlines() if "event 1:" in line), "")
    video = any(out.glob("*/annotated.mp4"))
    return f"exit {run.returncode}, annotated video {'yes' if video else 'no'}; {event}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=30)
    parser.add_argument("--keep", type=Path, help="write the encodings here and keep them")
    args = parser.parse_args()
    frames = sorted((SHARED_DATA / "davis" / "dog" / "JPEGImages").glob("*.jpg"))
    if not frames:
        sys.exit(f"no DAVIS dog frames under {SHARED_DATA}")
    images = [cv2.imread(str(f)) for f in frames[: args.frames]]
    with tempfile.TemporaryDirectory() as tmp:
        folder = args.keep or Path(tmp)
        folder.mkdir(parents=True, exist_ok=True)
        for name, codec, pix_fmt, size, options in FORMATS:
            if codec not in av.codecs_available:
                print(f"  {name:18s} skipped: no {codec} encoder in this PyAV build")
                continue
            path = encoded(images, folder / name, codec, pix_fmt, size, options)
            print(f"  {name:18s} {pix_fmt:13s} {first_event(path, folder / f'out-{name}')}")


if __name__ == "__main__":
    main()
