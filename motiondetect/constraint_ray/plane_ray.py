"""Nelson's constraint *ray* from the dominant plane's own motion.

A rigid point's image velocity lies on a half-line in velocity space
(section 3; Figure 2): it starts at the velocity a point at infinite depth
would have (the camera's rotation alone) and runs, through the velocity of
any depth in between, toward ever nearer points. The dominant plane's
homography ``H = K (R + t n^T / d) K^-1`` fixes one point of that half-line
at every pixel (the plane's own depth), and its decomposition into ``R``
and ``t`` fixes the start (``K R K^-1``) and so the direction. In terms of
the residual ``r`` (velocity minus the plane's), a rigid point at pixel
``p`` has ``r = -k * r_inf(p)``, where ``r_inf`` is the residual of a point
at infinity and ``k >= -1`` says how much nearer than the plane it lies
(``k = Z_plane / Z - 1``: 0 on the plane, -1 at infinity, positive in
front of it). ``k = h / (d - h)``, where ``h`` is the point's height over
the plane and ``d`` the plane's distance: ``h`` is the rigid point's own,
and ``d`` changes by a ratio the decomposition gives, so last frame's ``k``
predicts this frame's (:meth:`PlaneRay.depth_from_height`), which is what
lets a near rigid object be told from a mover over time
(:mod:`motiondetect.detection.rigid_depth`).

Two things limit it. The decomposition needs the focal length, taken from
a lens prior (``FitConfig.focal_share``); and one homography decomposes
two ways, both exact for the plane, which differ off it: the one under
which more of the frame's large residuals keep the depth they had in the
last frame is kept, else the one under which more lie on their rays. When
the plane's translation moves it by less than the residual tolerance (a
pan, a distant plane) there is no measurable ray, and none is returned.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np


def _transform(points: np.ndarray, matrix: np.ndarray) -> np.ndarray:
    """``points`` (..., 2) mapped by a 3x3 homography, float32."""
    flat = np.ascontiguousarray(points, np.float32).reshape(-1, 1, 2)
    if not len(flat):
        return np.zeros(points.shape, np.float32)
    return cv2.perspectiveTransform(flat, matrix).reshape(points.shape)


#: The lowest height kept (plane distances below the plane), standing for
#: "at infinity": its depth ratio now is -1 to float32 precision.
_FAR = np.float32(1e7)


@dataclass(frozen=True)
class PlaneRay:
    """One decomposition of the dominant plane's motion.

    Attributes
    ----------
    homography : (3, 3) ndarray
        The plane's homography, current work pixels to previous ones.
    rotation : (3, 3) ndarray
        ``K R K^-1``: the homography of the plane at infinity (rotation only).
    normal : (3,) ndarray
        The plane's unit normal, camera axes.
    distance_ratio : float
        The plane's distance from the camera in the previous frame over its
        distance now, ``1 + (R n) . t / d``.
    """

    homography: np.ndarray
    rotation: np.ndarray
    normal: np.ndarray
    distance_ratio: float

    def depth_from_height(self, height: np.ndarray) -> np.ndarray:
        """``k`` now of rigid points whose height over the plane, in units of
        its distance, was ``height`` in the previous frame (:func:`height`)."""
        scaled = height * np.float32(self.distance_ratio)
        return scaled / np.maximum(1.0 - scaled, 1e-3)

    def predicts(
        self, residual: np.ndarray, inf: np.ndarray, heights: np.ndarray, tolerance: float
    ) -> np.ndarray:
        """Whether each residual (N, 2) is what a rigid point would have now
        whose height was within last frame's bounds ``heights`` (N, 2: low,
        high; :func:`height_bounds`), (N,) bool. ``inf``: :meth:`at_infinity`
        at the residuals' points; ``tolerance``: this frame's, px/frame.

        The prediction is ``-k * r_inf`` at the middle of the bounds' depths
        now. Its error has two independent sources, each bounded at the same
        confidence: this frame's residual, within ``tolerance``, and last
        frame's depth, within half the bounds' spread of ``k`` times
        ``|r_inf|`` now (which grows with the plane's translation). Their
        difference is bounded by the root of the sum of squares.
        """
        low, high = self.depth_from_height(heights[:, 0]), self.depth_from_height(heights[:, 1])
        gap = residual + (0.5 * (low + high))[:, None] * inf
        carried = 0.5 * (high - low) * np.hypot(inf[:, 0], inf[:, 1])
        return gap[:, 0] ** 2 + gap[:, 1] ** 2 < np.float32(tolerance) ** 2 + carried**2

    def at_infinity(self, points: np.ndarray) -> np.ndarray:
        """``r_inf``: the residual of a point at infinite depth at each of
        ``points`` (..., 2), work px/frame, (..., 2) float32."""
        return _transform(points, self.homography) - _transform(points, self.rotation)

    @staticmethod
    def split(residual: np.ndarray, inf: np.ndarray) -> tuple[np.ndarray, ...]:
        """Each residual against its ray, given the ray's start ``inf``
        (:meth:`at_infinity` at the residuals' points): ``(k, off, length)``.

        ``k`` is the position along the ray in units of ``|r_inf|`` (the
        depth ratio of the module doc), ``off`` the distance from the
        residual to the half-line, px/frame, and ``length`` ``|r_inf|``;
        all (...) float32.
        """
        length = np.hypot(inf[..., 0], inf[..., 1])
        safe = np.maximum(length, 1e-9)
        ux, uy = -inf[..., 0] / safe, -inf[..., 1] / safe
        along = residual[..., 0] * ux + residual[..., 1] * uy
        across = np.abs(residual[..., 0] * uy - residual[..., 1] * ux)
        beyond = np.hypot(residual[..., 0] - inf[..., 0], residual[..., 1] - inf[..., 1])
        off = np.where(along >= -length, across, beyond)  # past infinity: from the start
        return (along / safe).astype(np.float32), off.astype(np.float32), length.astype(np.float32)


def height(k: np.ndarray) -> np.ndarray:
    """A point's height over the plane in units of the plane's distance,
    ``h / d = k / (1 + k)``, from its depth ratio ``k`` (NaN at infinity).

    ``h`` is the rigid point's own, so this changes only with ``d``, by the
    ratio the decomposition gives (:meth:`PlaneRay.depth_from_height`);
    ``k = h / (d - h)`` changes less simply.
    """
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(k > -1.0, k / (1.0 + k), np.nan).astype(np.float32)


def height_bounds(k: np.ndarray, spread: np.ndarray) -> np.ndarray:
    """Bounds on a point's :func:`height` from its depth ratio ``k`` known
    to within ``spread`` either way (the residual's tolerance over
    ``|r_inf|``): (..., 2) float32, low and high. A point that may lie at
    infinity has a very low bound (the height's limit there is minus
    infinity; its depth ratio, -1, is kept exactly)."""
    bounds = np.stack([height(k - spread), height(k + spread)], -1)
    return np.nan_to_num(np.maximum(bounds, -_FAR), nan=-_FAR)


def decompositions(homography: np.ndarray, shape: tuple[int, int], focal_share: float) -> list:
    """The plane's distinct decompositions under the lens prior, [PlaneRay].

    ``focal_share`` is the focal length as a share of the frame's long
    side; the principal point is the frame's centre. OpenCV returns each
    solution with both signs of ``t`` and ``n``; those give the same ray.
    """
    h, w = shape
    f = focal_share * max(h, w)
    k = np.array([[f, 0.0, w / 2.0], [0.0, f, h / 2.0], [0.0, 0.0, 1.0]])
    k_inv = np.linalg.inv(k)
    count, rotations, translations, normals = cv2.decomposeHomographyMat(homography, k)
    out: list[PlaneRay] = []
    for i in range(count):
        normal = normals[i].ravel()
        if any(abs(float(normal @ ray.normal)) > 0.999 for ray in out):
            continue
        ratio = 1.0 + float((rotations[i] @ normal) @ translations[i].ravel())
        out.append(PlaneRay(homography, k @ rotations[i] @ k_inv, normal, ratio))
    return out


def fit_plane_ray(
    homography: np.ndarray,
    points: np.ndarray,
    residual: np.ndarray,
    tolerance: float,
    shape: tuple[int, int],
    focal_share: float,
    depth: np.ndarray | None = None,
) -> tuple[PlaneRay, np.ndarray] | None:
    """The plane's decomposition whose rays explain the frame best, or None.

    Parameters
    ----------
    homography : (3, 3) ndarray
    points, residual : (N, 2) ndarray
        Grid samples of the frame and their plane residuals, work px/frame.
    tolerance : float
        Largest off-ray distance of an explained residual, px/frame.
    shape : (h, w)
    focal_share : float
        Lens prior (:func:`decompositions`); 0: no ray.
    depth : (N, 2) ndarray, optional
        Each sample's :func:`height_bounds` in the last frame, carried to it
        (NaN: none).

    Returns
    -------
    (PlaneRay, (N, 2) ndarray) or None
        The decomposition, with ``r_inf`` at ``points``, under which most
        residuals above ``tolerance`` keep the depth they had (a rigid world
        keeps its depths), then under which most lie on their rays, then
        whose plane faces the camera most; None when the chosen one's median
        ``|r_inf|`` is below ``tolerance``: the plane's translation is then
        not measured.
    """
    if focal_share <= 0 or len(points) == 0:
        return None
    large = np.hypot(residual[:, 0], residual[:, 1]) > tolerance
    if depth is None:
        depth = np.full((len(points), 2), np.nan, np.float32)
    known = large & np.isfinite(depth[:, 1])
    best, best_key = None, None
    for ray in decompositions(homography, shape, focal_share):
        inf = ray.at_infinity(points)
        _, off, _ = ray.split(residual[large], inf[large])
        kept = int(ray.predicts(residual[known], inf[known], depth[known], tolerance).sum())
        key = (kept, int((off < tolerance).sum()), abs(float(ray.normal[2])))
        if best_key is None or key > best_key:
            best, best_key = (ray, inf), key
    if best is None or np.median(np.hypot(best[1][:, 0], best[1][:, 1])) < tolerance:
        return None
    return best
