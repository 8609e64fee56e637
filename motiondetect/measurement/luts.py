"""The three MAX-MUX stages as 16-bit lookup tables over two 8-bit codes.

On the Datacube each MAX-MUX is a 65536-entry table addressed by two 8-bit
inputs. Here each table is a numpy array indexed by ``(a << 8) | b``; the
whole image goes through one fancy-indexing call, never a Python loop.

Codes (all 8-bit):

* blurred grey level: ``uint8`` 0..255 (the video signal itself);
* temporal difference: ``int8``, saturating at -128..127 grey levels;
* x and y gradient: ``int8``, log-companded (:func:`encode_gradient`), so
  that weak and strong gradients both keep about 3 % relative precision;
* gradient magnitude: ``uint8``, log-companded the same way;
* gradient direction: ``uint8``, 256 steps around the circle.

The float twins live in :mod:`motiondetect.measurement.stages`; ``docs/stages.md`` gives
the measured cost of the quantisation.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

GRADIENT_KNEE = 1.0  # grey/work px: below this the code is nearly linear
GRADIENT_MAX = 96.0  # grey/work px: largest encodable gradient component
FLOW_UNIT = 1.0 / 64.0  # work px per count of the int16 flow output
FLOW_INVALID = np.int16(-32768)

_LOG_SPAN = np.log1p(GRADIENT_MAX / GRADIENT_KNEE)
_ANGLE_STEP = 2.0 * np.pi / 256.0


def _compand(values: np.ndarray, levels: int) -> np.ndarray:
    return np.rint(levels * np.log1p(np.abs(values) / GRADIENT_KNEE) / _LOG_SPAN)


def _expand(codes: np.ndarray, levels: int) -> np.ndarray:
    return GRADIENT_KNEE * np.expm1(np.abs(codes) * _LOG_SPAN / levels)


def encode_grey(image: np.ndarray) -> np.ndarray:
    """Quantise a blurred float image to the 8-bit video signal."""
    return np.clip(np.rint(image), 0, 255).astype(np.uint8)


def encode_gradient(g: np.ndarray) -> np.ndarray:
    """Log-compand a gradient component (grey/work px) to a signed 8-bit code."""
    code = np.minimum(_compand(g, 127), 127)
    return (np.sign(g) * code).astype(np.int8)


def decode_gradient(code: np.ndarray) -> np.ndarray:
    """Inverse of :func:`encode_gradient`."""
    return (np.sign(code) * _expand(code.astype(np.float64), 127)).astype(np.float32)


def _index(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return (a.view(np.uint8).astype(np.uint16) << 8) | b.view(np.uint8)


@dataclass(frozen=True)
class MaxMuxTables:
    """The contents of the three MAX-MUX units for one ``min_gradient``."""

    difference: np.ndarray  # (65536,) int8   MAX-MUX 1, high byte
    average: np.ndarray  # (65536,) uint8      MAX-MUX 1, low byte
    magnitude: np.ndarray  # (65536,) uint8    MAX-MUX 2, high byte
    direction: np.ndarray  # (65536,) uint8    MAX-MUX 2, low byte
    flow: np.ndarray  # (65536,) int16         MAX-MUX 3
    magnitude_decode: np.ndarray  # (256,) float32

    @staticmethod
    @lru_cache(maxsize=8)
    def build(min_gradient: float) -> MaxMuxTables:
        codes = np.arange(256)
        a = codes.repeat(256)  # high byte
        b = np.tile(codes, 256)  # low byte
        # MAX-MUX 1: a = previous, b = current grey level.
        difference = np.clip(b - a, -128, 127).astype(np.int8)
        average = ((a + b + 1) // 2).astype(np.uint8)
        # MAX-MUX 2: a = gx code, b = gy code (both int8 bit patterns).
        gx = decode_gradient(a.astype(np.uint8).view(np.int8))
        gy = decode_gradient(b.astype(np.uint8).view(np.int8))
        mag = np.hypot(gx, gy)
        magnitude = np.minimum(_compand(mag, 255), 255).astype(np.uint8)
        angle = np.mod(np.arctan2(gy, gx), 2 * np.pi)
        direction = (np.rint(angle / _ANGLE_STEP).astype(np.int64) % 256).astype(np.uint8)
        # MAX-MUX 3: a = difference code (int8), b = magnitude code.
        magnitude_decode = _expand(codes.astype(np.float64), 255).astype(np.float32)
        dt = a.astype(np.uint8).view(np.int8).astype(np.float64)
        mag_b = magnitude_decode[b].astype(np.float64)
        with np.errstate(divide="ignore", invalid="ignore"):
            m = np.clip(np.rint(-dt / mag_b / FLOW_UNIT), -32767, 32767)
        flow = np.where(mag_b >= min_gradient, m, FLOW_INVALID).astype(np.int16)
        return MaxMuxTables(difference, average, magnitude, direction, flow, magnitude_decode)


def difference_and_average_lut(
    previous: np.ndarray, current: np.ndarray, tables: MaxMuxTables
) -> tuple[np.ndarray, np.ndarray]:
    """MAX-MUX 1 by table: (int8 difference, uint8 average) from two uint8 frames."""
    idx = _index(previous, current)
    return tables.difference[idx], tables.average[idx]


def gradient_polar_lut(
    gx: np.ndarray, gy: np.ndarray, tables: MaxMuxTables
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """MAX-MUX 2 by table.

    Parameters
    ----------
    gx, gy : (H, W) ndarray of float32
        Convolution outputs, grey/work px; quantised here to 8-bit codes.

    Returns
    -------
    magnitude_code : (H, W) ndarray of uint8
    magnitude : (H, W) ndarray of float32, decoded, grey/work px
    direction_rad : (H, W) ndarray of float32 in [-pi, pi)
    """
    idx = _index(encode_gradient(gx), encode_gradient(gy))
    mag_code = tables.magnitude[idx]
    dir_code = tables.direction[idx].astype(np.float32)
    direction = np.mod(
        dir_code * np.float32(_ANGLE_STEP) + np.float32(np.pi), np.float32(2 * np.pi)
    ) - np.float32(np.pi)
    return mag_code, tables.magnitude_decode[mag_code], direction


def normal_flow_lut(
    difference: np.ndarray, magnitude_code: np.ndarray, tables: MaxMuxTables
) -> tuple[np.ndarray, np.ndarray]:
    """MAX-MUX 3 by table: normal flow (work px/frame, float32) and validity."""
    raw = tables.flow[_index(difference, magnitude_code)]
    valid = raw != FLOW_INVALID
    flow = np.where(valid, raw.astype(np.float32) * np.float32(FLOW_UNIT), np.float32(0.0))
    return flow, valid


class BinTable:
    """``np.searchsorted(edges, x, side="right")`` by one table lookup.

    For bin edges that lie on a grid of ``step`` (plus optional infinite
    ends): every ``x`` in ``[k step, (k + 1) step)`` falls in the same bin,
    so the bin is a table entry indexed by ``floor(x / step)``. Beyond
    ``+-limit`` finite values saturate; infinities and NaN land where
    ``searchsorted`` puts them.
    """

    def __init__(self, edges: np.ndarray, step: float, limit: float) -> None:
        finite = np.asarray(edges)[np.isfinite(edges)]
        on_grid = np.abs(finite / step - np.rint(finite / step)) < 1e-9
        if not on_grid.all() or np.abs(finite).max() >= limit:
            raise ValueError("edges must lie on the step grid, inside +-limit")
        self.scale = 1.0 / step
        self.range = int(np.ceil(limit / step))
        centres = (np.arange(-self.range, self.range + 1) + 0.5) * step
        centres = np.append(centres, np.inf)
        self.table = np.searchsorted(edges, centres, side="right").astype(np.int64)

    def __call__(self, x: np.ndarray) -> np.ndarray:
        index = np.floor(np.asarray(x) * self.scale)
        # finite values saturate; +inf and NaN (which sorts last) take the extra entry
        index = np.where(
            np.isfinite(index) | (index < 0),
            np.clip(index, -self.range, self.range),
            self.range + 1,
        )
        return self.table[index.astype(np.int64) + self.range]
