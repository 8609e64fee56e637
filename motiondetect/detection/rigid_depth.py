"""Near rigid objects told from movers by their depth on the constraint ray.

Between two frames one near rigid object (a mounted head standing out of
the wall it hangs on, a post before a hedge) and one mover are alike: both
move off the dominant plane, coherently. Over time they differ. A rigid
point keeps its height over the plane, so its position on its constraint
ray, ``k`` (:mod:`motiondetect.constraint_ray.plane_ray`), follows from
last frame's while the camera's translation changes, and its residual is
predicted by that and this frame's ray: ``-k * r_inf``. A mover's residual
is its own motion and follows no such rule. Each depth is carried as the
bounds it was measured to (the tolerance over ``|r_inf|``), so its
prediction is as loose as the measurement was
(:meth:`~motiondetect.constraint_ray.plane_ray.PlaneRay.predicts`).

An object is dropped as rigid when most of its pixels sit in front of the
plane and were predicted so, within the constraint ray filter's tolerance
and the carried depth's own error, on this frame and the last (a mover's
motion can match one prediction by chance: woman.mp4's walker did on the
first frame of a fast turn). Only
the near side is judged: a mover the camera follows stays still in the
image while the background slides by, which is what a point at infinity
does, so objects between the plane and infinity are never dropped.

Blind spot: a mover translating parallel to the camera's translation at a
steady speed is, in every frame, what a rigid point at another depth would
be (no number of frames tells them apart); one in front of the plane is
dropped. The known ego-motion path, which bounds the depth, is not
subject to it, and skips this test.
"""

from __future__ import annotations

import cv2
import numpy as np

from motiondetect.constraint_ray.camera_fit import CameraFit
from motiondetect.constraint_ray.plane_ray import fit_plane_ray, height_bounds
from motiondetect.detection.objects import MovingObject
from motiondetect.measurement.dense_flow import VelocityField

#: The depths are kept on every 4th pixel each way: an object is judged by
#: the majority of its pixels, which a 4-px grid samples plenty (16x cheaper).
_STEP = 4


def _moved(image: np.ndarray, source: np.ndarray, outside: float) -> np.ndarray:
    """``image`` of the last frame (on the grid) moved to this frame's grid
    points, which came from ``source`` (grid units)."""
    return cv2.remap(
        image, source, None, cv2.INTER_NEAREST, borderMode=cv2.BORDER_CONSTANT, borderValue=outside
    )


def _grid(values: np.ndarray | None, shape: tuple[int, int]) -> np.ndarray | None:
    return None if values is None else values.reshape(shape)


class RigidDepth:
    """Each pixel's depth on its ray, carried from frame to frame.

    Parameters
    ----------
    share : float
        An object is rigid when at least this share of its pixels has a
        depth from the last frame, and this share of those is in front of
        the plane and predicted on this frame and the last (0: off).
    focal_share : float
        The lens prior of the plane's decomposition (``FitConfig.focal_share``).
    """

    def __init__(self, share: float, focal_share: float) -> None:
        self.share, self.focal_share = share, focal_share
        self._depth: np.ndarray | None = None  # (h, w, 2) height bounds, NaN: none
        self._rigid: np.ndarray | None = None  # (n,) this frame's explained grid points
        self._known: np.ndarray | None = None  # (n,) where a depth was carried
        self._predicted: np.ndarray | None = None  # (h, w) last frame's explained points

    def reset(self) -> None:
        self._depth = self._rigid = self._known = self._predicted = None

    def update(self, field: VelocityField, fit: CameraFit, tolerance: float) -> None:
        """Take this frame's fit: test it against the carried depths, keep its own.

        ``tolerance`` is the constraint ray filter's (which every flagged
        object exceeds), px/frame: the largest error of a rigid point's
        residual, off its ray and (with the carried depth's error,
        :meth:`PlaneRay.predicts`) from its prediction. Through a frame
        with no measurable ray the depths are only carried along.
        """
        carried, self._depth = self._depth, None
        explained, self._predicted = self._predicted, None
        self._rigid = self._known = None
        if self.share <= 0 or fit.homography is None or fit.residual_px is None:
            return
        shape = fit.residual_px[::_STEP, ::_STEP].shape[:2]
        bounds_shape = (*shape, 2)
        grid = np.ascontiguousarray(field.pixel_grid[::_STEP, ::_STEP]).reshape(-1, 2)
        residual = np.ascontiguousarray(fit.residual_px[::_STEP, ::_STEP]).reshape(-1, 2)
        before = previously = None
        if carried is not None and carried.shape == bounds_shape:
            source = field.source_px[::_STEP, ::_STEP] / np.float32(_STEP)
            before = _moved(carried, source, np.nan).reshape(-1, 2)
            if explained is not None:
                previously = _moved(explained.view(np.uint8), source, 0).ravel() > 0
        fitted = fit_plane_ray(
            fit.homography, grid, residual, tolerance, field.shape, self.focal_share, before
        )
        if fitted is None:
            self._depth = _grid(before, bounds_shape)
            self._predicted = _grid(previously, shape)
            return
        ray, inf = fitted
        k, off, length = ray.split(residual, inf)
        on_ray = (off < tolerance) & (length > max(fit.noise_px, 1e-3))
        bounds = height_bounds(k, tolerance / np.maximum(length, 1e-3))
        self._depth = np.where(on_ray[:, None], bounds, np.nan).reshape(bounds_shape)
        if before is None:
            return
        self._known = np.isfinite(before[:, 1])
        near = k * length > tolerance
        kept = ray.predicts(residual, inf, np.nan_to_num(before), tolerance)
        predicted = self._known & near & kept
        self._predicted = predicted.reshape(shape)
        # Predicted on this frame and the last: once is a mover's coincidence.
        self._rigid = predicted & previously if previously is not None else None

    def without_rigid(self, objects: list[MovingObject]) -> list[MovingObject]:
        """``objects`` less those this frame's depths explain as rigid."""
        if self._rigid is None:
            return objects
        kept = []
        for obj in objects:
            inside = obj.mask[::_STEP, ::_STEP].ravel()
            known = self._known[inside]
            if known.size and known.mean() >= self.share:
                if self._rigid[inside][known].mean() >= self.share:
                    continue
            kept.append(obj)
        return kept
