"""The one interface every detector shares, its output type, and the registry.

A detector is a small class with one frozen config (``config_type``), a
``name``, the ``measurement`` it consumes (``"normal"``: the 64x64 normal
flow of Appendix A; ``"velocity"``: the dense 2-D velocity), a per-frame
``process(field, frame_index)`` and ``reset()``. State lives only where
time needs it (the animate detectors' previous frame, an epipole).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING, Any, ClassVar, Protocol, runtime_checkable

import cv2
import numpy as np

from motiondetect.measurement.stages import GRID

if TYPE_CHECKING:
    from motiondetect.constraint_ray.camera_fit import CameraFit
    from motiondetect.constraint_ray.hough import CoarseField
    from motiondetect.constraint_ray.observer_motion import ObserverMotion
    from motiondetect.detection.regions import Region

#: A grid cell counts as flagged when this share of its pixels is.
CELL_SHARE = 0.25


def cells_from_mask(mask: np.ndarray, share: float = CELL_SHARE) -> np.ndarray:
    """(64, 64) bool: the grid cells of which at least ``share`` is flagged.

    Parameters
    ----------
    mask : (h, w) ndarray of bool
    """
    fraction = cv2.resize(mask.astype(np.float32), (GRID, GRID), interpolation=cv2.INTER_AREA)
    return fraction >= share


@dataclass(frozen=True)
class DetectorOutput:
    """What a detector reports for one frame.

    Attributes
    ----------
    grid, grid_strength : (64, 64) ndarray of bool, of float32 in [0, 1]
        The flagged cells and their strength as given (normal-flow
        detectors); None on the velocity path, where :attr:`flagged` and
        :attr:`strength` derive them from the pixel mask when first read
        (the judging never reads them: two resizes a detector a frame saved).
    regions : list of Region
        The detector's own grouping (normal-flow detectors).
    observer : ObserverMotion, optional
        The matched or known observer motion (normal-flow path).
    coarse : CoarseField, optional
        The 4x4 Hough field (normal-flow path).
    mask : (h, w) ndarray of bool, optional
        Flagged work pixels (velocity path).
    pixel_strength : (h, w) ndarray of float32, optional
    camera : CameraFit, optional
        The fitted observer motion (velocity path).
    extra : dict
        Diagnostics written to frames.jsonl.
    """

    grid: np.ndarray | None
    grid_strength: np.ndarray | None
    regions: list[Region] = field(default_factory=list)
    observer: ObserverMotion | None = None
    coarse: CoarseField | None = None
    mask: np.ndarray | None = None
    pixel_strength: np.ndarray | None = None
    camera: CameraFit | None = None
    extra: dict = field(default_factory=dict)

    @cached_property
    def flagged(self) -> np.ndarray:
        """(64, 64) bool: the flagged cells (:func:`cells_from_mask` of the mask
        on the velocity path)."""
        return cells_from_mask(self.mask) if self.grid is None else self.grid

    @cached_property
    def strength(self) -> np.ndarray:
        """(64, 64) float32 in [0, 1]: each flagged cell's mean strength, 0 elsewhere."""
        if self.grid_strength is not None:
            return self.grid_strength
        cells = cv2.resize(self.pixel_strength, (GRID, GRID), interpolation=cv2.INTER_AREA)
        return np.where(self.flagged, cells, 0.0).astype(np.float32)

    @classmethod
    def empty(cls, shape: tuple[int, int] | None = None, **kwargs) -> DetectorOutput:
        """Nothing flagged; ``shape`` (h, w) adds an empty pixel mask."""
        grid = np.zeros((GRID, GRID), bool)
        mask = None if shape is None else np.zeros(shape, bool)
        strength = None if shape is None else np.zeros(shape, np.float32)
        return cls(grid, grid.astype(np.float32), [], mask=mask, pixel_strength=strength, **kwargs)

    @classmethod
    def from_mask(cls, mask: np.ndarray, strength: np.ndarray, **kwargs) -> DetectorOutput:
        """From a pixel mask and its per-pixel strength (velocity path)."""
        if not mask.any():  # often (a quiet frame, the animate detector): skip the resizing
            return cls.empty(mask.shape, **kwargs)
        return cls(None, None, mask=mask, pixel_strength=strength, **kwargs)


@runtime_checkable
class Detector(Protocol):
    """What :class:`~motiondetect.detection.detector.MotionDetector` drives."""

    name: ClassVar[str]
    measurement: ClassVar[str]
    config_type: ClassVar[type]

    def process(self, field: Any, frame_index: int = 0) -> DetectorOutput: ...

    def reset(self) -> None: ...


def registry() -> dict[str, type]:
    """``{name: class}`` of every detector (imported here to keep layers one-way)."""
    from motiondetect.animate.normal_footprints import AnimateDetector
    from motiondetect.animate.velocity_footprints import VelocityAnimateDetector
    from motiondetect.constraint_ray.normal_filter import ConstraintRayDetector
    from motiondetect.constraint_ray.velocity_filter import VelocityRayDetector

    classes = (ConstraintRayDetector, AnimateDetector, VelocityRayDetector, VelocityAnimateDetector)
    return {cls.name: cls for cls in classes}


#: Which registered detectors ``--detector`` names, per ``--measure``.
DETECTOR_SETS = {
    "velocity": {
        "constraint-ray": ("velocity-ray",),
        "animate": ("velocity-animate",),
        "both": ("velocity-ray", "velocity-animate"),
    },
    "normal": {
        "constraint-ray": ("constraint-ray",),
        "animate": ("animate",),
        "both": ("constraint-ray", "animate"),
    },
}
