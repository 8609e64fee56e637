"""Each object's pixels go to the motion layer that predicts them: known answers."""

import numpy as np
import pytest

from motiondetect.constraint_ray.camera_fit import CameraFit
from motiondetect.detection.layers import assigned, assigned_objects
from motiondetect.detection.objects import MovingObject
from motiondetect.measurement.dense_flow import VelocityField, pixel_grid
from motiondetect.measurement.normal_flow import GridGeometry

H, W = 120, 160
SHIFT = 3  # the mover's velocity, px/frame along x; the camera is still


def _scene(background_texture: bool, squares=((40, 40),)):
    """Textured squares of side 30 moving SHIFT px right over a still background,
    textured or plain; each square's object mask carries a 6-px halo."""
    rng = np.random.default_rng(1)
    background = (
        rng.integers(0, 255, (H, W)) if background_texture else np.full((H, W), 128)
    ).astype(np.uint8)
    previous, grey = background.copy(), background.copy()
    truth = np.zeros((H, W), bool)
    for y, x in squares:
        texture = rng.integers(0, 255, (30, 30)).astype(np.uint8)
        previous[y : y + 30, x : x + 30] = texture
        grey[y : y + 30, x + SHIFT : x + SHIFT + 30] = texture
        truth[y : y + 30, x + SHIFT : x + SHIFT + 30] = True
    geometry = GridGeometry((W, H), (W, H))
    velocity = np.zeros((H, W, 2), np.float32)
    field = VelocityField(velocity, grey, previous, geometry, pixel_grid(W, H))
    plane_difference = np.abs(grey.astype(int) - previous.astype(int)).astype(np.uint8)
    return field, plane_difference, truth


def _object(truth: np.ndarray, halo: int) -> MovingObject:
    ys, xs = np.nonzero(truth)
    y0, y1 = max(ys.min() - halo, 0), min(ys.max() + 1 + halo, H)
    x0, x1 = max(xs.min() - halo, 0), min(xs.max() + 1 + halo, W)
    mask = np.zeros((H, W), bool)
    mask[y0:y1, x0:x1] = True
    return MovingObject(mask, (x0, y0, x1, y1), (float(SHIFT), 0.0))


def test_the_halo_the_plane_predicts_leaves_the_object():
    """Over a textured still background, the 6-px halo goes; the mover stays whole."""
    field, difference, truth = _scene(background_texture=True)
    obj = _object(truth, halo=6)
    out = assigned(obj, field, difference, margin=6.0, min_area=30)
    assert out.mask[truth].mean() > 0.97  # the mover kept
    assert (out.mask & ~truth).sum() < 0.3 * (obj.mask & ~truth).sum()  # most halo gone
    x0, y0, x1, y1 = out.box
    assert abs(x0 - (40 + SHIFT)) <= 3 and abs(x1 - (70 + SHIFT)) <= 3
    assert abs(y0 - 40) <= 3 and abs(y1 - 70) <= 3


def test_a_plain_background_cannot_tell_and_the_object_stays():
    """On a plain background both layers predict the halo equally well."""
    field, difference, truth = _scene(background_texture=False)
    obj = _object(truth, halo=6)
    out = assigned(obj, field, difference, margin=6.0, min_area=30)
    assert out is obj


def test_a_cut_into_two_movers_keeps_the_object_whole():
    """Two movers grouped as one would come apart: the object is left as it was."""
    field, difference, truth = _scene(True, squares=((40, 20), (40, 100)))
    obj = _object(truth, halo=6)
    assert assigned(obj, field, difference, margin=6.0, min_area=30) is obj


@pytest.mark.parametrize(("sigmas", "changed"), [(3.0, True), (0.0, False)])
def test_assigned_objects_follows_its_setting(sigmas, changed):
    field, difference, truth = _scene(background_texture=True)
    obj = _object(truth, halo=6)
    fit = CameraFit(np.eye(3), None, 0.1, 0.9, None, "", 0.0, difference, change_noise=2.0)
    (out,) = assigned_objects([obj], field, fit, sigmas, min_area_share=0.001)
    assert (out is not obj) == changed
