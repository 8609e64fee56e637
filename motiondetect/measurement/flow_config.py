"""Settings of the 2-D velocity measurement (:mod:`.dense_flow`), and DIS's
measured reach."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import cv2

from motiondetect.config_checks import check_fields
from motiondetect.measurement import stages
from motiondetect.measurement.picture import BAR_LIMIT

#: How far DIS's coarse-to-fine search reaches from where it starts, work
#: px/frame: searching from rest, its 90th-percentile error on known
#: translations is 0.24 px at 29.5 px/frame and 3.7 px at 40.5
#: (docs/stages.md).
DIS_REACH_PX = 30.0

PRESETS = {
    "ultrafast": cv2.DISOPTICAL_FLOW_PRESET_ULTRAFAST,
    "fast": cv2.DISOPTICAL_FLOW_PRESET_FAST,
    "medium": cv2.DISOPTICAL_FLOW_PRESET_MEDIUM,
}


@dataclass(frozen=True)
class DenseFlowConfig:
    """Settings of the 2-D velocity measurement.

    Attributes
    ----------
    work_size : int
        Long side of the working resolution, px; never above the input's
        (frames are only ever reduced). Velocities are in work px/frame.
    preset : {"ultrafast", "fast", "medium"}
        DIS preset (docs/detectors.md measures each on every data set).
    descent_iterations : int or None
        Gradient-descent iterations per patch, replacing the preset's (25
        for "medium"): 8 measured as good on every data set, for less time.
    patch_stride : int
        Step between DIS patches, work px (the "medium" preset's is 3): 4
        changed no data set's pooled cell F1 by more than 0.015 and costs 23 %
        less (docs/detectors.md).
    refinement_iterations : int or None
        Variational refinement iterations, replacing the preset's (5 for
        "medium"); None keeps the preset's. Fewer are faster (3: about a
        fifth less flow time) but left DAVIS's flow noisier: lower cell F1 on
        most of its clips (docs/detectors.md), so the default keeps 5.
    check_preset : {"ultrafast", "fast", "medium", "off"}
        DIS preset of the flow measured the other way, from the previous
        frame to this one, for the forward-backward check
        (:func:`~.dense_flow.confirmed_both_ways`); "off" skips it. "ultrafast" costs
        about 1 ms a frame at 320 px and caught as many of DIS's errors as
        "fast" (docs/detectors.md).
    bar_limit : int
        Grey level (of 255) at or below which a band along a frame edge that
        has stayed dark is a black bar (FFmpeg cropdetect's 24; a band
        without detail, a blurred panel, is one too), left out of the
        measurement (:mod:`~motiondetect.measurement.picture`); 0 measures
        the whole frame.
    start_speed_px : float
        Median speed of the last field, work px/frame, above which DIS
        starts this frame's search (both ways) from that field instead of
        from rest, when the pan is steady: its median velocity changed by
        less than half its length since the field before (a jerk, a
        reversal, starts from rest). DIS's search reaches only about 30
        px/frame from where it starts (:data:`DIS_REACH_PX`); started from the
        last field, a pan that speeds up steadily is measured well beyond
        (docs/detectors.md, "Fast steady pans"). 15, half that reach: a
        pan that doubles its speed in one frame is still measured. ``inf``:
        always from rest.
    repeat_level : float
        Mean absolute difference from the last frame, grey levels at working
        size, at or below which a frame may repeat it (and then also at most
        a quarter of the usual difference between frames;
        :mod:`~motiondetect.measurement.repeats`); 0: every frame is measured.
    """

    work_size: int = 320
    preset: Literal["ultrafast", "fast", "medium"] = "medium"
    descent_iterations: int | None = 8
    patch_stride: int = 4
    refinement_iterations: int | None = None
    check_preset: Literal["ultrafast", "fast", "medium", "off"] = "ultrafast"
    bar_limit: int = BAR_LIMIT
    start_speed_px: float = 15.0
    repeat_level: float = 1.0

    def __post_init__(self) -> None:
        check_fields(
            self,
            positive=("work_size", "patch_stride"),
            non_negative=("bar_limit", "repeat_level", "start_speed_px"),
            choices={"preset": tuple(PRESETS), "check_preset": (*PRESETS, "off")},
        )
        if self.descent_iterations is not None:
            check_fields(self, positive=("descent_iterations",))
        if self.refinement_iterations is not None:
            check_fields(self, non_negative=("refinement_iterations",))
        if self.work_size < stages.MIN_FRAME_SIDE:
            raise ValueError(f"work_size must be at least 64, but got {self.work_size}")
