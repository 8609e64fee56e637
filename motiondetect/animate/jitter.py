"""Rotational jitter of a handheld camera, for detector 2 (section 4).

Jitter adds one image shift to every block's flow at once, while smooth
observer motion changes each block's flow slowly; the detector removes the
shift before it compares values.
"""

from __future__ import annotations

import numpy as np

from motiondetect.measurement.normal_flow import NormalFlowField

JITTER_BLOCKS = 4


def block_flows(field: NormalFlowField, blocks: int = JITTER_BLOCKS) -> np.ndarray:
    """Least-squares uniform flow (vx, vy) of each of ``blocks x blocks``
    blocks, from ``m = v . n`` over its valid cells; NaN where a block has too
    few cells or too narrow a spread of gradient orientations to fix both
    components.

    Returns
    -------
    (blocks, blocks, 2) ndarray of float64
    """
    nx, ny = (np.asarray(c, np.float64) for c in field.normal)
    w = field.valid.astype(np.float64)
    m = field.flow_px.astype(np.float64) * w
    h, wd = w.shape
    terms = np.stack([nx * nx * w, nx * ny * w, ny * ny * w, nx * m, ny * m, w])
    sums = terms.reshape(6, blocks, h // blocks, blocks, wd // blocks).sum(axis=(2, 4))
    sxx, sxy, syy, bx, by, count = sums
    det = sxx * syy - sxy * sxy
    ok = (count >= 16) & (det > 0.1 * np.maximum(count, 1) ** 2 / 4)
    safe = np.where(ok, det, 1.0)
    vx = (syy * bx - sxy * by) / safe
    vy = (sxx * by - sxy * bx) / safe
    return np.where(ok[..., None], np.stack([vx, vy], axis=-1), np.nan)


def jitter_shift(previous: np.ndarray, current: np.ndarray) -> np.ndarray:
    """The frame's global image shift since the previous one, (dx, dy) px.

    Rotational jitter adds the same shift to every block's flow, while smooth
    observer motion changes each block's flow slowly; the median over blocks
    of the change keeps a mover in a few blocks from dragging the estimate.
    """
    change = (current - previous).reshape(-1, 2)
    change = change[np.isfinite(change).all(axis=1)]
    if len(change) < 4:
        return np.zeros(2)
    return np.median(change, axis=0)
