"""From a matched class to a constraint model: per-cell ``V_w``, ``V_XY`` and ``a``.

Section 3.1's first-order model: the flow at inverse depth ``s`` is
``V_w + s V_XY``. ``mode="paper"`` takes the library entry as is; ``mode=
"fitted"`` fits the class parameters to the coarse field and measures the
lower end of the speed range from the rigid world (docs/detectors.md).
"""

from __future__ import annotations

from typing import Literal

import numpy as np

from motiondetect.constraint_ray.hough import REGIONS, CoarseField
from motiondetect.constraint_ray.observer_motion import (
    UNBOUNDED,
    CanonicalMotion,
    ObserverMotion,
    region_centres,
)
from motiondetect.measurement.normal_flow import GridGeometry, NormalFlowField
from motiondetect.measurement.stages import GRID


def _cells(geometry: GridGeometry) -> np.ndarray:
    x, y = geometry.cell_centres_px()
    return np.stack([x, y], axis=-1).astype(np.float64)


def _speed_range(
    field: NormalFlowField,
    direction: np.ndarray,
    offset: np.ndarray | None,
    quantiles: tuple[float, float],
    margin: float,
    noise_grey: float = 1.0,
    max_sigma: float = 0.3,
    cells: np.ndarray | None = None,
) -> tuple[float, float] | None:
    """Both ends of ``s`` in ``m = offset.n + s * direction.n`` from the data.

    ``direction`` and ``offset`` are (64, 64, 2) per-cell vectors. Only
    precise cells take part: gradient within 45 degrees of ``direction``
    and an estimated error of ``s`` (``noise / (|grad I| |direction . n|)``)
    below ``max_sigma``. Quantiles, not extremes, so that an independent
    mover covering a few percent of the frame cannot stretch the range to
    include itself. ``cells`` restricts the estimate to part of the frame.
    """
    nx, ny = field.normal
    proj = direction[..., 0] * nx + direction[..., 1] * ny
    length = np.linalg.norm(direction, axis=-1)
    sigma = noise_grey / np.maximum(field.gradient * np.abs(proj), 1e-6)
    use = (
        field.valid
        & (length > 1e-6)
        & (np.abs(proj) >= np.cos(np.pi / 4) * length)
        & (sigma <= max_sigma * np.maximum(length, 1e-6))
    )
    if cells is not None:
        use &= cells
    if use.sum() < 32:
        return None
    m = field.flow_px.astype(np.float64)
    if offset is not None:
        m = m - (offset[..., 0] * nx + offset[..., 1] * ny)
    s = m[use] / proj[use]
    lo, hi = np.percentile(s, quantiles)
    pad = margin * max(abs(lo), abs(hi))
    return float(lo - pad), float(hi + pad)


def _axis(flows: np.ndarray, seed: np.ndarray) -> np.ndarray:
    """Dominant axis of (K, 2) region flows, oriented like ``seed``.

    Regions more than 45 degrees off the library entry's axis (movers, or a
    region the Hough step got wrong) do not take part; the rest vote with
    unit weight on doubled angles, so opposed flows (class 5) agree.
    """
    if len(flows) == 0:
        return seed
    units = flows / np.maximum(np.linalg.norm(flows, axis=1, keepdims=True), 1e-9)
    keep = np.abs(units @ seed) >= np.cos(np.pi / 4)
    if not keep.any():
        return seed
    angle = np.arctan2(units[keep, 1], units[keep, 0])
    axis_angle = 0.5 * np.arctan2(np.sin(2 * angle).sum(), np.cos(2 * angle).sum())
    d = np.array([np.cos(axis_angle), np.sin(axis_angle)])
    return d if d @ seed >= 0 else -d


def _fit_focus(points: np.ndarray, flows: np.ndarray, rounds: int = 3) -> np.ndarray | None:
    """Point c with every flow parallel to (p - c), robust to a few movers.

    Least squares on the cross products, then regions whose flow is more
    than 30 degrees off the radial direction are dropped and the fit redone.
    """
    keep = np.ones(len(flows), bool)
    sol = None
    for _ in range(rounds):
        if keep.sum() < 3:
            break
        vx, vy = flows[keep, 0], flows[keep, 1]
        a = np.stack([-vy, vx], axis=1)
        b = vx * points[keep, 1] - vy * points[keep, 0]
        fit, _, rank, _ = np.linalg.lstsq(a, b, rcond=None)
        if rank < 2:
            break
        sol = fit
        radial = points - sol
        cos = np.abs((radial * flows).sum(1)) / np.maximum(
            np.linalg.norm(radial, axis=1) * np.linalg.norm(flows, axis=1), 1e-9
        )
        new_keep = cos >= np.cos(np.pi / 6)
        if (new_keep == keep).all():
            break
        keep = new_keep
    return sol


def _fit_rotation(points: np.ndarray, flows: np.ndarray, centre: np.ndarray) -> np.ndarray:
    """Least-squares uniform w with (v - w) parallel to (p - centre).

    Generalises the paper's recipe for class 4, which reads the rotation off
    the flow components normal to lines through the image origin, to a
    least-squares fit over every moving region.
    """
    if len(flows) < 2:
        return np.zeros(2)
    q = points - centre
    a = np.stack([q[:, 1], -q[:, 0]], axis=1)
    b = flows[:, 0] * q[:, 1] - flows[:, 1] * q[:, 0]
    sol, *_ = np.linalg.lstsq(a, b, rcond=None)
    return sol


def _class_geometry(
    entry: CanonicalMotion, class_id: int, points: np.ndarray, flows: np.ndarray,
    geometry: GridGeometry, fitted: bool, fit_focus: bool, params: dict,
) -> tuple[np.ndarray, np.ndarray, tuple[float, float]]:  # fmt: skip
    """Per-cell translational direction, rotational offset and ``s`` range of a class."""
    shape = (GRID, GRID, 2)
    w, h = geometry.work_size
    centre = np.array([w / 2, h / 2])
    if class_id in (1, 5):
        a = np.deg2rad(entry.params["direction_deg" if class_id == 1 else "axis_deg"])
        d = np.array([np.cos(a), np.sin(a)])
        if fitted:
            d = _axis(flows, d)
            params["direction_deg"] = round(float(np.degrees(np.arctan2(d[1], d[0]))), 1)
        span = (0.0, UNBOUNDED) if class_id == 1 else (-UNBOUNDED, UNBOUNDED)
        return np.broadcast_to(d, shape), np.zeros(shape), span
    cells = _cells(geometry)
    if class_id in (2, 3):
        focus = np.array(entry.params["focus_frac"]) * [w, h]
        sign = 1.0 if entry.params["sense"] == "expansion" else -1.0
        if fitted and fit_focus:
            fit = _fit_focus(points, flows)
            if fit is not None and np.all(np.abs(fit - centre) < [2 * w, 2 * h]):
                focus = fit
            params["focus_px"] = [round(float(v), 1) for v in focus]
        return sign * (cells - focus), np.zeros(shape), (0.0, UNBOUNDED)
    rot = _fit_rotation(points, flows, centre)  # class 4
    sign = 1.0 if ((flows - rot) * (points - centre)).sum() >= 0 else -1.0
    params["rotation_px"] = [round(float(v), 3) for v in rot]
    return sign * (cells - centre), np.broadcast_to(rot, shape), (0.0, UNBOUNDED)


def _fitted_span(
    class_id: int, span: tuple[float, float], coarse: CoarseField, field: NormalFlowField,
    direction: np.ndarray, offset: np.ndarray, quantiles: tuple[float, float], margin: float,
) -> tuple[float, float]:  # fmt: skip
    """The lower end of the speed range measured from the rigid world.

    The rigid world is what the coarse field sees moving: the cells that
    voted for their moving region's dominant flow. A followed subject
    (near-zero flow) does not vote for the background's and stays out. Only
    the lower end is taken from the data (classes 1-4): a rigid world never
    moves against the dominant direction (section 3.2), so it may rise above
    zero (a tracking shot) but never drop below it. The upper end stays
    unbounded: a near rigid object covering a few percent of the frame would
    otherwise fall outside it. Class 5 keeps both ends open (the paper's
    "exclude motion with a significant perpendicular component").
    """
    size = field.flow_px.shape[0] // REGIONS
    rigid = np.kron(coarse.moving, np.ones((size, size), bool))
    if coarse.inliers is not None:
        rigid &= coarse.inliers
    measured = _speed_range(field, direction, offset, quantiles, margin, cells=rigid)
    if measured is None or class_id == 5:
        return span
    return (max(measured[0], 0.0), UNBOUNDED)


def constraint_model(
    entry: CanonicalMotion | None,
    class_id: int,
    confidence: float,
    coarse: CoarseField,
    field: NormalFlowField,
    *,
    mode: Literal["paper", "fitted"] = "fitted",
    quantiles: tuple[float, float] = (3.0, 97.0),
    margin: float = 0.15,
    fit_focus: bool = False,
) -> ObserverMotion:
    """Turn a classification into per-cell ``V_w``, ``V_XY`` and ``a``."""
    if class_id == -1:
        return ObserverMotion(-1, {}, 0.0)
    if class_id == 0:
        zero = np.zeros((*field.flow_px.shape, 2), np.float32)
        return ObserverMotion(0, {}, confidence, zero, zero, 0.0)
    assert entry is not None
    moving = coarse.moving
    points = region_centres(field.geometry)[moving]
    flows = coarse.flow_px[moving].astype(np.float64)
    params = dict(entry.params)
    fitted = mode == "fitted"
    direction, offset, span = _class_geometry(
        entry, class_id, points, flows, field.geometry, fitted, fit_focus, params
    )
    if fitted:
        span = _fitted_span(class_id, span, coarse, field, direction, offset, quantiles, margin)
        params["speed_range"] = [round(span[0], 4), round(span[1], 4)]
    lo, hi = span
    rotation = offset + lo * direction
    return ObserverMotion(
        class_id,
        params,
        confidence,
        rotation.astype(np.float32),
        np.ascontiguousarray(direction, dtype=np.float32),
        float(hi - lo),
    )
