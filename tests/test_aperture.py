"""The aperture problem: only the velocity the image determines is tested (issue 13)."""

from __future__ import annotations

import numpy as np
import pytest

from motiondetect.constraint_ray.plane import explained_share
from motiondetect.measurement.aperture import determined, structure_tensor
from motiondetect.measurement.dense_flow import VelocityField, pixel_grid
from motiondetect.measurement.normal_flow import GridGeometry


def stripes(shape=(64, 64), period=8):
    """Vertical stripes: the gradient is all along x."""
    x = np.arange(shape[1])
    row = 128 + 100 * np.sin(2 * np.pi * x / period)
    return np.tile(row, (shape[0], 1)).astype(np.uint8)


def checks(shape=(64, 64), period=8):
    """A 2-D pattern: gradients both ways."""
    y, x = np.mgrid[: shape[0], : shape[1]]
    image = 128 + 60 * np.sin(2 * np.pi * x / period) + 60 * np.sin(2 * np.pi * y / period)
    return image.astype(np.uint8)


def at_centre(residual, grey, energy):
    field = np.broadcast_to(np.float32(residual), grey.shape + (2,))
    return determined(field, structure_tensor(grey, 9), energy)[32, 32]


def test_motion_along_stripes_is_not_determined_motion_across_them_is():
    grey = stripes()
    a, b, c = (t[32, 32] for t in structure_tensor(grey, 9))
    assert c < 1e-3 * a and abs(b) < 1e-3 * a  # gradient energy only along x
    assert np.allclose(at_centre((0.0, 2.0), grey, 4.0), 0.0, atol=1e-3)
    across = at_centre((2.0, 0.0), grey, 4.0)
    assert across[0] == pytest.approx(2.0 * a / (a + 4.0), rel=1e-4) and abs(across[1]) < 1e-3
    # a component counts half where its gradient energy equals the noise energy
    assert at_centre((2.0, 0.0), grey, float(a))[0] == pytest.approx(1.0, rel=1e-4)


def test_a_two_dimensional_pattern_determines_the_whole_motion():
    grey = checks()
    for residual in ((0.0, 2.0), (2.0, 0.0), (1.5, -1.5)):
        kept = at_centre(residual, grey, 4.0)
        assert np.linalg.norm(kept) >= 0.95 * np.linalg.norm(residual)


def test_a_blank_patch_determines_nothing():
    grey = np.full((64, 64), 90, np.uint8)
    assert np.allclose(at_centre((3.0, -1.0), grey, 4.0), 0.0)


@pytest.mark.parametrize(
    ("pattern", "residual", "share"),
    [(stripes, (0.0, 3.0), 1.0), (stripes, (3.0, 0.0), 0.0), (checks, (0.0, 3.0), 0.0)],
)
def test_the_fit_confidence_counts_only_what_the_image_determines(pattern, residual, share):
    """No sample is a RANSAC inlier; a 3 px residual along stripes is the
    flow's fill-in and does not count against the plane, one the image
    determines does."""
    grey = pattern()
    h, w = grey.shape
    zero = np.zeros((h, w, 2), np.float32)
    field = VelocityField(
        zero, grey, grey, GridGeometry((w, h), (w, h)), pixel_grid(w, h), patch_px=9
    )
    step, energy = 8, 16.0  # the samples' grid; 4 grey levels of noise, squared
    n = grey[step:-step:step, step:-step:step].size
    sampled = np.tile(np.float32(residual), (n, 1))
    assert explained_share(field, sampled, np.zeros(n, bool), energy, step, 1.0) == share
    assert explained_share(field, sampled, np.ones(n, bool), energy, step, 1.0) == 1.0
    assert explained_share(field, sampled, np.zeros(n, bool), 0.0, step, 1.0) == 0.0
