"""Flagged cells to scored regions, shared by both detectors."""

from __future__ import annotations

from dataclasses import dataclass, field

import cv2
import numpy as np

from motiondetect.measurement.normal_flow import GridGeometry

_EIGHT = np.ones((3, 3), np.float32)


@dataclass(frozen=True)
class Region:
    """One detection.

    Attributes
    ----------
    bbox : [x, y, w, h]
        Input pixels.
    cells : (K, 2) ndarray of int
        (row, col) of the grid cells it covers.
    area_px : int
        Area of its cells, input pixels.
    score : float
        Mean violation strength of its cells, in [0, 1].
    detectors : tuple of str
        Which detectors found it.
    track : int or None
        Stable id of the object across frames (velocity path).
    held : bool
        Not found on this frame: a confirmed track reported where its own
        motion puts it (``detectors`` are those that found it last).
    velocity_px_s : (vx, vy) or None
        How it moves in the picture, input px per second (x right, y down):
        the median image velocity over its mask less a rim half a flow patch
        wide (velocity path; a held region carries its track's last).
    own_velocity_px_s : (vx, vy) or None
        How it moves against what lies behind it: the same median of its
        image velocity less the fitted camera motion's (the dominant plane's)
        at each pixel, input px per second. Zero for a rigid point on that
        plane, whatever the camera does.
    """

    bbox: list[int]
    cells: np.ndarray
    area_px: int
    score: float
    detectors: tuple[str, ...] = field(default_factory=tuple)
    track: int | None = None
    held: bool = False
    velocity_px_s: tuple[float, float] | None = None
    own_velocity_px_s: tuple[float, float] | None = None

    def to_json(self) -> dict:
        out = {
            "bbox": [int(v) for v in self.bbox],
            "area_px": int(self.area_px),
            "score": round(float(self.score), 4),
            "detectors": list(self.detectors),
        }
        if self.track is not None:
            out["track"] = int(self.track)
        if self.held:
            out["held"] = True
        for name in ("velocity_px_s", "own_velocity_px_s"):
            value = getattr(self, name)
            if value is not None:
                out[name] = velocity_json(value)
        return out


def velocity_json(value: tuple[float, float]) -> list[float]:
    """A velocity, px/s, as written to frames.jsonl: to 0.1, never -0.0."""
    return [round(float(v), 1) + 0.0 for v in value]


def drop_isolated(flagged: np.ndarray, min_neighbours: int) -> np.ndarray:
    """Keep flagged cells with at least ``min_neighbours`` flagged 8-neighbours."""
    if min_neighbours <= 0:
        return flagged
    counts = cv2.filter2D(flagged.astype(np.float32), -1, _EIGHT, borderType=cv2.BORDER_CONSTANT)
    return flagged & (counts - 1 >= min_neighbours - 0.5)


def find_regions(
    flagged: np.ndarray,
    strength: np.ndarray,
    geometry: GridGeometry,
    *,
    min_cells: int,
    detector: str,
) -> list[Region]:
    """Group flagged cells into 8-connected regions.

    Parameters
    ----------
    flagged : (64, 64) ndarray of bool
    strength : (64, 64) ndarray of float32
        Per-cell violation strength in [0, 1].
    geometry : GridGeometry
    min_cells : int
        Smaller components are dropped as noise.
    detector : str
        Name recorded in each region's ``detectors``.
    """
    count, labels, stats = components_with_stats(flagged)
    cw, ch = geometry.input_cell_px
    regions = []
    for label in range(1, count):
        x, y, w, h, area = (int(v) for v in stats[label])
        if area < min_cells:
            continue
        cells = np.argwhere(labels == label)
        score = float(strength[labels == label].mean())
        regions.append(
            Region(
                bbox=geometry.cell_box_to_input(x, y, w, h),
                cells=cells,
                area_px=round(area * cw * ch),
                score=score,
                detectors=(detector,),
            )
        )
    regions.sort(key=lambda r: -r.area_px)
    return regions


def regions_mask(regions: list[Region], shape: tuple[int, int] = (64, 64)) -> np.ndarray:
    """The (64, 64) boolean mask of the cells of ``regions``."""
    mask = np.zeros(shape, bool)
    for region in regions:
        mask[region.cells[:, 0], region.cells[:, 1]] = True
    return mask


_SQUARE3 = np.ones((3, 3), np.uint8)


def _label_type(shape: tuple[int, int]) -> int:
    """16-bit labels where they cannot overflow (at most one 8-connected
    component per 2x2 pixels), else 32-bit."""
    h, w = shape
    return cv2.CV_16U if ((h + 1) // 2) * ((w + 1) // 2) < 65535 else cv2.CV_32S


def true_pixels(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rows and columns of a (h, w) mask's true pixels in row-major order,
    as ``np.nonzero(mask)`` gives them: a search of the flattened mask costs
    a fifth to a twentieth of NumPy's 2-D ``nonzero`` at the working size."""
    return np.divmod(np.flatnonzero(mask), mask.shape[1])


def components(mask: np.ndarray) -> tuple[int, np.ndarray]:
    """8-connected components of a (h, w) mask: count and labels (16-bit
    where they fit, as :func:`components_with_stats`)."""
    return cv2.connectedComponents(
        mask.astype(np.uint8), connectivity=8, ltype=_label_type(mask.shape)
    )


def components_with_stats(mask: np.ndarray) -> tuple[int, np.ndarray, np.ndarray]:
    """8-connected components of a (h, w) mask: count, labels and
    ``cv2.connectedComponentsWithStats`` stats.

    Labels are 16-bit where they cannot overflow (at most one component per
    2x2 pixels): OpenCV's stats pass is then about 3x faster (0.19 against
    0.61 ms at 320x320, one thread).
    """
    count, labels, stats, _ = cv2.connectedComponentsWithStats(
        mask.astype(np.uint8), connectivity=8, ltype=_label_type(mask.shape)
    )
    return count, labels, stats


def hysteresis(
    distance: np.ndarray, tolerance: float, grow_ratio: float, seeds: np.ndarray | None = None
) -> np.ndarray:
    """Points off the ray by ``tolerance`` (opened 3x3), grown over those off by
    ``grow_ratio * tolerance`` that connect to them. (h, w) bool.

    ``seeds`` (bool), when given, replaces the strong points as the seeds."""
    if seeds is None:
        seeds = distance > tolerance
    if not seeds.any():
        return np.zeros(distance.shape, bool)
    strong = cv2.morphologyEx(seeds.astype(np.uint8), cv2.MORPH_OPEN, _SQUARE3)
    count, labels = components(distance > grow_ratio * tolerance)
    keep = np.zeros(count, bool)
    keep[labels[strong > 0]] = True
    keep[0] = False
    return keep.take(labels)


def without_frame_edge(distance: np.ndarray, band_px: float) -> np.ndarray:
    """Zero (or clear) the band along the frame edge where content enters or leaves.

    There the flow has no previous pixels to match and is extrapolated, so
    its residual says nothing about independent motion (the normal-flow
    detectors drop a border ring of cells for the same reason).
    """
    b = int(np.ceil(band_px))
    if b <= 0:
        return distance
    out = distance.copy()
    out[:b], out[-b:], out[:, :b], out[:, -b:] = 0, 0, 0, 0
    return out


def discounted_near_edge(distance: np.ndarray, band_px: float, ratio: float) -> np.ndarray:
    """``distance`` divided by ``ratio`` within ``band_px`` of the frame edge.

    Within one patch of the edge DIS's patches are cut by the border, and
    its error there is about twice the inside's (median, on motions with
    known answers: ``benchmarks/velocity_accuracy.py --border``), so a
    residual there means half as much. A new array; ``ratio`` 1 returns
    ``distance`` itself.
    """
    b = int(np.ceil(band_px))
    if ratio == 1 or b <= 0:
        return distance
    out = distance.copy()
    scale = np.float32(1.0 / ratio)
    out[:b] *= scale
    out[-b:] *= scale
    out[b:-b, :b] *= scale
    out[b:-b, -b:] *= scale
    return out
