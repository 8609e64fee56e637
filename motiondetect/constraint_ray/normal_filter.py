"""Detector 1: constraint ray filtering (section 3 of the paper).

In a rigid world the flow at image point p lies on the segment
``V_w + s * V_XY``, ``s`` in ``[0, a]`` (Figure 2). Its gradient-parallel
component along unit normal ``n`` is therefore confined to the exclusive OR
of the two disks whose diameters run from the origin to the segment's ends
(Figure 4), which is the same as the interval between ``V_w . n`` and
``(V_w + a V_XY) . n`` (docs/detectors.md); with ``a`` unbounded the far
disk becomes a half-plane and one end of the interval goes to infinity.

Per frame:

1. Hough the normal flow into a coarse 4x4 field (:mod:`.hough`);
2. match it against the canonical library, or take the known ego-motion
   (:mod:`.observer_motion`, :mod:`.egomotion`);
3. build the *filter image*: for every cell and each of 16 gradient
   directions, a 32-bit mask of the signed normal-flow bins a rigid world
   allows (the paper's bit encoding);
4. encode every measurement, widened by its noise tolerance, as a bit mask
   too; a measurement sharing no bit with the filter is flagged;
5. drop isolated cells and group the rest into regions.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from motiondetect.config_checks import check_fields
from motiondetect.constraint_ray.constraint_model import constraint_model
from motiondetect.constraint_ray.egomotion import known_motion
from motiondetect.constraint_ray.hough import CoarseField, coarse_field
from motiondetect.constraint_ray.observer_motion import ObserverMotion, classify
from motiondetect.detection.base import DetectorOutput
from motiondetect.detection.regions import drop_isolated, find_regions
from motiondetect.measurement.luts import BinTable
from motiondetect.measurement.normal_flow import (
    DIRECTION_BINS,
    NormalFlowField,
    direction_bin,
    measurement_tolerance,
)

NAME = "constraint-ray"

_POSITIVE_EDGES = np.array(
    [0.0, 0.125, 0.25, 0.375, 0.5, 0.75, 1.0, 1.25, 1.5, 2.0, 2.5, 3.0, 4.0, 5.0, 6.5, 8.5]
)
#: Edges of the 32 signed normal-flow bins, work px/frame.
MAGNITUDE_EDGES = np.concatenate([[-np.inf], -_POSITIVE_EDGES[:0:-1], _POSITIVE_EDGES, [np.inf]])
MAGNITUDE_BINS = len(MAGNITUDE_EDGES) - 1  # 32
_magnitude_bin = BinTable(MAGNITUDE_EDGES, step=0.125, limit=9.0)


# ----------------------------------------------------------------------------
# Geometry of Figure 4
# ----------------------------------------------------------------------------


def allowed_interval(
    rotation: np.ndarray,
    translation: np.ndarray,
    depth_bound: float,
    nx: np.ndarray,
    ny: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Normal-flow values a rigid world allows, as an interval.

    Parameters
    ----------
    rotation : (..., 2) ndarray
        ``V_w``, work px/frame.
    translation : (..., 2) ndarray
        ``V_XY``; the flow at inverse depth ``s`` is ``V_w + s V_XY``.
    depth_bound : float
        ``a``, the largest inverse depth (``UNBOUNDED`` for a half-plane).
    nx, ny : (...) ndarray
        Unit gradient direction.

    Returns
    -------
    lo, hi : (...) ndarray
        ``m`` is consistent iff ``lo <= m <= hi``.
    """
    e1 = rotation[..., 0] * nx + rotation[..., 1] * ny
    e2 = e1 + depth_bound * (translation[..., 0] * nx + translation[..., 1] * ny)
    return np.minimum(e1, e2), np.maximum(e1, e2)


def in_disk(point: np.ndarray, diameter_end: np.ndarray) -> np.ndarray:
    """Is ``point`` in the closed disk whose diameter runs from 0 to ``diameter_end``?"""
    centre = diameter_end / 2
    return ((point - centre) ** 2).sum(-1) <= (centre**2).sum(-1) * (1 + 1e-9) + 1e-12


def xor_of_disks(point: np.ndarray, v1: np.ndarray, v2: np.ndarray) -> np.ndarray:
    """Figure 4: the constraint region for the segment from ``v1`` to ``v2``."""
    return in_disk(point, v1) ^ in_disk(point, v2)


def disk_and_half_plane(point: np.ndarray, v1: np.ndarray, direction: np.ndarray) -> np.ndarray:
    """Figure 4 with ``a -> infinity``: the segment is a ray from ``v1`` along ``direction``.

    The far disk grows into the half-plane ``point . direction > 0``; the
    region is that half-plane minus the near disk, plus the near disk minus
    the half-plane.
    """
    half = (point * direction).sum(-1) > 0
    return in_disk(point, v1) ^ half


# ----------------------------------------------------------------------------
# Bit encoding: the filter image
# ----------------------------------------------------------------------------


def encode_interval(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Bit mask (uint32) of the magnitude bins that ``[lo, hi]`` touches."""
    first = np.clip(_magnitude_bin(lo) - 1, 0, MAGNITUDE_BINS - 1)
    last = np.clip(_magnitude_bin(hi) - 1, 0, MAGNITUDE_BINS - 1)
    one = np.uint64(1)
    upto_last = (one << (last.astype(np.uint64) + one)) - one
    below_first = (one << first.astype(np.uint64)) - one
    return (upto_last & ~below_first).astype(np.uint32)


def decode_mask(mask: int) -> tuple[float, float]:
    """The interval [lo, hi] of bin edges spanned by a contiguous mask."""
    bits = [i for i in range(MAGNITUDE_BINS) if mask >> i & 1]
    return float(MAGNITUDE_EDGES[bits[0]]), float(MAGNITUDE_EDGES[bits[-1] + 1])


def filter_bits(model: ObserverMotion, bins: np.ndarray) -> np.ndarray:
    """The filter image at one direction bin per cell: (64, 64) uint32.

    Bin ``b`` holds the allowed normal-flow bins for gradient directions in
    ``[b, b + 1) * pi / 16``: the union of the intervals at the bin's two
    edges and its centre, so the direction quantisation never forbids a
    value the exact filter allows.
    """
    step = np.pi / DIRECTION_BINS
    lo = hi = None
    for offset in (0.0, 0.5, 1.0):
        theta = (bins + offset) * step
        a, b = allowed_interval(
            model.rotation_px,
            model.translation_px,
            model.depth_bound,
            np.cos(theta),
            np.sin(theta),
        )
        lo = a if lo is None else np.minimum(lo, a)
        hi = b if hi is None else np.maximum(hi, b)
    return encode_interval(lo, hi)


def filter_image(model: ObserverMotion) -> np.ndarray:
    """The whole filter image: (64, 64, 16) uint32, one mask per direction bin.

    The detector only reads each cell's measured bin (:func:`filter_bits`);
    this materialises all of them, for inspection and figures.
    """
    shape = model.rotation_px.shape[:2]
    return np.stack([filter_bits(model, np.full(shape, b)) for b in range(DIRECTION_BINS)], axis=-1)


def check_measurements(
    model: ObserverMotion, field: NormalFlowField, tolerance: np.ndarray
) -> np.ndarray:
    """Cells whose measured normal flow shares no bit with the filter image.

    Returns
    -------
    flagged : (64, 64) ndarray of bool
    """
    theta, sign = field.orientation
    m = sign * field.flow_px
    allowed = filter_bits(model, direction_bin(theta))
    measured = encode_interval(m - tolerance, m + tolerance)
    return field.valid & ((allowed & measured) == 0)


# ----------------------------------------------------------------------------
# The detector
# ----------------------------------------------------------------------------


@dataclass(frozen=True)
class ConstraintRayConfig:
    """Settings of the constraint ray filter.

    Attributes
    ----------
    ego_model : {"fitted", "paper"}
        ``paper``: the matched library entry as is, depth unbounded.
        ``fitted``: class parameters and both ends of the speed range
        estimated from the frame (docs/detectors.md).
    noise_grey : float
        Noise of the temporal difference, grey levels; the tolerance of a
        measurement is ``noise_grey / |grad I|`` (times ``noise_sigmas``).
    noise_sigmas : float
    tolerance_floor_px : float
        Smallest tolerance, work px/frame.
    tolerance_relative : float
        Extra tolerance proportional to ``|m|``.
    min_neighbours : int
        Flagged cells with fewer flagged 8-neighbours are dropped as noise.
    min_cells : int
        Smallest region kept, cells.
    static_fraction : float
        Share of still regions above which the observer is static.
    min_confidence : float
        Below this classification confidence nothing is flagged.
    """

    ego_model: Literal["fitted", "paper"] = "fitted"
    noise_grey: float = 1.0
    noise_sigmas: float = 3.0
    tolerance_floor_px: float = 0.3
    tolerance_relative: float = 0.2
    min_neighbours: int = 2
    min_cells: int = 3
    static_fraction: float = 0.6
    min_confidence: float = 0.2

    def __post_init__(self) -> None:
        check_fields(
            self,
            positive=("noise_grey", "noise_sigmas", "tolerance_floor_px"),
            choices={"ego_model": ("fitted", "paper")},
        )


class ConstraintRayDetector:
    """Flags motion no rigid world seen by the current observer motion could make.

    Parameters
    ----------
    config : ConstraintRayConfig
    egomotion : callable, optional
        ``egomotion(frame_index, geometry) -> ObserverMotion | None``: known
        camera motion. Where it answers, the classification is skipped.
    """

    name = NAME
    measurement = "normal"
    config_type = ConstraintRayConfig

    def __init__(self, config: ConstraintRayConfig | None = None, egomotion=None) -> None:
        self.config = config or ConstraintRayConfig()
        self.egomotion = egomotion

    def reset(self) -> None:
        """Nothing carries over between frames."""

    def _observer(self, field: NormalFlowField, coarse: CoarseField, frame_index: int):
        cfg = self.config
        if self.egomotion is not None:
            known = known_motion(self.egomotion, field, frame_index)
            if known is not None:
                return known
        entry, class_id, confidence = classify(
            coarse, field.geometry, static_fraction=cfg.static_fraction
        )
        return constraint_model(entry, class_id, confidence, coarse, field, mode=cfg.ego_model)

    def process(self, field: NormalFlowField, frame_index: int = 0) -> DetectorOutput:
        """Detect independent motion in one frame's normal flow."""
        cfg = self.config
        coarse = coarse_field(field, noise_grey=cfg.noise_grey)
        observer = self._observer(field, coarse, frame_index)
        empty = np.zeros(field.flow_px.shape, bool)
        if not observer.constrains or observer.confidence < cfg.min_confidence:
            return DetectorOutput(
                empty, empty.astype(np.float32), [], observer=observer, coarse=coarse
            )
        tol = cfg.noise_sigmas * measurement_tolerance(
            field, cfg.noise_grey, cfg.tolerance_floor_px / cfg.noise_sigmas
        ) + cfg.tolerance_relative * np.abs(field.flow_px)
        flagged = check_measurements(observer, field, tol)
        flagged = drop_isolated(flagged, cfg.min_neighbours)
        nx, ny = field.normal
        lo, hi = allowed_interval(
            observer.rotation_px, observer.translation_px, observer.depth_bound, nx, ny
        )
        excess = np.maximum(np.maximum(lo - field.flow_px, field.flow_px - hi), 0.0)
        strength = np.where(flagged, excess / (excess + tol), 0.0).astype(np.float32)
        regions = find_regions(
            flagged, strength, field.geometry, min_cells=cfg.min_cells, detector=NAME
        )
        return DetectorOutput(flagged, strength, regions, observer=observer, coarse=coarse)
