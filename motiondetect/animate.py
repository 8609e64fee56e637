"""Detector 2: animate motion (section 4 of the paper).

Under smooth observer motion the image motion of a rigid point changes
slowly. Each valid cell at frame t-1 predicts where its world point may be
at t (its *footprint*) and flags those cells with its motion value; at t a
measured value that no footprint allowed is animate motion.

* **Values** are coarsely bit-encoded: the normal-flow vector ``m n`` falls
  in one of 8 direction bins x 6 magnitude bins, or the "still" bit; one bit
  each of a 64-bit word.
* **Footprints** (Figure 8): with only the normal component known, the
  point moved ``m`` along ``n`` and anything up to the speed bound along the
  constraint line, so the footprint is a bar across the flow, displaced by
  the flow, extended back through and a little beyond the generating point
  (the counterflow side) so that objects emerging from behind an occluder
  predict their own appearance.
* **Constraint map**: the footprints' bits OR together per cell.
* **Violations**: a measurement whose tolerance-widened candidate bits
  share none with the map. A moving cell where no footprint landed at all
  is a *first appearance*; ``first_appearance`` says whether to flag it.
* **Jitter**: section 4.2 warns that rotational jitter breaks smoothness.
  With ``jitter_compensation`` the frame's global flow is estimated, and its
  change since the previous frame is removed from the measurements and the
  map is shifted by it.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import Literal

import numpy as np

from .constraint_ray import DetectorOutput
from .hough import measurement_tolerance
from .pipeline import GridGeometry, NormalFlowField
from .regions import drop_isolated, find_regions

NAME = "animate"

VALUE_DIRECTIONS = 8
MAGNITUDE_EDGES_PX = np.array([0.6, 1.2, 2.4, 4.8, 9.6])  # bins: <0.6, ..., >= 9.6 (above still)
VALUE_MAGNITUDES = len(MAGNITUDE_EDGES_PX) + 1
STILL_BIT = VALUE_DIRECTIONS * VALUE_MAGNITUDES  # 48
FOOTPRINT_DIRECTIONS = 16  # finer, for the footprint geometry only
STENCIL_RADIUS = 4  # cells


@dataclass(frozen=True)
class AnimateConfig:
    """Settings of the animate-motion detector.

    Attributes
    ----------
    max_speed_px : float
        Speed bound of a rigid point, work px/frame: how far along the
        constraint line the footprint reaches.
    counterflow_cells : float
        How far the footprint extends behind its generating point, cells.
    still_px : float
        Normal flow below this is the "still" value.
    noise_grey, noise_sigmas, tolerance_floor_px : float
        Measurement tolerance, ``noise_sigmas * noise_grey / |grad I|``
        with a floor.
    accel_bins : int
        Extra magnitude bins a value may move by between frames.
    accel_relative : float
        Relative change of ``|m|`` allowed between frames (smooth change).
    first_appearance : {"ignore", "flag"}
        Motion where no footprint landed: ignored (default: at weak-texture
        borders it is mostly noise), or flagged as the paper suggests.
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
    still_px: float = 0.3
    noise_grey: float = 1.0
    noise_sigmas: float = 2.0
    tolerance_floor_px: float = 0.2
    accel_bins: int = 0
    accel_relative: float = 0.5
    first_appearance: Literal["ignore", "flag"] = "ignore"
    jitter_compensation: bool = True
    min_gradient: float = 1.0
    border_cells: int = 2
    min_neighbours: int = 2
    min_cells: int = 3

    def __post_init__(self) -> None:
        if self.first_appearance not in ("ignore", "flag"):
            raise ValueError(
                f"first_appearance must be 'ignore' or 'flag', but got {self.first_appearance!r}"
            )
        for name in ("max_speed_px", "still_px", "noise_grey", "noise_sigmas"):
            if getattr(self, name) <= 0:
                raise ValueError(f"{name} must be positive, but got {getattr(self, name)}")
        if self.counterflow_cells < 0 or self.accel_bins < 0:
            raise ValueError("counterflow_cells and accel_bins must not be negative")


# ----------------------------------------------------------------------------
# Value encoding
# ----------------------------------------------------------------------------


def flow_vector_angle(flow_px: np.ndarray, direction_rad: np.ndarray) -> np.ndarray:
    """Angle of the vector ``m n`` (points against n when m < 0)."""
    return np.where(flow_px >= 0, direction_rad, direction_rad + np.pi)


def _codes(
    flow_px: np.ndarray, direction_rad: np.ndarray, still_px: float
) -> tuple[np.ndarray, np.ndarray]:
    """Value bit (8 directions) and footprint class (16 directions) of each
    measurement, sharing one angle and one magnitude-bin computation."""
    angle = flow_vector_angle(flow_px, direction_rad)
    speed = np.abs(flow_px)
    mag = np.searchsorted(MAGNITUDE_EDGES_PX, speed, side="right")
    still = speed < still_px

    def direction_bin(n: int) -> np.ndarray:
        return np.rint(angle / (2 * np.pi / n)).astype(np.int64) % n

    bits = np.where(still, STILL_BIT, direction_bin(VALUE_DIRECTIONS) * VALUE_MAGNITUDES + mag)
    classes = np.where(
        still,
        FOOTPRINT_DIRECTIONS * VALUE_MAGNITUDES,
        direction_bin(FOOTPRINT_DIRECTIONS) * VALUE_MAGNITUDES + mag,
    )
    return bits, classes


def value_bits(flow_px: np.ndarray, direction_rad: np.ndarray, still_px: float) -> np.ndarray:
    """Bit index (0..48) of each measured value."""
    return _codes(flow_px, direction_rad, still_px)[0]


def decode_bit(bit: int) -> tuple[str, int, int]:
    """('still', -1, -1) or ('moving', direction bin, magnitude bin)."""
    if bit == STILL_BIT:
        return ("still", -1, -1)
    return ("moving", bit // VALUE_MAGNITUDES, bit % VALUE_MAGNITUDES)


def encode_bit(direction_bin: int, magnitude_bin: int) -> int:
    return direction_bin * VALUE_MAGNITUDES + magnitude_bin


_ONE = np.uint64(1)


def candidate_bits(
    flow_px: np.ndarray,
    direction_rad: np.ndarray,
    tolerance: np.ndarray,
    still_px: float,
    accel_bins: int,
    accel_relative: float = 0.0,
) -> np.ndarray:
    """Every bit a measurement, widened by its tolerance, could have had before.

    Returns
    -------
    (…) ndarray of uint64
    """
    speed = np.abs(flow_px)
    lo = np.maximum(speed / (1 + accel_relative) - tolerance, 0.0)
    hi = speed * (1 + accel_relative) + tolerance
    mag_lo = np.maximum(np.searchsorted(MAGNITUDE_EDGES_PX, lo, side="right") - accel_bins, 0)
    mag_hi = np.minimum(
        np.searchsorted(MAGNITUDE_EDGES_PX, hi, side="right") + accel_bins, VALUE_MAGNITUDES - 1
    )
    mag_mask = ((_ONE << (mag_hi.astype(np.uint64) + _ONE)) - _ONE) & ~(
        (_ONE << mag_lo.astype(np.uint64)) - _ONE
    )
    angle = flow_vector_angle(flow_px, direction_rad)
    centre = np.rint(angle / (2 * np.pi / VALUE_DIRECTIONS)).astype(np.int64)
    uncertain = lo < still_px  # direction unknown near zero: any direction
    out = np.zeros(flow_px.shape, np.uint64)
    for d in range(VALUE_DIRECTIONS):
        near = (np.abs(((centre - d + 4) % VALUE_DIRECTIONS) - 4) <= 1) | uncertain
        out |= np.where(near, mag_mask << np.uint64(d * VALUE_MAGNITUDES), np.uint64(0))
    out |= np.where(lo < still_px, _ONE << np.uint64(STILL_BIT), np.uint64(0))
    return out


# ----------------------------------------------------------------------------
# Footprints
# ----------------------------------------------------------------------------


def footprint_cells(
    displacement_px: float,
    angle_rad: float,
    cell_px: tuple[float, float],
    max_speed_px: float,
    counterflow_cells: float,
) -> np.ndarray:
    """Cell offsets (dy, dx) covered by one footprint (Figure 8, right).

    The point moved ``displacement_px`` along ``angle_rad`` and up to
    ``sqrt(max_speed^2 - displacement^2)`` either way across it; the
    footprint is that bar, extended back through the generating point by
    ``counterflow_cells``, dilated by half a cell diagonal.

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
    da = np.clip(a, -back, displacement_px) - a
    db = np.clip(b, -reach, reach) - b
    inside = np.hypot(da, db) <= half_cell
    return np.stack([dy[inside], dx[inside]], axis=1)


@lru_cache(maxsize=16)
def stencil_table(
    geometry: GridGeometry, max_speed_px: float, counterflow_cells: float, still_px: float
) -> tuple[np.ndarray, np.ndarray]:
    """Which offsets each footprint class covers.

    Classes: ``dir * VALUE_MAGNITUDES + mag`` for 16 footprint directions,
    then one "still" class. Each class uses the upper edge of its magnitude
    bin (the footprint must reach as far as the fastest value in it).

    Returns
    -------
    offsets : (O, 2) ndarray of int
    covers : (O, classes) ndarray of bool
    """
    r = STENCIL_RADIUS
    dy, dx = np.mgrid[-r : r + 1, -r : r + 1]
    offsets = np.stack([dy.ravel(), dx.ravel()], axis=1)
    index = {tuple(o): i for i, o in enumerate(offsets)}
    upper = np.append(MAGNITUDE_EDGES_PX, max_speed_px)
    n_classes = FOOTPRINT_DIRECTIONS * VALUE_MAGNITUDES + 1
    covers = np.zeros((len(offsets), n_classes), bool)
    for d in range(FOOTPRINT_DIRECTIONS):
        angle = d * 2 * np.pi / FOOTPRINT_DIRECTIONS
        for m in range(VALUE_MAGNITUDES):
            cells = footprint_cells(
                min(upper[m], max_speed_px),
                angle,
                geometry.cell_px,
                max_speed_px,
                counterflow_cells,
            )
            for cell in cells:
                covers[index[tuple(cell)], d * VALUE_MAGNITUDES + m] = True
    for cell in footprint_cells(0.0, 0.0, geometry.cell_px, still_px, counterflow_cells):
        covers[index[tuple(cell)], -1] = True
    used = covers.any(axis=1)
    return offsets[used], covers[used]


def footprint_classes(
    flow_px: np.ndarray, direction_rad: np.ndarray, still_px: float
) -> np.ndarray:
    """Stencil class of each measurement (see :func:`stencil_table`)."""
    return _codes(flow_px, direction_rad, still_px)[1]


def shift(a: np.ndarray, dy: int, dx: int) -> np.ndarray:
    """``out[y + dy, x + dx] = a[y, x]``, zero-filled."""
    out = np.zeros_like(a)
    h, w = a.shape
    ys, yd = (slice(0, h - dy), slice(dy, h)) if dy >= 0 else (slice(-dy, h), slice(0, h + dy))
    xs, xd = (slice(0, w - dx), slice(dx, w)) if dx >= 0 else (slice(-dx, w), slice(0, w + dx))
    out[yd, xd] = a[ys, xs]
    return out


def constraint_map(field: NormalFlowField, config: AnimateConfig) -> np.ndarray:
    """OR every valid cell's value bit over its footprint.

    Returns
    -------
    (64, 64) ndarray of uint64
    """
    offsets, covers = stencil_table(
        field.geometry, config.max_speed_px, config.counterflow_cells, config.still_px
    )
    bits, classes = _codes(field.flow_px, field.direction_rad, config.still_px)
    word = np.where(field.valid, _ONE << bits.astype(np.uint64), np.uint64(0))
    out = np.zeros(word.shape, np.uint64)
    for (dy, dx), cover in zip(offsets, covers):
        contrib = np.where(cover[classes], word, np.uint64(0))
        out |= shift(contrib, int(dy), int(dx))
    return out


def global_flow(field: NormalFlowField, iterations: int = 2) -> np.ndarray:
    """Robust least-squares uniform flow (vx, vy) explaining the normal flow."""
    nx, ny = field.normal
    v = field.valid
    if v.sum() < 16:
        return np.zeros(2)
    n = np.stack([nx[v], ny[v]], axis=1).astype(np.float64)
    m = field.flow_px[v].astype(np.float64)
    w = np.ones_like(m)
    sol = np.zeros(2)
    for _ in range(iterations):
        a = (n * w[:, None]).T @ n
        if np.linalg.det(a) < 1e-6:
            break
        sol = np.linalg.solve(a, (n * w[:, None]).T @ m)
        r = np.abs(n @ sol - m)
        scale = max(1.4826 * np.median(r), 0.1)
        w = np.minimum(1.0, 1.5 * scale / np.maximum(r, 1e-9))  # Huber weights
    return sol


class AnimateDetector:
    """Flags motion that breaks the smooth continuation of the previous frame's.

    State: the previous frame's constraint map and global flow.
    """

    name = NAME

    def __init__(self, config: AnimateConfig | None = None) -> None:
        self.config = config or AnimateConfig()
        self._map: np.ndarray | None = None
        self._global: np.ndarray | None = None

    def reset(self) -> None:
        self._map, self._global = None, None

    def process(self, field: NormalFlowField, frame_index: int = 0) -> DetectorOutput:
        cfg = self.config
        shape = field.flow_px.shape
        flow = field.flow_px
        extra: dict = {}
        map_, previous_global = self._map, self._global
        current_global = global_flow(field) if cfg.jitter_compensation else None
        if cfg.jitter_compensation and previous_global is not None and map_ is not None:
            delta = current_global - previous_global
            nx, ny = field.normal
            flow = flow - (delta[0] * nx + delta[1] * ny).astype(np.float32)
            cw, ch = field.geometry.cell_px
            map_ = shift(map_, int(np.rint(delta[1] / ch)), int(np.rint(delta[0] / cw)))
            extra["jitter_px"] = [round(float(delta[0]), 3), round(float(delta[1]), 3)]
        self._map = constraint_map(field, cfg)
        self._global = current_global
        empty = np.zeros(shape, bool)
        if map_ is None:
            return DetectorOutput(empty, empty.astype(np.float32), [], extra=extra)
        tol = np.maximum(
            cfg.noise_sigmas * measurement_tolerance(field, cfg.noise_grey, 0.0),
            cfg.tolerance_floor_px,
        )
        cand = candidate_bits(
            flow, field.direction_rad, tol, cfg.still_px, cfg.accel_bins, cfg.accel_relative
        )
        covered = map_ != 0
        tested = field.valid & (field.gradient >= cfg.min_gradient)
        b = cfg.border_cells
        if b > 0:
            tested[:b], tested[-b:], tested[:, :b], tested[:, -b:] = False, False, False, False
        violation = tested & covered & ((map_ & cand) == 0)
        if cfg.first_appearance == "flag":
            violation |= tested & ~covered & (np.abs(flow) > cfg.still_px + tol)
        flagged = drop_isolated(violation, cfg.min_neighbours)
        speed = np.abs(flow)
        strength = np.where(flagged, speed / (speed + tol), 0.0).astype(np.float32)
        regions = find_regions(
            flagged, strength, field.geometry, min_cells=cfg.min_cells, detector=NAME
        )
        return DetectorOutput(flagged, strength, regions, extra=extra)
