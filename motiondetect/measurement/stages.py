"""The Maxvideo stages of Appendix A (Figure 10) as pure array functions.

Dataflow, one function per box of Figure 10::

    DIGIMAX   -> to_grey, to_working_size
    VFIR x2   -> blur                      (two cascaded Gaussian passes)
    (reduce)  -> reduce_to_grid            (area averaging, see docs/stages.md)
    ROISTORE  -> FrameDelay (pipeline.py)  (the only state)
    MAX-MUX 1 -> difference_and_average
    VFIR x2   -> gradients                 (two parallel convolutions)
    MAX-MUX 2 -> gradient_polar
    MAX-MUX 3 -> normal_flow
    ROISTORE  -> subsample                 (to 64x64)

Every MAX-MUX stage has a float reference here and a lookup-table twin in
:mod:`motiondetect.measurement.luts`; tests compare the two.

Units: grey levels are 0..255 (16-bit input is scaled by 1/257); distances are
*working-resolution pixels* ("work px"); flow is work px per frame; angles are
radians in image coordinates (x right, y down).
"""

from __future__ import annotations

import cv2
import numpy as np

MIN_FRAME_SIDE = 64
GRID = 64  # the second ROISTORE's output size, per axis

_DTYPES = (np.uint8, np.uint16)


def validate_frame(frame: object, name: str = "frame") -> np.ndarray:
    """Check that ``frame`` is an image OpenCV could deliver.

    Parameters
    ----------
    frame : (H, W) or (H, W, C) ndarray of uint8 or uint16, C in {1, 3, 4}
        H and W at least 64.

    Raises
    ------
    ValueError
        Naming ``name``, what was expected and what came in.
    """
    if not isinstance(frame, np.ndarray):
        raise ValueError(f"{name} must be a numpy ndarray, but got {type(frame).__name__}")
    if frame.dtype not in _DTYPES:
        raise ValueError(f"{name} must have dtype uint8 or uint16, but got {frame.dtype}")
    if frame.ndim == 3 and frame.shape[2] not in (1, 3, 4):
        raise ValueError(
            f"{name} must have 1, 3 or 4 channels (grey, BGR, BGRA), but got shape {frame.shape}"
        )
    if frame.ndim not in (2, 3):
        raise ValueError(f"{name} must be a 2-D or 3-D array, but got shape {frame.shape}")
    h, w = frame.shape[:2]
    if h < MIN_FRAME_SIDE or w < MIN_FRAME_SIDE:
        raise ValueError(
            f"{name} must be at least {MIN_FRAME_SIDE}x{MIN_FRAME_SIDE} pixels, "
            f"but got {w}x{h} (width x height)"
        )
    return frame


def to_grey(frame: np.ndarray) -> np.ndarray:
    """Convert a validated frame to one grey channel on the 0..255 scale.

    Parameters
    ----------
    frame : (H, W) or (H, W, C) ndarray of uint8 or uint16
        Grey, BGR or BGRA, as ``cv2.VideoCapture`` or ``cv2.imread`` deliver it.

    Returns
    -------
    grey : (H, W) ndarray
        uint8 for 8-bit input; float32 in 0..255 for 16-bit input.
    """
    validate_frame(frame)
    if frame.ndim == 3:
        code = {1: None, 3: cv2.COLOR_BGR2GRAY, 4: cv2.COLOR_BGRA2GRAY}[frame.shape[2]]
        frame = frame[:, :, 0] if code is None else cv2.cvtColor(frame, code)
    if frame.dtype == np.uint16:
        return frame.astype(np.float32) * np.float32(1.0 / 257.0)
    return frame


def working_size(width: int, height: int, work_size: int) -> tuple[int, int]:
    """The (width, height) of the working resolution.

    The long side becomes ``work_size`` (up or down), keeping the aspect
    ratio, but the short side never drops below 64 pixels.
    """
    if work_size < MIN_FRAME_SIDE:
        raise ValueError(f"work_size must be at least {MIN_FRAME_SIDE}, but got {work_size}")
    scale = work_size / max(width, height)
    scale = max(scale, MIN_FRAME_SIDE / min(width, height))
    return max(MIN_FRAME_SIDE, round(width * scale)), max(MIN_FRAME_SIDE, round(height * scale))


def to_working_size(grey: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """Resample a grey frame to ``size`` = (width, height).

    Area averaging when shrinking (anti-aliased), bilinear when enlarging.
    """
    h, w = grey.shape
    if (w, h) == tuple(size):
        return grey
    shrink = size[0] * size[1] < w * h
    return cv2.resize(grey, size, interpolation=cv2.INTER_AREA if shrink else cv2.INTER_LINEAR)


def blur(image: np.ndarray, sigma_px: float) -> np.ndarray:
    """Two cascaded Gaussian convolutions: the two VFIR units of Figure 10.

    Parameters
    ----------
    image : (H, W) ndarray of uint8 or float32
    sigma_px : float
        Standard deviation of *each* pass, in pixels of ``image``. The
        cascade is equivalent to one Gaussian of ``sigma_px * sqrt(2)``.

    Returns
    -------
    blurred : (H, W) ndarray of float32
    """
    if sigma_px <= 0:
        raise ValueError(f"sigma_px must be positive, but got {sigma_px}")
    out = image.astype(np.float32, copy=False)
    for _ in range(2):
        out = cv2.GaussianBlur(out, (0, 0), sigma_px, borderType=cv2.BORDER_REFLECT_101)
    return out


def reduce_to_grid(image: np.ndarray, grid_shape: tuple[int, int]) -> np.ndarray:
    """Area-average ``image`` onto a (rows, cols) grid.

    The grid may sample the two axes differently (non-square frames map onto
    a square grid); :func:`gradients` takes the spacing into account.
    """
    rows, cols = grid_shape
    if image.shape == (rows, cols):
        return image
    h, w = image.shape
    interp = cv2.INTER_AREA if (rows <= h and cols <= w) else cv2.INTER_LINEAR
    return cv2.resize(image, (cols, rows), interpolation=interp)


def difference_and_average(
    previous: np.ndarray, current: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """MAX-MUX 1 (float reference): temporal difference and mean grey level.

    Parameters
    ----------
    previous, current : (H, W) ndarray of float32
        Consecutive blurred frames, grey levels.

    Returns
    -------
    difference : (H, W) ndarray of float32
        ``current - previous``: the temporal derivative, grey levels per frame.
    average : (H, W) ndarray of float32
        ``(current + previous) / 2``: the unbiased grey level at mid-frame.
    """
    return current - previous, (current + previous) * np.float32(0.5)


_DERIVATIVE_TAPS = np.array([1.0, -8.0, 0.0, 8.0, -1.0], np.float32) / 12.0
_PASS_THROUGH = np.array([1.0], np.float32)


def gradients(
    average: np.ndarray, spacing_px: tuple[float, float]
) -> tuple[np.ndarray, np.ndarray]:
    """x and y partial derivatives: the two parallel convolutions.

    A 5-tap central difference, exact to fourth order, with no cross-axis
    smoothing (the blur stage already smoothed). docs/stages.md compares it
    with a Sobel pair: on the 128 grid the Sobel pair under-reads the
    gradient by several percent, which biases the normal flow by as much.
    The result is divided by the grid spacing, so it is in grey levels per
    *working* pixel even when the grid samples x and y differently.

    Parameters
    ----------
    average : (H, W) ndarray of float32
    spacing_px : (float, float)
        Grid spacing (dx, dy) in working pixels.

    Returns
    -------
    gx, gy : (H, W) ndarray of float32
    """
    dx, dy = spacing_px
    gx = cv2.sepFilter2D(
        average,
        cv2.CV_32F,
        _DERIVATIVE_TAPS / np.float32(dx),
        _PASS_THROUGH,
        borderType=cv2.BORDER_REPLICATE,
    )
    gy = cv2.sepFilter2D(
        average,
        cv2.CV_32F,
        _PASS_THROUGH,
        _DERIVATIVE_TAPS / np.float32(dy),
        borderType=cv2.BORDER_REPLICATE,
    )
    return gx, gy


def gradient_polar(gx: np.ndarray, gy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """MAX-MUX 2 (float reference): gradient magnitude and direction.

    Returns
    -------
    magnitude : (H, W) ndarray of float32
        Grey levels per working pixel.
    direction_rad : (H, W) ndarray of float32
        ``atan2(gy, gx)`` in [-pi, pi], image coordinates (y down).
    """
    magnitude = cv2.magnitude(gx, gy)
    direction = np.arctan2(gy, gx)
    return magnitude, direction


def normal_flow(
    difference: np.ndarray, magnitude: np.ndarray, min_gradient: float
) -> tuple[np.ndarray, np.ndarray]:
    """MAX-MUX 3 (float reference): the gradient-parallel flow component.

    ``m = -dI/dt / |grad I|``, signed along the gradient direction, so that a
    pattern translating with velocity ``v`` gives ``m = v . n``.

    Parameters
    ----------
    difference : (H, W) ndarray of float32
        Temporal derivative, grey levels per frame.
    magnitude : (H, W) ndarray of float32
        Gradient magnitude, grey levels per working pixel.
    min_gradient : float
        Below this magnitude the measurement is too weak to trust.

    Returns
    -------
    flow_px : (H, W) ndarray of float32
        Normal flow in working pixels per frame; 0 where invalid.
    valid : (H, W) ndarray of bool
    """
    valid = magnitude >= min_gradient
    safe = np.where(valid, magnitude, np.float32(1.0))
    flow = np.where(valid, -difference / safe, np.float32(0.0)).astype(np.float32, copy=False)
    return flow, valid


def subsample(key: np.ndarray, *fields: np.ndarray, grid: int = GRID) -> tuple[np.ndarray, ...]:
    """The second ROISTORE: reduce (G*k, G*k) fields to (G, G).

    Each k x k block keeps the one sample where ``key`` is largest. With
    ``key`` the gradient magnitude this keeps the most trustworthy normal-flow
    measurement of each block (its error grows like 1/|grad I|), where plain
    decimation would keep an arbitrary one and averaging would mix
    projections onto different directions.

    Parameters
    ----------
    key : (G*k, G*k) ndarray
    *fields : (G*k, G*k) ndarrays, sampled at the same place as the key
    grid : int
        G, the output size per axis.

    Returns
    -------
    tuple of (G, G) ndarrays
        The reduced key, then each reduced field.
    """
    rows_total, cols_total = key.shape
    ky, kx = rows_total // grid, cols_total // grid
    if ky * grid != rows_total or kx * grid != cols_total:
        raise ValueError(f"key must be a multiple of {grid} per axis, but got shape {key.shape}")
    if ky == kx == 1:
        return (key, *fields)

    blocks = key.reshape(grid, ky, grid, kx).transpose(0, 2, 1, 3).reshape(grid, grid, ky * kx)
    pick = np.argmax(blocks, axis=2)
    # One flat index into the full-size arrays, then a plain gather per field.
    rows = np.arange(grid)[:, None] * ky + pick // kx
    cols = np.arange(grid)[None, :] * kx + pick % kx
    flat = rows * cols_total + cols
    return tuple(a.ravel()[flat] for a in (key, *fields))
