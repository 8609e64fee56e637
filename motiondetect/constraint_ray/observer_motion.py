"""Which motion is the observer making? Section 3.2's canonical classes.

A coarse 4x4 field (:mod:`motiondetect.constraint_ray.hough`) is normalised into a feature
vector and matched by nearest neighbour against a library of canonical
motion fields:

1. ``uniform``: flow roughly one way (8 directions);
2. ``expansion-centre``: focus of expansion (or contraction) at the centre;
3. ``expansion-focus``: focus of expansion anywhere (a 5x5 grid);
4. ``expansion-rotation``: expansion about the centre plus a uniform
   rotational part large enough to put the apparent focus outside the frame;
5. ``fixation``: flow in two opposed directions along one axis.

Plus ``static`` (most regions still: any motion is independent) and
``unknown`` (too few regions measurable: no guess, no detections).

The match becomes a constraint model: for every cell, the rotational flow
``V_w`` and the translational direction ``V_XY`` (section 3.1), with the
inverse-depth bound ``a``. ``mode="paper"`` uses the library entry as is
(``a`` unbounded, the disk-and-half-plane filter of Figure 4);
``mode="fitted"`` estimates the class parameters and both ends of the speed
range from the data (docs/detectors.md measures the difference).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache
from typing import Literal

import numpy as np

from motiondetect.constraint_ray.hough import DIRECTIONS, REGIONS, STILL, CoarseField
from motiondetect.measurement.normal_flow import GridGeometry, NormalFlowField

UNBOUNDED = 1.0e4  # inverse-depth bound standing in for "a -> infinity"

CLASS_NAMES = {
    -1: "unknown",
    0: "static",
    1: "uniform",
    2: "expansion-centre",
    3: "expansion-focus",
    4: "expansion-rotation",
    5: "fixation",
    6: "known-egomotion",
}

_FOCUS_GRID = (0.1, 0.3, 0.5, 0.7, 0.9)
_ROTATION_RATIOS = (1.2, 2.0)


@dataclass(frozen=True)
class CanonicalMotion:
    """One library entry: a class, its parameters and its 4x4 template."""

    class_id: int
    params: dict
    template: np.ndarray  # (4, 4, 2) unit vectors; zero where the field vanishes
    axial: bool = False  # direction known only up to sign (class 5)


@dataclass(frozen=True)
class ObserverMotion:
    """The observer motion a frame was judged to have, as a constraint model.

    Attributes
    ----------
    class_id, name, params, confidence
        What is reported per frame.
    rotation_px : (64, 64, 2) ndarray of float32
        ``V_w`` per cell: the flow at infinite depth, work px/frame.
    translation_px : (64, 64, 2) ndarray of float32
        ``V_XY`` per cell, in units such that the flow at inverse depth
        ``s`` is ``V_w + s * V_XY`` with ``s`` in ``[0, depth_bound]``.
    depth_bound : float
        ``a``; ``UNBOUNDED`` for the half-plane case.
    """

    class_id: int
    params: dict = field(default_factory=dict)
    confidence: float = 0.0
    rotation_px: np.ndarray | None = None
    translation_px: np.ndarray | None = None
    depth_bound: float = 0.0

    @property
    def name(self) -> str:
        return CLASS_NAMES[self.class_id]

    @property
    def constrains(self) -> bool:
        return self.rotation_px is not None

    def to_json(self) -> dict:
        return {
            "class": self.class_id,
            "name": self.name,
            "confidence": round(float(self.confidence), 3),
            "params": self.params,
        }


def region_centres(geometry: GridGeometry) -> np.ndarray:
    """(4, 4, 2) centres of the 4x4 regions, work px."""
    w, h = geometry.work_size
    xs = (np.arange(REGIONS) + 0.5) * w / REGIONS
    ys = (np.arange(REGIONS) + 0.5) * h / REGIONS
    gx, gy = np.meshgrid(xs, ys)
    return np.stack([gx, gy], axis=-1)


def _unit(v: np.ndarray, dead: float) -> np.ndarray:
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    return np.where(n > dead, v / np.maximum(n, 1e-9), 0.0)


@lru_cache(maxsize=16)
def canonical_library(geometry: GridGeometry) -> tuple[CanonicalMotion, ...]:
    """The stored library of canonical motion fields for one frame geometry."""
    w, h = geometry.work_size
    p = region_centres(geometry)
    centre = np.array([w / 2, h / 2])
    dead = 0.35 * min(w, h) / REGIONS  # near a focus the field vanishes
    lib: list[CanonicalMotion] = []
    for k in range(DIRECTIONS):
        a = k * 2 * np.pi / DIRECTIONS
        d = np.array([np.cos(a), np.sin(a)])
        lib.append(CanonicalMotion(1, {"direction_deg": k * 45.0}, np.broadcast_to(d, p.shape)))
    for sign in (1.0, -1.0):
        sense = "expansion" if sign > 0 else "contraction"
        lib.append(
            CanonicalMotion(
                2, {"focus_frac": [0.5, 0.5], "sense": sense}, _unit(sign * (p - centre), dead)
            )
        )
        for fx in _FOCUS_GRID:
            for fy in _FOCUS_GRID:
                if fx == fy == 0.5:
                    continue
                focus = np.array([fx * w, fy * h])
                lib.append(
                    CanonicalMotion(
                        3, {"focus_frac": [fx, fy], "sense": sense}, _unit(sign * (p - focus), dead)
                    )
                )
    half = 0.5 * min(w, h)
    for k in range(DIRECTIONS):
        a = k * 2 * np.pi / DIRECTIONS
        d = np.array([np.cos(a), np.sin(a)])
        for ratio in _ROTATION_RATIOS:
            field_ = (p - centre) / half + ratio * d
            lib.append(
                CanonicalMotion(
                    4, {"rotation_direction_deg": k * 45.0, "ratio": ratio}, _unit(field_, 1e-6)
                )
            )
    for k in range(DIRECTIONS // 2):
        a = k * 2 * np.pi / DIRECTIONS
        d = np.array([np.cos(a), np.sin(a)])
        lib.append(
            CanonicalMotion(5, {"axis_deg": k * 45.0}, np.broadcast_to(d, p.shape), axial=True)
        )
    return tuple(lib)


@lru_cache(maxsize=16)
def _library_features(geometry: GridGeometry) -> tuple[np.ndarray, np.ndarray]:
    """Stacked features of every library entry (class 5 has no first-order part)."""
    firsts, seconds = [], []
    for entry in canonical_library(geometry):
        t1, t2 = _features(np.asarray(entry.template, float))
        firsts.append(np.zeros_like(t1) if entry.axial else t1)
        seconds.append(t2)
    return np.stack(firsts), np.stack(seconds)


def _features(units: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """First-order (cos, sin) and doubled-angle (cos 2t, sin 2t) features."""
    x, y = units[..., 0], units[..., 1]
    doubled = np.stack([x * x - y * y, 2 * x * y], axis=-1)
    return units, doubled


def observed_units(coarse: CoarseField) -> np.ndarray:
    """(4, 4, 2) quantised unit directions; zero for still or unknown regions."""
    idx = coarse.direction_index.astype(int)
    angle = idx * (2 * np.pi / DIRECTIONS)
    units = np.stack([np.cos(angle), np.sin(angle)], axis=-1)
    return np.where(coarse.moving[..., None], units, 0.0)


def classify(
    coarse: CoarseField,
    geometry: GridGeometry,
    *,
    static_fraction: float = 0.75,
    min_known: int = 4,
) -> tuple[CanonicalMotion | None, int, float]:
    """Nearest-neighbour match of a coarse field against the library.

    Returns
    -------
    entry : CanonicalMotion or None
        None for the static and unknown cases.
    class_id : int
        -1 unknown, 0 static, else the entry's class.
    confidence : float in [0, 1]
        Share of regions measured times (1 - distance / 2).
    """
    known = coarse.known
    n_known = int(known.sum())
    if n_known < min_known:
        return None, -1, 0.0
    n_still = int((coarse.direction_index == STILL).sum())
    coverage = n_known / known.size
    if n_still >= static_fraction * n_known:
        return None, 0, coverage * n_still / n_known
    first, second = _features(observed_units(coarse))
    t1, t2 = _library_features(geometry)  # (L, 4, 4, 2) each
    d = ((first - t1) ** 2).sum(-1) + ((second - t2) ** 2).sum(-1)  # (L, 4, 4)
    dist = d[:, known].mean(axis=1)
    pick = int(np.argmin(dist))
    best, best_d = canonical_library(geometry)[pick], float(dist[pick])
    return best, best.class_id, coverage * max(0.0, 1.0 - best_d / 2.0)


# ----------------------------------------------------------------------------
# From a match to a constraint model
# ----------------------------------------------------------------------------


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

    The paper's recipe for class 4: the rotation shows in the flow components
    normal to lines through the image origin.
    """
    if len(flows) < 2:
        return np.zeros(2)
    q = points - centre
    a = np.stack([q[:, 1], -q[:, 0]], axis=1)
    b = flows[:, 0] * q[:, 1] - flows[:, 1] * q[:, 0]
    sol, *_ = np.linalg.lstsq(a, b, rcond=None)
    return sol


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
    geometry = field.geometry
    shape = (*field.flow_px.shape, 2)
    if class_id == -1:
        return ObserverMotion(-1, {}, 0.0)
    if class_id == 0:
        zero = np.zeros(shape, np.float32)
        return ObserverMotion(0, {}, confidence, zero, zero, 0.0)
    assert entry is not None
    cells = _cells(geometry)
    w, h = geometry.work_size
    centre = np.array([w / 2, h / 2])
    moving = coarse.moving
    points = region_centres(geometry)[moving]
    flows = coarse.flow_px[moving].astype(np.float64)
    params = dict(entry.params)
    fitted = mode == "fitted"

    if class_id in (1, 5):
        a = np.deg2rad(entry.params["direction_deg" if class_id == 1 else "axis_deg"])
        d = np.array([np.cos(a), np.sin(a)])
        if fitted:
            d = _axis(flows, d)
        direction = np.broadcast_to(d, shape)
        offset = np.zeros(shape)
        span = (0.0, UNBOUNDED) if class_id == 1 else (-UNBOUNDED, UNBOUNDED)
        if fitted:
            params["direction_deg"] = round(float(np.degrees(np.arctan2(d[1], d[0]))), 1)
    elif class_id in (2, 3):
        focus = np.array(entry.params["focus_frac"]) * [w, h]
        sign = 1.0 if entry.params["sense"] == "expansion" else -1.0
        if fitted and fit_focus:
            fit = _fit_focus(points, flows)
            if fit is not None and np.all(np.abs(fit - centre) < [2 * w, 2 * h]):
                focus = fit
            params["focus_px"] = [round(float(v), 1) for v in focus]
        direction = sign * (cells - focus)
        offset = np.zeros(shape)
        span = (0.0, UNBOUNDED)
    else:  # class 4
        rot = _fit_rotation(points, flows, centre)
        q = cells - centre
        sign = 1.0 if ((flows - rot) * (points - centre)).sum() >= 0 else -1.0
        direction = sign * q
        offset = np.broadcast_to(rot, shape)
        span = (0.0, UNBOUNDED)
        params["rotation_px"] = [round(float(v), 3) for v in rot]

    if fitted:
        # The rigid world is what the coarse field sees moving: the cells that
        # voted for their moving region's dominant flow. A followed subject
        # (near-zero flow) does not vote for the background's and stays out.
        size = field.flow_px.shape[0] // REGIONS
        rigid = np.kron(moving, np.ones((size, size), bool))
        if coarse.inliers is not None:
            rigid &= coarse.inliers
        measured = _speed_range(field, direction, offset, quantiles, margin, cells=rigid)
        if measured is not None:
            # Only the lower end is taken from the data (classes 1-4): a rigid
            # world never moves against the dominant direction (section 3.2),
            # so the lower end may rise above zero (a tracking shot, where a
            # followed subject has near-zero flow) but never drop below it.
            # The upper end stays unbounded: a near rigid object covering a
            # few percent of the frame would otherwise fall outside it.
            # Class 5 keeps both ends open (the paper's "exclude motion with
            # a significant perpendicular component"); only its axis is fitted.
            if class_id != 5:
                span = (max(measured[0], 0.0), UNBOUNDED)
    lo, hi = span
    if fitted:
        params["speed_range"] = [round(lo, 4), round(hi, 4)]
    rotation = offset + lo * direction
    return ObserverMotion(
        class_id,
        params,
        confidence,
        rotation.astype(np.float32),
        np.ascontiguousarray(direction, dtype=np.float32),
        float(hi - lo),
    )
