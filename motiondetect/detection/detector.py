"""Detectors chosen by name, and their fusion (the paper's "best of both worlds").

:class:`MotionDetector` drives the stage pipeline and the chosen detectors
for one input, frame by frame. With ``both``, the flagged cells of the two
detectors are united and regrouped into regions; each region records which
detector (or both) flagged its cells.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import cv2
import numpy as np

from motiondetect.animate.normal_footprints import AnimateConfig, AnimateDetector
from motiondetect.constraint_ray.hough import CoarseField
from motiondetect.constraint_ray.normal_filter import (
    ConstraintRayConfig,
    ConstraintRayDetector,
    DetectorOutput,
)
from motiondetect.constraint_ray.observer_motion import ObserverMotion
from motiondetect.detection.regions import Region, find_regions, regions_mask
from motiondetect.measurement.normal_flow import (
    GridGeometry,
    NormalFlowField,
    NormalFlowPipeline,
    StageConfig,
)

_GROW = np.ones((3, 3), np.uint8)

DETECTORS = {
    "constraint-ray": ("constraint-ray",),
    "animate": ("animate",),
    "both": ("constraint-ray", "animate"),
}


@dataclass(frozen=True)
class FrameResult:
    """Everything reported for one frame."""

    index: int
    time_s: float
    regions: list[Region]
    flagged: np.ndarray  # (64, 64) bool, union of the detectors
    observer: ObserverMotion | None
    coarse: CoarseField | None
    field: NormalFlowField | None
    outputs: dict[str, DetectorOutput] = field(default_factory=dict)

    @property
    def moving_fraction(self) -> float:
        return float(self.flagged.mean())

    @property
    def score(self) -> float:
        return max((r.score for r in self.regions), default=0.0)

    @property
    def warm_up(self) -> bool:
        return self.field is None


def fuse(
    outputs: dict[str, DetectorOutput], geometry: GridGeometry, min_cells: int
) -> tuple[np.ndarray, list[Region]]:
    """Union of the detectors' flagged cells, regrouped, with attribution."""
    names = list(outputs)
    if len(names) == 1:
        only = outputs[names[0]]
        return only.flagged, only.regions
    flagged = np.zeros_like(outputs[names[0]].flagged)
    strength = np.zeros(flagged.shape, np.float32)
    for out in outputs.values():
        flagged |= out.flagged
        strength = np.maximum(strength, out.strength)
    regions = find_regions(flagged, strength, geometry, min_cells=min_cells, detector="")
    fused = []
    for region in regions:
        rows, cols = region.cells[:, 0], region.cells[:, 1]
        found = tuple(n for n in names if outputs[n].flagged[rows, cols].any())
        fused.append(Region(region.bbox, region.cells, region.area_px, region.score, found))
    return flagged, fused


class MotionDetector:
    """Stage pipeline + detectors for one input.

    Parameters
    ----------
    detector : {"constraint-ray", "animate", "both"}
    stages, constraint_ray, animate : configs
    egomotion : callable, optional
        Known camera motion for the constraint ray filter.
    """

    def __init__(
        self,
        detector: str = "both",
        *,
        stages: StageConfig | None = None,
        constraint_ray: ConstraintRayConfig | None = None,
        animate: AnimateConfig | None = None,
        egomotion=None,
        persistence: int = 2,
    ) -> None:
        if persistence < 1:
            raise ValueError(f"persistence must be at least 1, but got {persistence}")
        self.persistence = persistence
        self._recent: list[np.ndarray] = []
        if detector not in DETECTORS:
            raise ValueError(f"detector must be one of {sorted(DETECTORS)}, but got {detector!r}")
        self.pipeline = NormalFlowPipeline(stages)
        self.detectors = {}
        for name in DETECTORS[detector]:
            if name == "constraint-ray":
                self.detectors[name] = ConstraintRayDetector(constraint_ray, egomotion)
            else:
                self.detectors[name] = AnimateDetector(animate)
        self.min_cells = min(
            (constraint_ray or ConstraintRayConfig()).min_cells,
            (animate or AnimateConfig()).min_cells,
        )

    def _persistent(
        self, flagged: np.ndarray, regions: list[Region]
    ) -> tuple[np.ndarray, list[Region]]:
        """Keep regions whose cells (grown by one) touched flagged cells in each
        of the previous ``persistence - 1`` frames: independent movers persist
        in place, most noise does not."""
        recent, self._recent = self._recent, [*self._recent, flagged][-(self.persistence - 1) :]
        if self.persistence <= 1:
            return flagged, regions
        if len(recent) < self.persistence - 1:
            return np.zeros_like(flagged), []
        grown = [cv2.dilate(r.astype(np.uint8), _GROW) > 0 for r in recent]
        kept = [r for r in regions if all(g[r.cells[:, 0], r.cells[:, 1]].any() for g in grown)]
        return (regions_mask(kept) if kept else np.zeros_like(flagged)), kept

    def process(self, frame: np.ndarray, index: int, time_s: float) -> FrameResult:
        """Run one frame through the stages and the detectors."""
        flow = self.pipeline.process(frame)
        if flow is None:
            empty = np.zeros((64, 64), bool)
            return FrameResult(index, time_s, [], empty, None, None, None)
        outputs = {name: det.process(flow, index) for name, det in self.detectors.items()}
        flagged, regions = fuse(outputs, flow.geometry, self.min_cells)
        flagged, regions = self._persistent(flagged, regions)
        ray = outputs.get("constraint-ray")
        observer = ray.observer if ray else None
        coarse = ray.coarse if ray else None
        return FrameResult(index, time_s, regions, flagged, observer, coarse, flow, outputs)
