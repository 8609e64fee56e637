"""The normal-flow pipeline: stages wired as in Figure 10, plus the frame delay.

:class:`NormalFlowPipeline` is the only stateful piece of the measurement
side. It holds the previous blurred frame (the ROISTORE delay) and turns
each new frame into a :class:`NormalFlowField` on the 64x64 grid.

Grid mapping: the 64x64 grid always covers the whole frame. On a non-square
frame each cell is a rectangle of ``(W/64) x (H/64)`` pixels; flow,
gradients and directions are still expressed in isotropic working pixels
(the derivative convolutions divide by the true spacing of each axis).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Literal

import numpy as np

from motiondetect.measurement import luts, stages
from motiondetect.measurement.stages import GRID


@dataclass(frozen=True)
class StageConfig:
    """Settings of the measurement stages.

    Attributes
    ----------
    work_size : int
        Long side of the working resolution, pixels. Flow is measured in
        pixels of this resolution.
    blur_sigma_px : float
        Standard deviation of each of the two cascaded blur passes, work px.
    derivative_grid : int
        Size per axis of the grid on which differences and gradients are
        taken: 64 * k. The blurred frame is area-averaged onto it first
        (docs/stages.md measures this against full resolution).
    min_gradient : float
        Gradient magnitude (grey levels per work px) below which the normal
        flow is marked invalid.
    arithmetic : {"float", "lut"}
        Float reference stages, or the three MAX-MUX lookup tables over
        8-bit codes.
    pyramid : bool
        Add a coarser level (half the grid, twice the blur) and use it in the
        cells whose motion exceeds ``fine_band_px``.
    fine_band_px : float
        Largest normal-flow magnitude (work px/frame) trusted at the fine
        level when the pyramid is on.
    border_cells : int
        Rings of cells at the frame edge marked invalid: there the blur and
        derivative kernels reach past the frame and content enters or leaves.
    prereduce : bool
        Area-reduce the working frame by 2 before the blur (with half the
        sigma) when it is at least twice the derivative grid.
    """

    work_size: int = 512
    blur_sigma_px: float = 4.0
    derivative_grid: int = 128
    min_gradient: float = 1.0
    arithmetic: Literal["float", "lut"] = "float"
    pyramid: bool = True
    fine_band_px: float = 4.0
    border_cells: int = 1
    prereduce: bool = True

    def __post_init__(self) -> None:
        if self.work_size < stages.MIN_FRAME_SIDE:
            raise ValueError(f"work_size must be at least 64, but got {self.work_size}")
        if self.blur_sigma_px <= 0:
            raise ValueError(f"blur_sigma_px must be positive, but got {self.blur_sigma_px}")
        if self.derivative_grid % GRID or not 64 <= self.derivative_grid <= 1024:
            raise ValueError(
                f"derivative_grid must be a multiple of 64 in 64..1024, "
                f"but got {self.derivative_grid}"
            )
        if self.min_gradient <= 0:
            raise ValueError(f"min_gradient must be positive, but got {self.min_gradient}")
        if self.arithmetic not in ("float", "lut"):
            raise ValueError(f"arithmetic must be 'float' or 'lut', but got {self.arithmetic!r}")
        if self.fine_band_px <= 0:
            raise ValueError(f"fine_band_px must be positive, but got {self.fine_band_px}")


@dataclass(frozen=True)
class GridGeometry:
    """How the 64x64 grid maps onto the input and working frames."""

    input_size: tuple[int, int]  # (width, height) px
    work_size: tuple[int, int]  # (width, height) work px

    @property
    def cell_px(self) -> tuple[float, float]:
        """Cell (width, height) in work px."""
        return self.work_size[0] / GRID, self.work_size[1] / GRID

    @property
    def input_cell_px(self) -> tuple[float, float]:
        """Cell (width, height) in input px."""
        return self.input_size[0] / GRID, self.input_size[1] / GRID

    def cell_box_to_input(self, col0: int, row0: int, cols: int, rows: int) -> list[int]:
        """[x, y, w, h] in input pixels of a block of cells."""
        cw, ch = self.input_cell_px
        x0, y0 = round(col0 * cw), round(row0 * ch)
        x1, y1 = round((col0 + cols) * cw), round((row0 + rows) * ch)
        return [x0, y0, x1 - x0, y1 - y0]

    def cell_centres_px(self) -> tuple[np.ndarray, np.ndarray]:
        """(x, y) of every cell centre, work px, each (64, 64) float32."""
        cw, ch = self.cell_px
        x = (np.arange(GRID, dtype=np.float32) + 0.5) * cw
        y = (np.arange(GRID, dtype=np.float32) + 0.5) * ch
        return np.meshgrid(x, y)


@dataclass(frozen=True)
class NormalFlowField:
    """What the detectors consume: one frame's 64x64 normal flow.

    Attributes
    ----------
    flow_px : (64, 64) ndarray of float32
        Normal flow, work px/frame, signed along ``direction_rad``.
    direction_rad : (64, 64) ndarray of float32
        Gradient direction, radians in [-pi, pi], image coordinates.
    gradient : (64, 64) ndarray of float32
        Gradient magnitude, grey levels per work px (the noise of
        ``flow_px`` scales as 1 / gradient).
    valid : (64, 64) ndarray of bool
    level : (64, 64) ndarray of uint8
        Pyramid level each cell came from (0 fine, 1 coarse).
    geometry : GridGeometry
    since : int, optional
        Index of the frame the flow was measured from, attached when judged;
        None: the frame before. Known ego-motion spans the same frames.
    """

    flow_px: np.ndarray
    direction_rad: np.ndarray
    gradient: np.ndarray
    valid: np.ndarray
    level: np.ndarray
    geometry: GridGeometry
    since: int | None = None

    @cached_property
    def normal(self) -> tuple[np.ndarray, np.ndarray]:
        """Unit gradient direction (nx, ny), each (64, 64) float32 (computed once)."""
        return np.cos(self.direction_rad), np.sin(self.direction_rad)

    @cached_property
    def orientation(self) -> tuple[np.ndarray, np.ndarray]:
        """(theta, sign): the gradient orientation folded into [0, pi) and
        +-1 such that ``(theta, sign * flow_px)`` is the same measurement.
        Computed once per frame and shared by both detectors."""
        return fold_orientation(self.direction_rad)


DIRECTION_BINS = 16  # over [0, pi): (n, m) and (-n, -m) are the same measurement


def direction_bin(theta: np.ndarray) -> np.ndarray:
    """Bin 0..15 of an orientation in [0, pi)."""
    return np.minimum((theta * (DIRECTION_BINS / np.pi)).astype(np.intp), DIRECTION_BINS - 1)


def measurement_tolerance(field: NormalFlowField, noise_grey: float, floor_px: float) -> np.ndarray:
    """Per-cell noise tolerance of ``flow_px``: noise / |grad I|, with a floor.

    The normal-flow error grows like 1/|grad I| (docs/maths.md), so a fixed
    tolerance would be too strict on weak edges and too loose on strong ones.
    """
    grad = np.maximum(field.gradient, 1e-3)
    return np.maximum(np.float32(floor_px), np.float32(noise_grey) / grad)


def fold_orientation(direction_rad: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Fold gradient directions into orientations in [0, pi).

    ``(n, m)`` and ``(-n, -m)`` are the same measurement, so a direction
    outside [0, pi) turns by pi and its normal flow changes sign.

    Returns
    -------
    theta : ndarray, like ``direction_rad``
    sign : ndarray of +-1, like ``direction_rad``
    """
    d = np.asarray(direction_rad)
    below, above = d < 0, d >= np.pi
    theta = np.where(below, d + np.pi, np.where(above, d - np.pi, d))
    sign = np.where(below | above, -1, 1).astype(d.dtype if d.dtype.kind == "f" else np.float64)
    return theta, sign


def fold_direction(direction_rad: np.ndarray, flow_px: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Map (direction, m) to the equivalent (theta, m') with theta in [0, pi)."""
    theta, sign = fold_orientation(direction_rad)
    return theta, sign * flow_px


def measure_level(
    previous: np.ndarray,
    current: np.ndarray,
    spacing_px: tuple[float, float],
    config: StageConfig,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """MAX-MUX 1, the derivative convolutions, MAX-MUX 2 and MAX-MUX 3.

    Parameters
    ----------
    previous, current : (R, C) ndarray of float32
        Delayed and current blurred frames on the derivative grid.
    spacing_px : (float, float)
        Grid spacing (dx, dy) in work px.

    Returns
    -------
    flow_px, direction_rad, gradient, valid : (R, C) ndarrays
    """
    if config.arithmetic == "lut":
        tables = luts.MaxMuxTables.build(config.min_gradient)
        diff, avg = luts.difference_and_average_lut(
            luts.encode_grey(previous), luts.encode_grey(current), tables
        )
        gx, gy = stages.gradients(avg.astype(np.float32), spacing_px)
        mag_code, magnitude, direction = luts.gradient_polar_lut(gx, gy, tables)
        flow, valid = luts.normal_flow_lut(diff, mag_code, tables)
        return flow, direction, magnitude, valid
    diff, avg = stages.difference_and_average(previous, current)
    gx, gy = stages.gradients(avg, spacing_px)
    magnitude, direction = stages.gradient_polar(gx, gy)
    flow, valid = stages.normal_flow(diff, magnitude, config.min_gradient)
    return flow, direction, magnitude, valid


class NormalFlowPipeline:
    """Frames in, 64x64 normal-flow fields out.

    The one-frame delay (the first ROISTORE) is the only state. The first
    frame, and the first frame after :meth:`reset`, returns ``None``.

    Parameters
    ----------
    config : StageConfig
    """

    def __init__(self, config: StageConfig | None = None) -> None:
        self.config = config or StageConfig()
        self._delayed: tuple[np.ndarray, ...] | None = None
        self._geometry: GridGeometry | None = None

    def reset(self) -> None:
        """Forget the delayed frame (e.g. after a cut or a decode gap)."""
        self._delayed = None

    def geometry_for(self, width: int, height: int) -> GridGeometry:
        work = stages.working_size(width, height, self.config.work_size)
        return GridGeometry((width, height), work)

    def _levels(self, frame: np.ndarray, geometry: GridGeometry) -> tuple[np.ndarray, ...]:
        cfg = self.config
        grey = stages.to_working_size(stages.to_grey(frame), geometry.work_size)
        # The blur is wide (sigma 4 work px): blurring a 2x area-reduced frame
        # with half the sigma gives the same signal on the derivative grid at
        # a quarter of the cost (docs/performance.md measures both).
        grid = (cfg.derivative_grid, cfg.derivative_grid)
        factor = 2 if (cfg.prereduce and min(grey.shape) >= 2 * cfg.derivative_grid) else 1
        if factor > 1:
            half = (grey.shape[1] // 2, grey.shape[0] // 2)
            grey = stages.to_working_size(grey.astype(np.float32, copy=False), half)
        fine = stages.reduce_to_grid(stages.blur(grey, cfg.blur_sigma_px / factor), grid)
        if not cfg.pyramid:
            return (fine,)
        sx, sy = self._spacing(geometry, cfg.derivative_grid)
        # Twice the fine blur: measured best for 6-12 px/frame (docs/stages.md).
        coarse_sigma = 2.0 * cfg.blur_sigma_px / min(sx, sy)
        coarse = stages.reduce_to_grid(stages.blur(fine, coarse_sigma), (GRID, GRID))
        return fine, coarse

    @staticmethod
    def _spacing(geometry: GridGeometry, grid: int) -> tuple[float, float]:
        return geometry.work_size[0] / grid, geometry.work_size[1] / grid

    def process(self, frame: np.ndarray) -> NormalFlowField | None:
        """Push one frame through the stages.

        Parameters
        ----------
        frame : (H, W) or (H, W, C) ndarray of uint8 or uint16
            At least 64x64; grey, BGR or BGRA.

        Returns
        -------
        NormalFlowField or None
            None for the first frame (nothing to difference against yet).
        """
        stages.validate_frame(frame)
        h, w = frame.shape[:2]
        if self._geometry is None or self._geometry.input_size != (w, h):
            self._geometry = self.geometry_for(w, h)
            self._delayed = None
        levels = self._levels(frame, self._geometry)
        delayed, self._delayed = self._delayed, levels
        if delayed is None:
            return None
        return self._measure(delayed, levels, self._geometry)

    def _measure(
        self,
        delayed: tuple[np.ndarray, ...],
        current: tuple[np.ndarray, ...],
        geometry: GridGeometry,
    ) -> NormalFlowField:
        cfg = self.config
        spacing = self._spacing(geometry, cfg.derivative_grid)
        flow, direction, gradient, valid = measure_level(delayed[0], current[0], spacing, cfg)
        key = np.where(valid, gradient, -1.0).astype(np.float32)
        _, flow, direction, gradient, valid = stages.subsample(
            key, flow, direction, gradient, valid
        )
        level = np.zeros((GRID, GRID), np.uint8)
        if cfg.pyramid:
            c_flow, c_dir, c_grad, c_valid = measure_level(
                delayed[1], current[1], self._spacing(geometry, GRID), cfg
            )
            use = c_valid & (~valid | (np.abs(c_flow) > cfg.fine_band_px))
            flow = np.where(use, c_flow, flow)
            direction = np.where(use, c_dir, direction)
            gradient = np.where(use, c_grad, gradient)
            valid = valid | use
            level[use] = 1
        b = cfg.border_cells
        if b > 0:
            valid = valid.copy()
            valid[:b], valid[-b:], valid[:, :b], valid[:, -b:] = False, False, False, False
        return NormalFlowField(
            flow_px=flow.astype(np.float32, copy=False),
            direction_rad=direction.astype(np.float32, copy=False),
            gradient=gradient.astype(np.float32, copy=False),
            valid=valid,
            level=level,
            geometry=geometry,
        )
