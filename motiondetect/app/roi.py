"""Regions of interest and the minimum area: which detections a run keeps."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import cv2
import numpy as np

from motiondetect.app.inputs import InputError
from motiondetect.app.settings import Settings
from motiondetect.detection.detector import FrameResult
from motiondetect.detection.regions import Region, regions_mask
from motiondetect.measurement.stages import GRID


def roi_mask(settings: Settings, width: int, height: int) -> np.ndarray | None:
    """(GRID, GRID) bool mask of cells whose centre lies in any region of interest."""
    polygons = []
    for x, y, w, h in settings.roi:
        polygons.append(np.array([[x, y], [x + w, y], [x + w, y + h], [x, y + h]], np.int32))
    if settings.roi_file is not None:
        polygons.extend(load_polygons(settings.roi_file))
    if not polygons:
        return None
    full = np.zeros((height, width), np.uint8)
    cv2.fillPoly(full, polygons, 1)
    ys = ((np.arange(GRID) + 0.5) * height / GRID).astype(int)
    xs = ((np.arange(GRID) + 0.5) * width / GRID).astype(int)
    return full[np.ix_(ys, xs)] > 0


def load_polygons(path: Path) -> list[np.ndarray]:
    """A polygon file: one polygon per line, ``x,y x,y x,y ...`` in input pixels."""
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except OSError as exc:
        raise InputError(f"cannot read ROI file {path}: {exc.strerror or exc}") from exc
    polygons = []
    for n, line in enumerate(lines, 1):
        line = line.split("#")[0].strip()
        if not line:
            continue
        try:
            pts = [tuple(int(float(v)) for v in p.split(",")) for p in line.split()]
        except ValueError:
            raise InputError(f"ROI file {path}, line {n}: expected 'x,y x,y x,y ...'") from None
        if len(pts) < 3 or any(len(p) != 2 for p in pts):
            raise InputError(f"ROI file {path}, line {n}: a polygon needs at least 3 x,y points")
        polygons.append(np.array(pts, np.int32))
    return polygons


def _keep(region: Region, roi: np.ndarray | None, min_area: int) -> bool:
    if region.area_px < min_area:
        return False
    if roi is None:
        return True
    return bool(roi[region.cells[:, 0], region.cells[:, 1]].any())


def keep_detections(result: FrameResult, roi: np.ndarray | None, min_area: int) -> FrameResult:
    if roi is None and min_area <= 0:
        return result
    kept = [r for r in result.regions if _keep(r, roi, min_area)]
    flagged = regions_mask(kept) if kept else np.zeros_like(result.flagged)
    mask = result.mask
    if mask is not None:
        h, w = mask.shape
        mask = mask & (
            cv2.resize(flagged.astype(np.uint8), (w, h), interpolation=cv2.INTER_NEAREST_EXACT) > 0
        )
    return dataclasses.replace(result, regions=kept, flagged=flagged, mask=mask)
