"""Detector 2: animate motion (section 4 of the paper).

Under smooth observer motion the image motion of a rigid point changes
slowly. Each valid cell at frame t-1 predicts where its world point may be
at t (its *footprint*) and flags those cells with its motion value; at t a
measured value that no footprint allowed is animate motion.

* **Values** are coarsely bit-encoded: the gradient orientation (mod pi,
  8 bins) and the normal flow signed along it (15 bins, finer near zero),
  16 bits per orientation, two 64-bit words per cell. A value is written in
  its own orientation bin and the nearer neighbouring one. Keeping the
  orientation matters: a rigid point keeps its gradient orientation from
  frame to frame, but neighbouring texture with another orientation shows
  another normal flow for the same motion (the aperture problem), and
  comparing values across orientations either flags rigid texture or
  forgives everything.
* **Footprints** (Figure 8): with only the normal component known, the
  point moved ``m`` along ``n`` and anything up to the speed bound along the
  constraint line, so the footprint is a bar across the flow, displaced by
  the flow, extended back through and a little beyond the generating point
  (the counterflow side) so that objects emerging from behind an occluder
  predict their own appearance, and forward past the predicted position so
  that background uncovered behind a faster occluder is predicted too.
* **Constraint map**: the footprints' bits OR together per cell.
* **Violations**: a measurement whose candidate bits (its value widened by
  the noise tolerance and a small smooth-change allowance) share none with
  the map's bits for its orientation. A cell where no footprint of its
  orientation landed is a *first appearance*; ``first_appearance`` says
  whether to flag it. Content that may have entered the frame since the
  last one is not tested.
* **Jitter**: section 4.2 warns that rotational jitter breaks smoothness.
  With ``jitter_compensation`` the frame's global shift is estimated as the
  median over 4x4 blocks of the change of each block's uniform flow; it is
  removed from the measurements and the map is shifted by it.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import Literal

import numpy as np

from motiondetect.animate.jitter import block_flows, jitter_shift
from motiondetect.animate.values import WORDS, candidate_slots, map_slot, value_words
from motiondetect.config_checks import check_fields
from motiondetect.detection.base import DetectorOutput
from motiondetect.detection.regions import drop_isolated, find_regions
from motiondetect.measurement.luts import BinTable
from motiondetect.measurement.normal_flow import (
    GridGeometry,
    NormalFlowField,
    measurement_tolerance,
)

NAME = "animate"

# Footprint geometry only: 16 directions of the vector m n x 6 magnitudes + still.
FOOTPRINT_DIRECTIONS = 16
FOOTPRINT_MAGNITUDE_EDGES_PX = np.array([0.6, 1.2, 2.4, 4.8, 9.6])
FOOTPRINT_MAGNITUDES = len(FOOTPRINT_MAGNITUDE_EDGES_PX) + 1
STENCIL_RADIUS = 4  # cells
_footprint_magnitude = BinTable(FOOTPRINT_MAGNITUDE_EDGES_PX, step=0.1, limit=10.0)


@dataclass(frozen=True)
class AnimateConfig:
    """Settings of the animate-motion detector.

    Attributes
    ----------
    max_speed_px : float
        Speed bound of a rigid point, work px/frame: how far along the
        constraint line the footprint reaches.
    counterflow_cells : float
        How far the footprint extends behind its generating point, cells
        (Figure 8: objects emerging from behind an occluder).
    ahead_cells : float
        How far the footprint extends beyond the predicted position, cells:
        background uncovered at the trailing edge of a faster occluder
        appears ahead of its visible part (the mirror case of Figure 8).
    still_px : float
        Normal flow below this is "still": its footprint is a small disk.
    noise_grey, noise_sigmas, tolerance_floor_px : float
        Measurement tolerance, ``noise_sigmas * noise_grey / |grad I|``
        with a floor.
    accel_px : float
        Change of the normal flow a rigid point may show between frames,
        px/frame (smooth observer motion: section 4.1 puts it at about the
        squared angular speed, well under a pixel).
    accel_relative : float
        Further allowance proportional to ``|m|``: the stages' error grows
        with speed (docs/stages.md).
    first_appearance : {"ignore", "flag"}
        Motion where no footprint of the same gradient orientation landed:
        ignored (default), or flagged as the paper suggests.
    jitter_compensation : bool
    min_gradient : float
        Only measurements with at least this gradient (grey/work px) are
        tested; weaker ones still make footprints.
    border_cells : int
        Cells this close to the frame edge are not tested: content entering
        the frame has no predecessor to make a footprint.
    min_neighbours, min_cells : int
        Noise removal and smallest region, as in detector 1.
    """

    max_speed_px: float = 6.0
    counterflow_cells: float = 1.0
    ahead_cells: float = 2.0
    still_px: float = 0.3
    noise_grey: float = 1.0
    noise_sigmas: float = 2.0
    tolerance_floor_px: float = 0.2
    accel_px: float = 0.75
    accel_relative: float = 0.1
    first_appearance: Literal["ignore", "flag"] = "ignore"
    jitter_compensation: bool = True
    min_gradient: float = 2.0
    border_cells: int = 2
    min_neighbours: int = 2
    min_cells: int = 3

    def __post_init__(self) -> None:
        check_fields(
            self,
            positive=("max_speed_px", "still_px", "noise_grey", "noise_sigmas"),
            non_negative=("counterflow_cells", "ahead_cells", "accel_px", "accel_relative"),
            choices={"first_appearance": ("ignore", "flag")},
        )


# ----------------------------------------------------------------------------
# Footprints
# ----------------------------------------------------------------------------


def footprint_cells(
    displacement_px: float,
    angle_rad: float,
    cell_px: tuple[float, float],
    max_speed_px: float,
    counterflow_cells: float,
    ahead_cells: float = 0.0,
) -> np.ndarray:
    """Cell offsets (dy, dx) covered by one footprint (Figure 8, right).

    The point moved ``displacement_px`` along ``angle_rad`` and up to
    ``sqrt(max_speed^2 - displacement^2)`` either way across it; the
    footprint is that bar, extended back through the generating point by
    ``counterflow_cells`` and forward past it by ``ahead_cells``, dilated
    by half a cell diagonal.

    Returns
    -------
    (K, 2) ndarray of int
    """
    cw, ch = cell_px
    r = STENCIL_RADIUS
    dy, dx = np.mgrid[-r : r + 1, -r : r + 1]
    px, py = dx * cw, dy * ch
    along = np.array([np.cos(angle_rad), np.sin(angle_rad)])
    across = np.array([-along[1], along[0]])
    a = px * along[0] + py * along[1]
    b = px * across[0] + py * across[1]
    half_cell = 0.5 * np.hypot(cw, ch)
    reach = np.sqrt(max(max_speed_px**2 - displacement_px**2, 0.0))
    back = counterflow_cells * max(cw, ch)
    ahead = ahead_cells * max(cw, ch)
    da = np.clip(a, -back, displacement_px + ahead) - a
    db = np.clip(b, -reach, reach) - b
    inside = np.hypot(da, db) <= half_cell
    return np.stack([dy[inside], dx[inside]], axis=1)


@lru_cache(maxsize=16)
def stencil_table(
    geometry: GridGeometry,
    max_speed_px: float,
    counterflow_cells: float,
    ahead_cells: float,
    still_px: float,
) -> tuple[np.ndarray, np.ndarray]:
    """Which offsets each footprint class covers.

    Classes: ``dir * FOOTPRINT_MAGNITUDES + mag`` for 16 directions of the
    vector ``m n``, then one "still" class. Each class uses the upper edge
    of its magnitude bin (the footprint must reach as far as the fastest
    value in it).

    Returns
    -------
    offsets : (O, 2) ndarray of int
    covers : (O, classes) ndarray of bool
    """
    r = STENCIL_RADIUS
    dy, dx = np.mgrid[-r : r + 1, -r : r + 1]
    offsets = np.stack([dy.ravel(), dx.ravel()], axis=1)
    index = {tuple(o): i for i, o in enumerate(offsets)}
    upper = np.append(FOOTPRINT_MAGNITUDE_EDGES_PX, max_speed_px)
    n_classes = FOOTPRINT_DIRECTIONS * FOOTPRINT_MAGNITUDES + 1
    covers = np.zeros((len(offsets), n_classes), bool)
    for d in range(FOOTPRINT_DIRECTIONS):
        angle = d * 2 * np.pi / FOOTPRINT_DIRECTIONS
        for m in range(FOOTPRINT_MAGNITUDES):
            cells = footprint_cells(
                min(upper[m], max_speed_px),
                angle,
                geometry.cell_px,
                max_speed_px,
                counterflow_cells,
                ahead_cells,
            )
            for cell in cells:
                covers[index[tuple(cell)], d * FOOTPRINT_MAGNITUDES + m] = True
    for cell in footprint_cells(0.0, 0.0, geometry.cell_px, still_px, counterflow_cells):
        covers[index[tuple(cell)], -1] = True
    used = covers.any(axis=1)
    return offsets[used], covers[used]


def footprint_classes(
    flow_px: np.ndarray, direction_rad: np.ndarray, still_px: float
) -> np.ndarray:
    """Stencil class of each measurement (see :func:`stencil_table`)."""
    angle = np.where(flow_px >= 0, direction_rad, direction_rad + np.pi)
    speed = np.abs(flow_px)
    mag = _footprint_magnitude(speed)
    direction = np.rint(angle / (2 * np.pi / FOOTPRINT_DIRECTIONS)).astype(np.int64)
    classes = (direction % FOOTPRINT_DIRECTIONS) * FOOTPRINT_MAGNITUDES + mag
    return np.where(speed < still_px, FOOTPRINT_DIRECTIONS * FOOTPRINT_MAGNITUDES, classes)


def shift(a: np.ndarray, dy: int, dx: int) -> np.ndarray:
    """``out[..., y + dy, x + dx] = a[..., y, x]``, zero-filled."""
    out = np.zeros_like(a)
    h, w = a.shape[-2:]
    ys, yd = (slice(0, h - dy), slice(dy, h)) if dy >= 0 else (slice(-dy, h), slice(0, h + dy))
    xs, xd = (slice(0, w - dx), slice(dx, w)) if dx >= 0 else (slice(-dx, w), slice(0, w + dx))
    out[..., yd, xd] = a[..., ys, xs]
    return out


def constraint_map(field: NormalFlowField, config: AnimateConfig) -> np.ndarray:
    """OR every valid cell's value over its footprint.

    Returns
    -------
    (2, 64, 64) ndarray of uint64
    """
    offsets, covers = stencil_table(
        field.geometry,
        config.max_speed_px,
        config.counterflow_cells,
        config.ahead_cells,
        config.still_px,
    )
    classes = footprint_classes(field.flow_px, field.direction_rad, config.still_px)
    theta, sign = field.orientation
    words = np.where(field.valid, value_words(theta, sign * field.flow_px), np.uint64(0))
    # Accumulate into a frame padded by the stencil radius: each offset is one
    # in-place OR of a slice, with no shifted copies.
    r = STENCIL_RADIUS
    h, w = classes.shape
    out = np.zeros((WORDS, h + 2 * r, w + 2 * r), np.uint64)
    part = np.empty_like(words)
    for (dy, dx), cover in zip(offsets, covers):
        target = out[:, r + dy : r + dy + h, r + dx : r + dx + w]
        np.multiply(words, cover[classes], out=part)  # the words of the classes covering it
        np.bitwise_or(target, part, out=target)
    return out[:, r:-r, r:-r].copy()


@lru_cache(maxsize=16)
def _room_inside(geometry: GridGeometry, border_cells: int) -> np.ndarray:
    """Each cell centre's distance to the frame edge less the border, work px
    (fixed per geometry, so computed once)."""
    x, y = geometry.cell_centres_px()
    width, height = geometry.work_size
    cw, ch = geometry.cell_px
    room = np.minimum(
        np.minimum(x, width - x) - border_cells * cw,
        np.minimum(y, height - y) - border_cells * ch,
    )
    room.flags.writeable = False
    return room


def entering(field: NormalFlowField, flow_px: np.ndarray, config: AnimateConfig) -> np.ndarray:
    """Cells whose content may have been outside the frame a frame ago.

    A point within ``border_cells`` cells plus its own normal flow of the
    frame edge may have entered since the last frame, so nothing predicted
    it: the frame edge is an occluder that every moving camera uncovers.

    Returns
    -------
    (64, 64) ndarray of bool
    """
    edge = _room_inside(field.geometry, config.border_cells)
    return edge < np.abs(flow_px)


class AnimateDetector:
    """Flags motion that breaks the smooth continuation of the previous frame's.

    State: the previous frame's constraint map and per-block uniform flows.
    """

    name = NAME
    measurement = "normal"
    config_type = AnimateConfig

    def __init__(self, config: AnimateConfig | None = None, egomotion=None) -> None:
        self.config = config or AnimateConfig()
        self._map: np.ndarray | None = None
        self._blocks: np.ndarray | None = None

    def reset(self) -> None:
        self._map, self._blocks = None, None

    def process(self, field: NormalFlowField, frame_index: int = 0) -> DetectorOutput:
        cfg = self.config
        shape = field.flow_px.shape
        flow = field.flow_px
        extra: dict = {}
        map_, previous_blocks = self._map, self._blocks
        current_blocks = block_flows(field) if cfg.jitter_compensation else None
        if cfg.jitter_compensation and previous_blocks is not None and map_ is not None:
            delta = jitter_shift(previous_blocks, current_blocks)
            nx, ny = field.normal
            flow = flow - (delta[0] * nx + delta[1] * ny).astype(np.float32)
            cw, ch = field.geometry.cell_px
            map_ = shift(map_, int(np.rint(delta[1] / ch)), int(np.rint(delta[0] / cw)))
            extra["jitter_px"] = [round(float(delta[0]), 3), round(float(delta[1]), 3)]
        self._map = constraint_map(field, cfg)
        self._blocks = current_blocks
        empty = np.zeros(shape, bool)
        if map_ is None:
            return DetectorOutput(empty, empty.astype(np.float32), [], extra=extra)
        tol = np.maximum(
            cfg.noise_sigmas * measurement_tolerance(field, cfg.noise_grey, 0.0),
            cfg.tolerance_floor_px,
        )
        theta, sign = field.orientation
        orientation, cand = candidate_slots(
            theta, sign * flow, tol, cfg.accel_px, cfg.accel_relative
        )
        allowed = map_slot(map_, orientation)
        covered = allowed != 0
        tested = field.valid & (field.gradient >= cfg.min_gradient) & ~entering(field, flow, cfg)
        violation = tested & covered & ((allowed & cand) == 0)
        if cfg.first_appearance == "flag":
            violation |= tested & ~covered & (np.abs(flow) > cfg.still_px + tol)
        flagged = drop_isolated(violation, cfg.min_neighbours)
        speed = np.abs(flow)
        strength = np.where(flagged, speed / (speed + tol), 0.0).astype(np.float32)
        regions = find_regions(
            flagged, strength, field.geometry, min_cells=cfg.min_cells, detector=NAME
        )
        return DetectorOutput(flagged, strength, regions, extra=extra)
