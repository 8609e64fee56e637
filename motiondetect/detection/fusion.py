"""How the detectors' outputs become the reported regions.

On the normal path (the paper's) the detectors' 64x64 cells are united and
regrouped (:func:`fuse`); on the velocity path each tracked object becomes
one region (:func:`object_region`), naming the detectors that found it.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import cv2
import numpy as np

from motiondetect.detection.base import DetectorOutput, cells_from_mask
from motiondetect.detection.objects import MovingObject
from motiondetect.detection.regions import Region, find_regions
from motiondetect.measurement.normal_flow import GridGeometry


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


@dataclass(frozen=True)
class FrameMotion:
    """What a frame's objects' velocities are read from.

    Attributes
    ----------
    velocity : (h, w, 2) ndarray of float32
        Image velocity, work px over ``interval_s``.
    residual : (h, w, 2) ndarray of float32
        ``velocity`` less the fitted camera motion's (the plane residual).
    interval_s : float
        Seconds the velocities span (positive).
    rim_px : int
        Width of the rim left out, work px: half a flow patch, how far the
        flow smears a mover's velocity into what lies round it.
    """

    velocity: np.ndarray
    residual: np.ndarray
    interval_s: float
    rim_px: int


def object_velocities(
    mask: np.ndarray, box: tuple, motion: FrameMotion
) -> tuple[tuple[float, float], tuple[float, float]] | None:
    """The median image velocity and own velocity (the residual) of an
    object, work px per second, over its (h, w) bool ``mask`` (empty outside
    its (x0, y0, x1, y1) ``box``) less a rim ``motion.rim_px`` wide (the
    whole mask where that leaves nothing); None for an empty mask."""
    rim, (h, w) = motion.rim_px, mask.shape
    x0, y0 = max(int(box[0]) - rim, 0), max(int(box[1]) - rim, 0)
    x1, y1 = min(int(np.ceil(box[2])) + rim, w), min(int(np.ceil(box[3])) + rim, h)
    own_pixels = mask[y0:y1, x0:x1]
    side = 2 * rim + 1
    core = cv2.erode(own_pixels.astype(np.uint8), np.ones((side, side), np.uint8)) > 0
    inside = core if core.any() else own_pixels
    if not inside.any():
        return None
    speeds = []
    for field in (motion.velocity, motion.residual):
        part = field[y0:y1, x0:x1]
        speeds.append(
            tuple(float(np.median(part[..., i][inside])) / motion.interval_s for i in (0, 1))
        )
    return speeds[0], speeds[1]


def object_region(
    obj: MovingObject,
    outputs: dict[str, DetectorOutput],
    geometry: GridGeometry,
    before: Region | None = None,
    motion: FrameMotion | None = None,
) -> Region:
    """A tracked object as a reported region, in input pixels, with its
    velocities where ``motion`` is given; a held one takes the detectors and
    velocities of ``before``, its track's last region."""
    sx = geometry.input_size[0] / geometry.work_size[0]
    sy = geometry.input_size[1] / geometry.work_size[1]
    x0, y0, x1, y1 = obj.box
    bbox = [round(x0 * sx), round(y0 * sy), round((x1 - x0) * sx), round((y1 - y0) * sy)]
    cells = np.argwhere(cells_from_mask(obj.mask, share=1e-6))
    inside = (slice(y0, y1), slice(x0, x1))  # the mask is empty outside its box
    own = obj.mask[inside]
    found = tuple(n for n, out in outputs.items() if (out.mask[inside] & own).any())
    strength = max(float(out.pixel_strength[inside][own].mean()) for out in outputs.values())
    area = round(float(own.sum()) * sx * sy)
    region = Region(bbox, cells, area, strength, found, obj.track, obj.held)
    if obj.held:
        if before is None:
            return region
        return dataclasses.replace(
            region,
            detectors=before.detectors,
            velocity_px_s=before.velocity_px_s,
            own_velocity_px_s=before.own_velocity_px_s,
        )
    if motion is None:
        return region
    velocities = object_velocities(obj.mask, obj.box, motion)
    if velocities is None:
        return region
    (vx, vy), (ox, oy) = velocities
    return dataclasses.replace(
        region, velocity_px_s=(vx * sx, vy * sy), own_velocity_px_s=(ox * sx, oy * sy)
    )
