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

import numpy as np

from motiondetect.constraint_ray.hough import DIRECTIONS, REGIONS, STILL, CoarseField
from motiondetect.measurement.normal_flow import GridGeometry

#: The inverse-depth bound ``a`` standing in for "a -> infinity" (the paper's
#: disk-and-half-plane case). At 1e4 the far end of every interval lies beyond
#: any measurable flow (bins stop at 8.5 px/frame), so it acts as infinity
#: while the arithmetic stays finite (docs/detectors.md).
UNBOUNDED = 1.0e4

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
    static_fraction: float = 0.6,
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
