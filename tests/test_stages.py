"""The Maxvideo stages against exact motion (issue 2)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from motiondetect.measurement import stages
from motiondetect.measurement.normal_flow import NormalFlowPipeline, StageConfig

from .conftest import as_uint8, fourier_shift

# Tolerances, px/frame at the working resolution.
MEDIAN_TOL = 0.15
P90_TOL = 0.5


def measure(f0: np.ndarray, f1: np.ndarray, config: StageConfig | None = None):
    pipe = NormalFlowPipeline(config)
    assert pipe.process(f0) is None
    field = pipe.process(f1)
    assert field is not None
    return field


def interior(field) -> np.ndarray:
    mask = field.valid.copy()
    mask[:2], mask[-2:], mask[:, :2], mask[:, -2:] = False, False, False, False
    return mask


def translation_errors(photo, speed, angle, config=None):
    vx, vy = speed * np.cos(angle), speed * np.sin(angle)
    f0 = as_uint8(fourier_shift(photo, -vx / 2, -vy / 2))
    f1 = as_uint8(fourier_shift(photo, vx / 2, vy / 2))
    field = measure(f0, f1, config)
    scale = field.geometry.work_size[0] / photo.shape[1]
    nx, ny = field.normal
    truth = (vx * nx + vy * ny) * scale
    mask = interior(field)
    assert mask.mean() > 0.5, "most of a textured photo should be measurable"
    return np.abs(field.flow_px - truth)[mask] / scale


@pytest.mark.parametrize("speed", [0.5, 1.0, 2.0, 3.0, 4.0])
def test_known_translation_matches_v_dot_n(photo, speed):
    errors = np.concatenate(
        [translation_errors(photo, speed, 2 * np.pi * k / 16) for k in range(16)]
    )
    assert np.median(errors) <= MEDIAN_TOL
    assert np.percentile(errors, 90) <= P90_TOL


def test_fast_translation_uses_the_coarse_level(photo):
    errs_pyr = translation_errors(photo, 8.0, 0.3)
    errs_flat = translation_errors(photo, 8.0, 0.3, StageConfig(pyramid=False))
    assert np.median(errs_pyr) < 0.8 * np.median(errs_flat)
    assert np.median(errs_pyr) <= 0.5


def test_identical_frames_give_zero_flow(photo):
    field = measure(photo, photo)
    assert field.valid.mean() > 0.5
    assert np.all(field.flow_px == 0.0)


def test_global_brightness_change_reads_as_flow(photo):
    """Documented behaviour: +d grey levels everywhere gives m = -d / |grad I|."""
    brighter = as_uint8(photo.astype(np.float64) + 10.0)
    field = measure(photo, brighter, StageConfig(pyramid=False))
    mask = interior(field) & (field.gradient > 2.0)
    expected = -10.0 / field.gradient[mask]
    unclipped = (photo < 245).mean()
    assert unclipped > 0.95
    assert np.median(np.abs(field.flow_px[mask] - expected)) < 0.1


def _warp_pair(photo, matrix_half):
    """Frames at -half and +half of a similarity motion about the centre."""
    big = cv2.GaussianBlur(photo, (0, 0), 1.0)
    h, w = big.shape
    frames = []
    for sign in (-1, 1):
        angle_deg, scale = matrix_half
        m = cv2.getRotationMatrix2D((w / 2 - 0.5, h / 2 - 0.5), sign * angle_deg, scale**sign)
        frames.append(
            cv2.warpAffine(big, m, (w, h), flags=cv2.INTER_CUBIC, borderMode=cv2.BORDER_REFLECT)
        )
    return frames


@pytest.mark.parametrize(
    ("angle_deg", "zoom"), [(0.5, 1.0), (-0.5, 1.0), (0.0, 1.005), (0.0, 0.995)]
)
def test_rotation_and_zoom_match_the_analytic_field(photo, angle_deg, zoom):
    f0, f1 = _warp_pair(photo, (angle_deg / 2, np.sqrt(zoom)))
    field = measure(f0, f1)
    x, y = field.geometry.cell_centres_px()
    cx, cy = (np.array(field.geometry.work_size) - 0) / 2
    dx, dy = x - cx, y - cy
    # OpenCV's positive angle is counter-clockwise on screen (y down).
    w = -np.deg2rad(angle_deg)
    vx = -w * dy + (zoom - 1) * dx
    vy = w * dx + (zoom - 1) * dy
    nx, ny = field.normal
    truth = vx * nx + vy * ny
    mask = interior(field)
    err = np.abs(field.flow_px - truth)[mask]
    # Sub-cell position of the chosen sample adds up to |omega| * 3 px.
    assert np.median(err) <= MEDIAN_TOL
    assert np.corrcoef(field.flow_px[mask], truth[mask])[0, 1] > 0.9


def test_lookup_tables_agree_with_float(photo):
    f0 = as_uint8(fourier_shift(photo, -1.0, -0.5))
    f1 = as_uint8(fourier_shift(photo, 1.0, 0.5))
    fl = measure(f0, f1, StageConfig(arithmetic="float"))
    lut = measure(f0, f1, StageConfig(arithmetic="lut"))
    both = interior(fl) & interior(lut)
    diff = np.abs(fl.flow_px - lut.flow_px)[both]
    # Stated bound (docs/stages.md): median 0.1, 90th percentile 0.4 px/frame.
    assert np.median(diff) <= 0.1
    assert np.percentile(diff, 90) <= 0.4
    ang = np.angle(np.exp(1j * (fl.direction_rad - lut.direction_rad)))[both]
    assert np.percentile(np.abs(ang), 90) < np.deg2rad(5)
    assert (fl.valid != lut.valid).mean() < 0.05


def test_non_square_frame_translation(photo):
    crop = photo[:288, :]  # 512 x 288
    errors = []
    for k in range(8):
        angle = 2 * np.pi * k / 8
        vx, vy = 2 * np.cos(angle), 2 * np.sin(angle)
        f0 = as_uint8(fourier_shift(crop, -vx / 2, -vy / 2))
        f1 = as_uint8(fourier_shift(crop, vx / 2, vy / 2))
        field = measure(f0, f1)
        assert field.flow_px.shape == (64, 64)
        assert field.geometry.cell_px == (8.0, 4.5)
        nx, ny = field.normal
        mask = interior(field)
        errors.append(np.abs(field.flow_px - (vx * nx + vy * ny))[mask])
    assert np.median(np.concatenate(errors)) <= MEDIAN_TOL


def test_input_formats_agree(photo):
    f0 = as_uint8(fourier_shift(photo, -1, 0))
    f1 = as_uint8(fourier_shift(photo, 1, 0))
    ref = measure(f0, f1)
    bgr = measure(*(cv2.cvtColor(f, cv2.COLOR_GRAY2BGR) for f in (f0, f1)))
    bgra = measure(*(cv2.cvtColor(f, cv2.COLOR_GRAY2BGRA) for f in (f0, f1)))
    deep = measure(*(f.astype(np.uint16) * 257 for f in (f0, f1)))
    one = measure(f0[..., None], f1[..., None])
    for other in (bgr, bgra, deep, one):
        np.testing.assert_allclose(other.flow_px, ref.flow_px, atol=1e-3)


@pytest.mark.parametrize(
    ("frame", "message"),
    [
        ([[1, 2]], "must be a numpy ndarray, but got list"),
        (np.zeros((64, 64), np.float32), "dtype uint8 or uint16, but got float32"),
        (np.zeros((63, 100), np.uint8), "at least 64x64 pixels, but got 100x63"),
        (np.zeros((64, 64, 2), np.uint8), "1, 3 or 4 channels"),
        (np.zeros((64, 64, 3, 1), np.uint8), "2-D or 3-D array"),
    ],
)
def test_bad_frames_raise_value_error_naming_the_parameter(frame, message):
    with pytest.raises(ValueError, match="frame") as info:
        NormalFlowPipeline().process(frame)
    assert message in str(info.value)


def test_frame_size_change_resets_the_delay(photo):
    pipe = NormalFlowPipeline()
    pipe.process(photo)
    assert pipe.process(photo[:256, :256]) is None


def test_blur_is_two_cascaded_gaussians():
    impulse = np.zeros((101, 101), np.float32)
    impulse[50, 50] = 1.0
    out = stages.blur(impulse, 3.0)
    ys, xs = np.mgrid[:101, :101]
    var = (out * ((xs - 50) ** 2)).sum() / out.sum()
    assert var == pytest.approx(2 * 3.0**2, rel=0.02)


def test_subsample_keeps_the_strongest_sample_per_block():
    key = np.arange(128 * 128, dtype=np.float32).reshape(128, 128)[::-1].copy()
    value = key * 2
    k, v = stages.subsample(key, value)
    assert k.shape == (64, 64)
    assert k[0, 0] == key[:2, :2].max()
    np.testing.assert_array_equal(v, k * 2)


def test_working_size_keeps_aspect_and_minimum():
    assert stages.working_size(1920, 1080, 512) == (512, 288)
    assert stages.working_size(352, 288, 512) == (512, 419)
    assert stages.working_size(1000, 64, 512) == (1000, 64)
    with pytest.raises(ValueError, match="work_size"):
        stages.working_size(100, 100, 10)


def test_bin_table_equals_searchsorted():
    from motiondetect.constraint_ray.normal_filter import MAGNITUDE_EDGES
    from motiondetect.measurement.luts import BinTable

    table = BinTable(MAGNITUDE_EDGES, step=0.125, limit=9.0)
    edges = MAGNITUDE_EDGES[1:-1]
    x = np.concatenate(
        [
            np.random.default_rng(0).uniform(-12, 12, 10000),
            edges,
            np.nextafter(edges, -np.inf),
            [np.inf, -np.inf, np.nan, 1e30, -1e30],
        ]
    )
    np.testing.assert_array_equal(table(x), np.searchsorted(MAGNITUDE_EDGES, x, side="right"))
    with pytest.raises(ValueError, match="grid"):
        BinTable(np.array([0.0, 0.3]), step=0.125, limit=9.0)
