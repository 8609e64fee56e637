"""How the detectors' outputs become the reported regions.

On the normal path (the paper's) the detectors' 64x64 cells are united and
regrouped (:func:`fuse`); on the velocity path each tracked object becomes
one region (:func:`object_region`), naming the detectors that found it.
"""

from __future__ import annotations

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


def object_region(
    obj: MovingObject,
    outputs: dict[str, DetectorOutput],
    geometry: GridGeometry,
    found_before: tuple[str, ...] = (),
) -> Region:
    """A tracked object as a reported region, in input pixels; a held one
    names ``found_before``, the detectors that found its track last."""
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
    if obj.held:
        found = found_before or found
    return Region(bbox, cells, area, strength, found, obj.track, obj.held)
