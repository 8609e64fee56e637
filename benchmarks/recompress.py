"""The shared clips as a phone or a website would deliver them: through H.264.

Each DAVIS clip and each of UCSD's moving-camera clips is encoded with
libx264 at a constant rate factor (``--crf``; 23 is x264's default, 30-35 is
streaming quality, with blocking on plain ground and smeared texture), decoded
again and written into ``OUT`` as near-lossless JPEGs under the same names,
with the ground truth linked, not copied. The frames never leave this machine::

    python benchmarks/recompress.py /tmp/crf32 --crf 32
    MOTIONDETECT_DATA=/tmp/crf32 python benchmarks/sweep.py davis,ucsd '{"default": {}}'
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import av
import cv2
import numpy as np
from subsample import moving_clips, numbered


def _through_h264(frames: list[Path], crf: int, tmp: Path) -> list[np.ndarray]:
    """The frames encoded at ``crf`` and decoded again (even sizes, as yuv420p needs)."""
    h, w = cv2.imread(str(frames[0])).shape[:2]
    h, w = h - h % 2, w - w % 2
    with av.open(str(tmp), "w") as out:
        stream = out.add_stream("libx264", rate=30, options={"crf": str(crf)})
        stream.width, stream.height, stream.pix_fmt = w, h, "yuv420p"
        for path in frames:
            image = np.ascontiguousarray(cv2.imread(str(path))[:h, :w])
            out.mux(stream.encode(av.VideoFrame.from_ndarray(image, format="bgr24")))
        out.mux(stream.encode(None))
    with av.open(str(tmp)) as video:
        return [frame.to_ndarray(format="bgr24") for frame in video.decode(video=0)]


def recompress(images: Path, truth: Path, target: Path, crf: int, tmp: Path) -> None:
    frames = numbered(images, ".jpg")
    decoded = _through_h264(frames, crf, tmp)
    if len(decoded) != len(frames):
        raise SystemExit(f"{images}: {len(frames)} frames in, {len(decoded)} decoded")
    (target / images.name).mkdir(parents=True, exist_ok=True)
    for path, image in zip(frames, decoded):
        cv2.imwrite(str(target / images.name / path.name), image, [cv2.IMWRITE_JPEG_QUALITY, 99])
    link = target / truth.name
    if not link.exists():
        link.symlink_to(truth.resolve())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path)
    parser.add_argument("--crf", type=int, default=32)
    args = parser.parse_args()
    if not 0 <= args.crf <= 51:
        parser.error("--crf must be 0-51")
    clips = moving_clips()
    with tempfile.TemporaryDirectory() as tmp:
        for images, truth, group in clips:
            target = args.out / group / images.parent.name
            recompress(images, truth, target, args.crf, Path(tmp) / "clip.mp4")
    print(f"{len(clips)} clips through H.264 at CRF {args.crf} in {args.out}")


if __name__ == "__main__":
    main()
