"""Detector 2's values: what one normal-flow measurement is, as bits (section 4).

A value is the gradient orientation (mod pi, 8 bins) with the normal flow
signed along it (15 bins, finer near 0): 16 bits per orientation, two 64-bit
words per cell. The constraint map holds, per cell, the OR of the values the
previous frame's footprints predicted there.
"""

from __future__ import annotations

import numpy as np

from motiondetect.measurement.luts import BinTable
from motiondetect.measurement.normal_flow import DIRECTION_BINS, direction_bin

# Values: the gradient orientation (mod pi) in 8 bins x the signed normal flow
# along it in 15 bins; 16 bits per orientation, so two 64-bit words per cell.
ORIENTATIONS = 8
FLOW_EDGES_PX = np.array([0.4, 1.2, 2.2, 3.5, 5.0, 7.0, 9.5])
FLOW_EDGES_SIGNED = np.concatenate([-FLOW_EDGES_PX[::-1], FLOW_EDGES_PX])
FLOW_BINS = len(FLOW_EDGES_SIGNED) + 1  # 15; the middle one is "still"
SLOT_BITS = 16
WORDS = ORIENTATIONS * SLOT_BITS // 64  # 2
SLOTS_PER_WORD = 64 // SLOT_BITS  # 4


def orientation_bin(theta: np.ndarray) -> np.ndarray:
    """Bin 0..7 of an orientation in [0, pi): pairs of the filter's 16 bins."""
    return direction_bin(theta) // (DIRECTION_BINS // ORIENTATIONS)


#: Bin 0..14 of a signed normal flow; bin 7 is ``|m| < 0.4``.
flow_bin = BinTable(FLOW_EDGES_SIGNED, step=0.1, limit=10.0)


def encode_value(orientation: int, flow: int) -> tuple[int, int]:
    """(word, bit) of the value ``(orientation bin, flow bin)``."""
    slot = orientation % SLOTS_PER_WORD
    return orientation // SLOTS_PER_WORD, slot * SLOT_BITS + flow


def decode_value(word: int, bit: int) -> tuple[int, int]:
    """Inverse of :func:`encode_value`: (orientation bin, flow bin)."""
    return word * SLOTS_PER_WORD + bit // SLOT_BITS, bit % SLOT_BITS


_ONE = np.uint64(1)
_SLOT_MASK = np.uint64((1 << SLOT_BITS) - 1)
#: (2, 128): the two words with only bit i set, for i in 0..127.
_ONE_HOT = np.array(
    [[(1 << i) & (2**64 - 1), (1 << i) >> 64] for i in range(WORDS * 64)], np.uint64
).T.copy()


def value_words(theta: np.ndarray, m: np.ndarray) -> np.ndarray:
    """Bit-encoded value of each measurement, written into its orientation
    bin and the nearer neighbouring bin (with the sign of ``m`` flipped when
    that neighbour is across 0/pi), so that orientations closer than half a
    bin always share one.

    Parameters
    ----------
    theta, m : ndarray
        Folded measurements: orientation in [0, pi) and the normal flow
        signed along it (:func:`motiondetect.measurement.normal_flow.fold_direction`).

    Returns
    -------
    (2, …) ndarray of uint64
    """
    width = np.pi / ORIENTATIONS
    own = orientation_bin(theta)
    step = np.where(theta - own * width >= width / 2, 1, -1)
    other = own + step
    across = (other < 0) | (other >= ORIENTATIONS)
    first = own * SLOT_BITS + flow_bin(m)  # bit 0..127 over the two words
    second = (other % ORIENTATIONS) * SLOT_BITS + flow_bin(np.where(across, -m, m))
    return np.take(_ONE_HOT, first, axis=1) | np.take(_ONE_HOT, second, axis=1)


def candidate_slots(
    theta: np.ndarray,
    m: np.ndarray,
    tolerance: np.ndarray,
    accel_px: float,
    accel_relative: float,
) -> tuple[np.ndarray, np.ndarray]:
    """Orientation bin and the flow bits a measurement could have had one
    frame earlier under smooth motion: ``m`` widened by the noise tolerance,
    ``accel_px`` and ``accel_relative * |m|``. ``theta, m`` are folded, as
    for :func:`value_words`.

    Returns
    -------
    orientation : (…) ndarray of int
    bits : (…) ndarray of uint64, within a 16-bit slot
    """
    allowance = tolerance + accel_px + accel_relative * np.abs(m)
    lo = flow_bin(m - allowance).astype(np.uint64)
    hi = flow_bin(m + allowance).astype(np.uint64)
    bits = ((_ONE << (hi + _ONE)) - _ONE) & ~((_ONE << lo) - _ONE)
    return orientation_bin(theta), bits


def map_slot(map_: np.ndarray, orientation: np.ndarray) -> np.ndarray:
    """The 16 bits the constraint map holds for each cell's orientation bin."""
    word = np.take_along_axis(map_, (orientation // SLOTS_PER_WORD)[None], axis=0)[0]
    return (word >> (np.uint64(SLOT_BITS) * (orientation % SLOTS_PER_WORD).astype(np.uint64))) & (
        _SLOT_MASK
    )
