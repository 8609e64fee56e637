"""A burnt-in caption on a long real clip: how often it is flagged.

``woman.mp4`` (479 frames, a pan) is run as shipped and with the caption of
``benchmarks/degrade.py --overlay`` burnt into every frame, with the
screen-fixed test on (the default) and off (``[track] overlay_frames = 0``).
Printed per run: regions reaching into the caption's band (the bottom 12 %
of the frame), per frame and per 60-frame stretch, and regions elsewhere::

    python benchmarks/overlay.py
"""

from __future__ import annotations

from common import SHARED_DATA, single_thread
from degrade import caption

from motiondetect.detection.detector import MotionDetector
from motiondetect.detection.objects import TrackConfig
from motiondetect.io.video import open_source

BAND = 0.88  # the caption's band: below this share of the frame's height
STRETCH = 60  # frames per count of the timeline


def count(clip, captioned: bool, frames: int) -> tuple[list[int], int, int]:
    """(regions in the band per stretch, in the band, elsewhere) over the clip."""
    md = MotionDetector("both", TrackConfig(overlay_frames=frames))
    stretches: list[int] = []
    band = elsewhere = 0
    with open_source(clip) as source:
        for frame in source:
            image = caption(frame.image, frame.index) if captioned else frame.image
            result = md.process(image, frame.index, frame.time_s)
            low = sum(r.bbox[1] + r.bbox[3] > BAND * image.shape[0] for r in result.regions)
            if frame.index % STRETCH == 0:
                stretches.append(0)
            stretches[-1] += low
            band, elsewhere = band + low, elsewhere + len(result.regions) - low
    return stretches, band, elsewhere


def main() -> None:
    single_thread()
    clip = SHARED_DATA / "woman" / "woman.mp4"
    if not clip.exists():
        raise SystemExit(f"{clip} not found (set MOTIONDETECT_DATA)")
    frames = TrackConfig().overlay_frames
    for label, captioned, fixed in (
        ("as shipped", False, frames),
        ("caption, test off", True, 0),
        (f"caption, test on ({frames} frames)", True, frames),
    ):
        stretches, band, elsewhere = count(clip, captioned, fixed)
        print(f"{label:32s} band {band:4d}  elsewhere {elsewhere:4d}  per {STRETCH}: {stretches}")


if __name__ == "__main__":
    main()
