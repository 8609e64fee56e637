"""The epipole (focus of expansion) that rigid parallax points to or from.

After the dominant plane's motion is removed, a rigid point's residual lies
on the line through it and the epipole (docs/maths.md, section 6): that
line is Nelson's constraint ray with the rotation taken out. A single
mover's residuals are parallel and so fit *some* epipole; an epipole is
therefore accepted only when its support is spread over the frame.
"""

from __future__ import annotations

import numpy as np

from motiondetect.measurement.dense_flow import vector_length


def off_ray(
    residual: np.ndarray,
    points: np.ndarray,
    epipole: np.ndarray | None,
    magnitude: np.ndarray | None = None,
) -> np.ndarray:
    """How far each residual lies off its point's constraint ray, px/frame.

    Parameters
    ----------
    residual : (..., 2) ndarray
    points : (..., 2) ndarray
        Work pixels of the residuals.
    epipole : (3,) ndarray or None
        Homogeneous. None: no parallax is expected, so the whole residual
        is off the ray.
    magnitude : (...) ndarray of float32, optional
        ``|residual|`` when already known.

    Returns
    -------
    (...) ndarray of float32
        The component of the residual across the line through the point
        and the epipole (its length where the point is within 1 px of it).
    """
    if magnitude is None:
        magnitude = vector_length(residual)
    if epipole is None:
        return magnitude
    ux = epipole[0] - epipole[2] * points[..., 0]
    uy = epipole[1] - epipole[2] * points[..., 1]
    norm = np.hypot(ux, uy)
    across = np.abs(residual[..., 0] * uy - residual[..., 1] * ux) / np.maximum(norm, 1e-9)
    near = norm < max(abs(float(epipole[2])), 1e-9)  # within 1 px of a finite epipole
    return np.where(near, magnitude, across).astype(np.float32)


def _lines(points: np.ndarray, residual: np.ndarray) -> np.ndarray:
    """Homogeneous lines through each point along its residual, unit normals, (N, 3)."""
    n = np.stack([-residual[:, 1], residual[:, 0]], axis=1)
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-9)
    return np.concatenate([n, -(n * points).sum(axis=1, keepdims=True)], axis=1)


def _blocks_covered(points: np.ndarray, shape: tuple[int, int]) -> int:
    h, w = shape
    bx = np.minimum((points[:, 0] * 4 / w).astype(int), 3)
    by = np.minimum((points[:, 1] * 4 / h).astype(int), 3)
    return len(np.unique(by * 4 + bx))


def fit_epipole(
    points: np.ndarray,
    residual: np.ndarray,
    tol_px: float,
    shape: tuple[int, int],
    min_blocks: int,
    previous: np.ndarray | None = None,
    rng: np.random.Generator | None = None,
) -> np.ndarray | None:
    """The epipole that the parallax residuals point to or from, or None.

    Parameters
    ----------
    points, residual : (N, 2) ndarray
        Samples whose residual is well above the noise.
    tol_px : float
        Largest off-ray distance of a supporting residual.
    shape : (h, w)
        Work frame size, for the spread test.
    min_blocks : int
        Of the frame's 4x4 blocks, how many the support must reach.
    previous : (3,) ndarray, optional
        Last frame's epipole, tried first (a camera's heading changes slowly).

    Returns
    -------
    (3,) ndarray of float64 or None
        Unit-norm homogeneous epipole; None when the support is too small
        or too concentrated to be parallax rather than a mover.
    """
    if len(points) < 2 * min_blocks:
        return None
    rng = rng or np.random.default_rng(0)
    lines = _lines(points, residual)
    hypotheses = [previous] if previous is not None else []
    pairs = rng.integers(0, len(points), size=(64, 2))
    hypotheses += [np.cross(lines[i], lines[j]) for i, j in pairs if i != j]
    best, best_support = None, None
    for e in hypotheses:
        norm = np.linalg.norm(e)
        if norm < 1e-12:
            continue
        support = off_ray(residual, points, e / norm) < tol_px
        if best_support is None or support.sum() > best_support.sum():
            best, best_support = e / norm, support
    if best is None or best_support.mean() < 0.6:
        return None
    if _blocks_covered(points[best_support], shape) < min_blocks:
        return None
    # Least squares over the support: the point closest to all its lines.
    _, _, vt = np.linalg.svd(lines[best_support])
    refined = vt[-1]
    return refined if np.dot(refined, best) >= 0 else -refined
