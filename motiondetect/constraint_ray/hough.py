"""The Hough step of section 3.3: normal flow to a coarse 4x4 motion field.

Each valid normal-flow measurement ``m`` along unit gradient ``n`` says the
true flow ``v`` lies on the constraint line ``v . n = m``. Every candidate
velocity collects the votes of the measurements whose line passes within
their noise tolerance of it; in each of the 4x4 regions the candidate with
most votes wins, is refined by least squares over its voters, and is
quantised to one of 8 directions (Figure 5).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from motiondetect.measurement.normal_flow import NormalFlowField, measurement_tolerance
from motiondetect.measurement.stages import GRID

REGIONS = 4
DIRECTIONS = 8
UNKNOWN, STILL = -1, DIRECTIONS  # codes in CoarseField.direction_index

_HOUGH_DIRECTIONS = 16
_HOUGH_SPEEDS_PX = np.array([0.3, 0.5, 0.8, 1.2, 1.8, 2.7, 4.0, 6.0, 9.0, 13.0], np.float32)


@dataclass(frozen=True)
class CoarseField:
    """The coarse field of Figure 5.

    Attributes
    ----------
    direction_index : (4, 4) ndarray of int8
        0..7 (k * 45 degrees, image coordinates, 0 = right, 2 = down),
        ``STILL`` (8) for no motion, ``UNKNOWN`` (-1) for too little data.
    flow_px : (4, 4, 2) ndarray of float32
        Refined (vx, vy) per region, work px/frame; zero when still/unknown.
    support : (4, 4) ndarray of float32
        Share of the region's valid measurements that voted for the winner.
    count : (4, 4) ndarray of int
        Valid measurements per region.
    inliers : (64, 64) ndarray of bool, optional
        Cells that voted for their region's winner.
    """

    direction_index: np.ndarray
    flow_px: np.ndarray
    support: np.ndarray
    count: np.ndarray
    inliers: np.ndarray | None = None

    @property
    def known(self) -> np.ndarray:
        return self.direction_index != UNKNOWN

    @property
    def moving(self) -> np.ndarray:
        return self.known & (self.direction_index != STILL)


def _candidates() -> np.ndarray:
    angles = np.arange(_HOUGH_DIRECTIONS) * (2 * np.pi / _HOUGH_DIRECTIONS)
    unit = np.stack([np.cos(angles), np.sin(angles)], axis=1)
    moving = (unit[None, :, :] * _HOUGH_SPEEDS_PX[:, None, None]).reshape(-1, 2)
    # Refinement by least squares recovers directions between these steps.
    return np.vstack([np.zeros((1, 2)), moving]).astype(np.float32)


_CANDIDATES = _candidates()


def _by_region(a: np.ndarray) -> np.ndarray:
    """(..., 64, 64) -> (..., 16, 256): the cells of each 4x4 region."""
    s = GRID // REGIONS
    lead = a.shape[:-2]
    return (
        a.reshape(*lead, REGIONS, s, REGIONS, s)
        .swapaxes(-3, -2)
        .reshape(*lead, REGIONS * REGIONS, s * s)
    )


def _refine(
    flow: np.ndarray, best: np.ndarray, best_speed: np.ndarray, voters: np.ndarray,
    n: np.ndarray, m: np.ndarray,
) -> np.ndarray:  # fmt: skip
    """Least-squares refinement of each region's winner over its voters.

    Solves ``(sum n n^T) v = sum n m``; kept only where the gradients span
    both axes and the result stays near the winner (an ill-posed region can
    run away).
    """
    a = np.einsum("irp,jrp,rp->rij", n, n, voters.astype(np.float32))
    b = np.einsum("irp,rp->ri", n, np.where(voters, m, 0.0))
    det = a[:, 0, 0] * a[:, 1, 1] - a[:, 0, 1] ** 2
    trace = a[:, 0, 0] + a[:, 1, 1]
    conditioned = det > 0.05 * trace**2  # gradients span both axes
    safe = np.where(conditioned, det, 1.0)
    vx = (a[:, 1, 1] * b[:, 0] - a[:, 0, 1] * b[:, 1]) / safe
    vy = (a[:, 0, 0] * b[:, 1] - a[:, 0, 1] * b[:, 0]) / safe
    refined = np.stack([vx, vy], axis=1)
    near = np.hypot(*(refined - flow).T) <= 0.5 * best_speed + 0.3
    refine = conditioned & (best > 0) & near
    flow[refine] = refined[refine]
    return flow


def coarse_field(
    field: NormalFlowField,
    *,
    noise_grey: float = 1.0,
    floor_px: float = 0.15,
    relative: float = 0.15,
    min_count: int = 24,
    min_support: float = 0.5,
) -> CoarseField:
    """Hough-transform the normal flow into a 4x4 field of 8 directions.

    Parameters
    ----------
    field : NormalFlowField
    noise_grey, floor_px : float
        Measurement tolerance, see :func:`measurement_tolerance`.
    relative : float
        Extra tolerance proportional to the candidate speed.
    min_count : int
        A region with fewer valid measurements is UNKNOWN.
    min_support : float
        A region whose winner has fewer votes than this share is UNKNOWN.
    """
    nx, ny = field.normal
    valid = _by_region(field.valid)  # (16, 256)
    m = _by_region(field.flow_px)
    n = np.stack([_by_region(nx), _by_region(ny)])  # (2, 16, 256)
    tol = _by_region(measurement_tolerance(field, noise_grey, floor_px))
    cand = _CANDIDATES  # (C, 2)
    speed = np.hypot(cand[:, 0], cand[:, 1]).astype(np.float32)
    pred = (cand @ n.reshape(2, -1)).reshape(len(cand), *m.shape)  # (C, 16, 256)
    pred -= m[None]
    np.abs(pred, out=pred)
    pred -= relative * speed[:, None, None]
    within = pred <= np.where(valid, tol, -np.inf).astype(np.float32)[None]
    votes = np.count_nonzero(within, axis=2)  # (C, 16)
    best = votes.argmax(axis=0)  # (16,)
    count = valid.sum(axis=1)
    region = np.arange(REGIONS * REGIONS)
    support = votes[best, region] / np.maximum(count, 1)

    voters = within[best, region]  # (16, 256)
    flow = _refine(cand[best].copy(), best, speed[best], voters, n, m)

    angle = np.arctan2(flow[:, 1], flow[:, 0])
    index = np.rint(angle / (2 * np.pi / DIRECTIONS)).astype(int) % DIRECTIONS
    index[best == 0] = STILL
    flow[best == 0] = 0.0
    index[(count < min_count) | (support < min_support)] = UNKNOWN
    flow[index == UNKNOWN] = 0.0
    shape = (REGIONS, REGIONS)
    return CoarseField(
        direction_index=index.reshape(shape).astype(np.int8),
        flow_px=flow.reshape(*shape, 2).astype(np.float32),
        support=support.reshape(shape).astype(np.float32),
        count=count.reshape(shape),
        inliers=_from_regions(voters & (index != UNKNOWN)[:, None]),
    )


def _from_regions(a: np.ndarray) -> np.ndarray:
    """Inverse of :func:`_by_region`: (16, 256) -> (64, 64)."""
    s = GRID // REGIONS
    return a.reshape(REGIONS, REGIONS, s, s).swapaxes(1, 2).reshape(GRID, GRID)
