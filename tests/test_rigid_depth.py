"""The constraint ray from the plane's decomposition, and near rigid objects
told from movers by the depth they keep on it (exact synthetic geometry)."""

from __future__ import annotations

from types import SimpleNamespace

import cv2
import numpy as np
import pytest

from motiondetect.constraint_ray.plane_ray import (
    PlaneRay,
    decompositions,
    fit_plane_ray,
    height,
    height_bounds,
)
from motiondetect.detection.objects import MovingObject
from motiondetect.detection.rigid_depth import RigidDepth

W, H = 320, 240
FOCAL = 0.75 * W  # the lens prior's own focal length
K = np.array([[FOCAL, 0, W / 2], [0, FOCAL, H / 2], [0, 0, 1.0]])
WALL = 5.0  # the dominant plane: Z = WALL, facing the camera


def rotation(wx: float, wy: float, wz: float) -> np.ndarray:
    return cv2.Rodrigues(np.array([wx, wy, wz]))[0]


def plane_homography(r: np.ndarray, t: np.ndarray, n=(0.0, 0.0, 1.0), d=WALL) -> np.ndarray:
    """Current pixels to previous ones for the plane n.X = d, with X' = R X + t."""
    return K @ (r + np.outer(t, n) / d) @ np.linalg.inv(K)


def project_previous(pixels: np.ndarray, depth: np.ndarray, r, t) -> np.ndarray:
    """Where the points at ``pixels`` (N, 2) and ``depth`` (N,) were in the previous frame."""
    rays = np.linalg.inv(K) @ np.c_[pixels, np.ones(len(pixels))].T
    moved = r @ (rays * depth) + t[:, None]
    image = K @ moved
    return (image[:2] / image[2]).T


def residuals(pixels, depth, r, t):
    """Velocity minus the wall's velocity, as the fit computes it."""
    h = plane_homography(r, t)
    previous = project_previous(pixels, depth, r, t)
    warped = np.c_[pixels, np.ones(len(pixels))] @ h.T
    return (warped[:, :2] / warped[:, 2:] - previous).astype(np.float32), h


PIXELS = np.stack(np.meshgrid(np.arange(8, W, 16.0), np.arange(8, H, 16.0)), -1).reshape(-1, 2)


@pytest.mark.parametrize("share", [0.3, 0.7, 1.0, 1.5, 4.0, 1e6])
def test_rigid_points_at_any_depth_lie_on_the_chosen_half_ray(share):
    r, t = rotation(0.01, -0.02, 0.005), np.array([0.08, -0.03, 0.05])
    depth = np.full(len(PIXELS), WALL * share)
    residual, h = residuals(PIXELS, depth, r, t)
    # The choice sees the frame: the wall (on the plane) and a few depths off it.
    mixed = np.where(np.arange(len(PIXELS)) % 3 == 0, WALL * 0.5, WALL)
    mixed_residual, _ = residuals(PIXELS, mixed, r, t)
    fitted = fit_plane_ray(h, PIXELS, mixed_residual, 0.05, (H, W), 0.75)
    assert fitted is not None
    ray, start = fitted
    assert np.allclose(start, ray.at_infinity(PIXELS))
    k, off, _ = PlaneRay.split(residual, ray.at_infinity(PIXELS))
    assert off.max() < 0.02
    # Nearer than the plane: positive; on it: 0; beyond it: down to -1 at infinity.
    if share < 1:
        assert (k > 0).all()
    elif share == 1:
        assert np.abs(k).max() < 1e-3
    else:
        assert ((k < 0) & (k >= -1.001)).all()
    # The other decomposition is exact for the wall but not off it.
    other = [d for d in decompositions(h, (H, W), 0.75) if abs(d.normal @ ray.normal) < 0.999]
    if share != 1:
        worst = [PlaneRay.split(mixed_residual, d.at_infinity(PIXELS))[1].max() for d in other]
        assert max(worst) > 0.5


def test_motion_across_the_ray_or_past_infinity_is_off_it():
    r, t = rotation(0.0, 0.01, 0.0), np.array([0.1, 0.0, 0.0])
    _, h = residuals(PIXELS, np.full(len(PIXELS), WALL), r, t)
    ray = decompositions(h, (H, W), 0.75)[0]
    start = ray.at_infinity(PIXELS)
    across = np.stack([-start[:, 1], start[:, 0]], 1) * 2.0
    assert np.allclose(PlaneRay.split(across, start)[1], 2.0 * np.hypot(*start.T), rtol=1e-4)
    past = start * 3.0  # farther than infinity: three times the start, on its line
    assert np.allclose(PlaneRay.split(past, start)[1], 2.0 * np.hypot(*start.T), rtol=1e-4)


def test_no_ray_when_the_plane_only_rotates():
    h = K @ rotation(0.01, 0.03, 0.0) @ np.linalg.inv(K)
    residual = np.random.default_rng(0).normal(0, 2, (len(PIXELS), 2)).astype(np.float32)
    assert fit_plane_ray(h, PIXELS, residual, 0.5, (H, W), 0.75) is None
    assert fit_plane_ray(h, PIXELS, residual, 0.5, (H, W), 0.0) is None  # prior off


def _frame(r, t, depth_map, own_motion):
    """A field and fit over the whole work frame: the wall, a near box and a mover."""
    ys, xs = np.mgrid[0:H, 0:W].astype(np.float32)
    grid = np.stack([xs, ys], -1)
    flat = grid.reshape(-1, 2)
    residual, h = residuals(flat, depth_map.ravel(), r, t)
    source = project_previous(flat, depth_map.ravel(), r, t).astype(np.float32)
    residual += own_motion.reshape(-1, 2)
    source -= own_motion.reshape(-1, 2)
    field = SimpleNamespace(pixel_grid=grid, source_px=source.reshape(H, W, 2), shape=(H, W))
    fit = SimpleNamespace(homography=h, residual_px=residual.reshape(H, W, 2), noise_px=0.05)
    return field, fit


def test_a_near_rigid_object_is_dropped_and_a_mover_is_kept():
    box = np.zeros((H, W), bool)
    box[60:140, 40:120] = True  # a near rigid object, at 0.4 of the wall's depth
    mover = np.zeros((H, W), bool)
    mover[80:160, 200:280] = True  # at the wall's depth, with a motion of its own
    far = np.zeros((H, W), bool)
    far[170:230, 20:100] = True  # rigid, behind the plane: what a followed mover looks like
    depth = np.where(box, 0.4 * WALL, np.where(far, 4 * WALL, WALL))
    own = np.zeros((H, W, 2), np.float32)
    own[mover] = (3.0, -2.0)
    objects = [MovingObject(m, (0, 0, 1, 1), (0.0, 0.0)) for m in (box, mover, far)]
    rigid = RigidDepth(0.5, 0.75)
    # A handheld camera: its translation changes from frame to frame.
    motions = [(0.06, 0.01, 0.02), (0.03, -0.02, 0.04), (0.08, 0.02, -0.01), (0.02, 0.04, 0.03)]
    kept = []
    for i, t in enumerate(motions):
        field, fit = _frame(rotation(0.002 * i, -0.004, 0.001), np.array(t), depth, own)
        rigid.update(field, fit, tolerance=0.5)
        left = rigid.without_rigid(objects)
        kept.append([i for i, obj in enumerate(objects) if any(obj is o for o in left)])
    # Frame 0 gives depths, frame 1 the first prediction; from frame 2 on the
    # box has been predicted twice running and is dropped; the mover never
    # is, nor the far side, which is never judged.
    assert kept == [[0, 1, 2], [0, 1, 2], [1, 2], [1, 2]]


def test_a_depth_measured_under_a_small_translation_predicts_within_its_bounds():
    """A depth measured while the plane's translation is small is known only
    to within the tolerance over ``|r_inf|``; when the translation then grows
    fivefold, its prediction is as loose, and the box is still dropped (a
    point prediction misses it). A mover is still kept."""
    box = np.zeros((H, W), bool)
    box[60:140, 40:120] = True
    mover = np.zeros((H, W), bool)
    mover[80:160, 200:280] = True
    depth = np.where(box, 0.4 * WALL, WALL)
    objects = [MovingObject(m, (0, 0, 1, 1), (0.0, 0.0)) for m in (box, mover)]
    rng = np.random.default_rng(1)
    rigid = RigidDepth(0.5, 0.75)
    kept = []
    for t in [(0.02, 0.0, 0.0), (0.1, 0.01, 0.0), (0.09, -0.01, 0.01)]:
        own = rng.uniform(-0.3, 0.3, (H, W, 2)).astype(np.float32)  # flow noise
        own[mover] += (3.0, -2.0)
        field, fit = _frame(rotation(0.0, -0.002, 0.0), np.array(t), depth, own)
        rigid.update(field, fit, tolerance=0.5)
        left = rigid.without_rigid(objects)
        kept.append([i for i, obj in enumerate(objects) if any(obj is o for o in left)])
    assert kept == [[0, 1], [0, 1], [1]]


def test_a_prediction_is_as_loose_as_the_depth_it_comes_from():
    ray = PlaneRay(np.eye(3), np.eye(3), np.array([0.0, 0.0, 1.0]), 1.0)
    inf = np.array([[-2.0, 0.0]] * 5, np.float32)  # the ray runs toward +x, |r_inf| 2 px
    # k = 0.5 known to +-0.3: a prediction of 1 px along the ray, within
    # sqrt(0.4^2 + (0.3 * 2)^2) = 0.72 px (this frame's tolerance 0.4).
    heights = height_bounds(np.full(5, 0.5, np.float32), np.full(5, 0.3, np.float32))
    low, high = (ray.depth_from_height(heights[:, i]) for i in (0, 1))
    assert np.allclose([low[0], high[0]], [0.2, 0.8], atol=1e-5)
    residual = np.array([[1.0, 0.0], [1.7, 0.0], [1.75, 0.0], [1.0, 0.7], [0.2, 0.0]], np.float32)
    assert ray.predicts(residual, inf, heights, 0.4).tolist() == [True, True, False, True, False]
    # An exact depth predicts to within this frame's tolerance alone.
    exact = height_bounds(np.full(5, 0.5, np.float32), np.zeros(5, np.float32))
    assert ray.predicts(residual, inf, exact, 0.4).tolist() == [True] + [False] * 4
    # A depth that may be at infinity gets a very low bound, k -1 now.
    far = height_bounds(np.array([-0.5], np.float32), np.array([0.6], np.float32))
    assert far[0, 0] < -1e6
    assert abs(ray.depth_from_height(far[:, 0])[0] + 1.0) < 1e-5


def test_off_and_after_a_reset_nothing_is_dropped():
    box = np.zeros((H, W), bool)
    box[60:140, 40:120] = True
    depth = np.where(box, 0.4 * WALL, WALL)
    objects = [MovingObject(box, (0, 0, 1, 1), (0.0, 0.0))]
    for share in (0.0, 0.5):
        rigid = RigidDepth(share, 0.75)
        for i, t in enumerate([(0.06, 0.01, 0.02), (0.03, -0.02, 0.04), (0.08, 0.02, -0.01)]):
            if i == 2 and share:
                rigid.reset()  # a new input: no depth carried from the last
            field, fit = _frame(np.eye(3), np.array(t), depth, np.zeros((H, W, 2), np.float32))
            rigid.update(field, fit, tolerance=0.5)
            assert len(rigid.without_rigid(objects)) == 1


@pytest.mark.parametrize("approach", [0.05, 0.2, 0.4])
def test_a_rigid_point_keeps_its_height_as_the_camera_nears_the_plane(approach):
    """``k`` grows as the camera approaches the wall (k = h / (d - h)); the
    height over the plane in units of its distance, scaled by the plane's
    distance ratio, predicts it (measured: errors 0.001, 0.010, 0.050 against
    0.039, 0.169, 0.383 for carrying ``k`` itself)."""
    near = np.arange(len(PIXELS)) % 2 == 0
    rays = np.linalg.inv(K) @ np.c_[PIXELS, np.ones(len(PIXELS))].T
    points = rays * np.where(near, 2.0, WALL)  # camera axes of frame 0
    normal, distance = np.array([0.0, 0.0, 1.0]), WALL
    depths = []
    for r, t in [
        (rotation(0.01, -0.01, 0.0), np.array([0.05, 0.0, approach])),
        (rotation(0.0, 0.01, 0.0), np.array([-0.04, 0.02, approach])),
    ]:
        moved = r.T @ (points - t[:, None])  # X_prev = R X + t
        normal, distance = r.T @ normal, distance - normal @ t
        image = K @ moved
        current = (image[:2] / image[2]).T.astype(np.float32)
        h = plane_homography(r, t, normal, distance)
        warped = np.c_[current, np.ones(len(current))] @ h.T
        before = K @ points
        residual = (warped[:, :2] / warped[:, 2:] - (before[:2] / before[2]).T).astype(np.float32)
        ray, start = fit_plane_ray(h, current, residual, 0.01, (H, W), 0.75)
        depths.append((ray, PlaneRay.split(residual, start)[0]))
        points = moved
    (_, k1), (ray2, k2) = depths
    predicted = ray2.depth_from_height(height(k1))
    carried = np.abs(k2 - k1)[near].max()
    assert carried > 0.03
    assert np.abs(k2 - predicted)[near].max() < 0.15 * carried
