"""Where the image changed once the camera's motion is undone.

A mover changes the image where it is; flow alone can be wrong (blank sky,
water, the boundaries DIS smears across). The plane difference is the
current working frame against the previous one warped by the fitted
dominant plane; the chained difference reaches further back through the
product of several frames' planes, so a slow mover, which changes the
image by less than the noise in one frame, shows over several.

A camera's automatic exposure changes the brightness of the whole frame
by a few per cent a frame as the view moves. Over one frame that is within
the difference's noise; over several it adds up on every pixel, so the
comparisons that reach back several frames (the chained difference, the
remembered background) first match the older image's exposure to the
current one (:func:`matched_exposure`).
"""

from __future__ import annotations

import cv2
import numpy as np

from motiondetect.measurement.dense_flow import VelocityField

#: Gaussian 1-D noise: median |x| = sigma / 1.4826.
_ABS_MEDIAN_TO_SIGMA = 1.4826
#: Grey levels trusted for the exposure ratio: neither near black (where
#: noise and the sensor's offset dominate) nor near clipping.
_MID_TONES = (16, 240)
#: Exposure ratios closer to 1 than this are left alone (under one grey
#: level at mid-grey).
_SAME_EXPOSURE = 0.005


def matched_exposure(older: np.ndarray, current: np.ndarray) -> np.ndarray:
    """``older`` scaled to ``current``'s exposure, same shape and dtype.

    The exposure ratio is the median of ``current / older`` over the
    mid-tone pixels of every second row and column: the two images are
    registered (warped by the fitted planes), so most pixels show the same
    scene and the median ignores the movers and the pixels that entered the
    view. ``older`` is returned as it is when the ratio is within 0.5 % of 1.

    Parameters
    ----------
    older : (h, w) ndarray of uint8 or float32
        Grey levels, registered to ``current``.
    current : (h, w) ndarray of uint8 or float32
    """
    a = older[::2, ::2].astype(np.float32)
    b = current[::2, ::2].astype(np.float32)
    low, high = _MID_TONES
    usable = (a > low) & (a < high) & (b > low) & (b < high)
    if usable.sum() < 100:
        return older
    gain = float(np.median(b[usable] / a[usable]))
    if abs(gain - 1.0) < _SAME_EXPOSURE:
        return older
    if older.dtype == np.uint8:
        return cv2.convertScaleAbs(older, alpha=gain)
    return older * np.float32(gain)


def _warped_back(
    image: np.ndarray, field: VelocityField, homography: np.ndarray, offsets: np.ndarray | None
) -> np.ndarray:
    """``image`` (previous-frame pixels) at the current frame's pixels, each
    taken from where the plane (plus ``offsets``) says it was; 0 where that
    lies outside the previous frame."""
    h, w = field.shape
    if offsets is not None:
        grid = field.pixel_grid.reshape(-1, 1, 2)
        previous = cv2.perspectiveTransform(grid, homography).reshape(h, w, 2) - offsets
        return cv2.remap(image, previous, None, cv2.INTER_LINEAR)
    return _through(image, homography)


def _through(image: np.ndarray, homography: np.ndarray) -> np.ndarray:
    """``image`` (an earlier frame's pixels, (h, w)) at the current frame's
    pixels, each taken from where ``homography`` (current pixels to that
    frame's) says it was; 0 where that lies outside."""
    h, w = image.shape[:2]
    return cv2.warpPerspective(image, homography, (w, h), flags=cv2.WARP_INVERSE_MAP)


def plane_difference(
    field: VelocityField, homography: np.ndarray, offsets: np.ndarray | None = None
) -> np.ndarray:
    """``|grey - previous grey warped by the plane|``, (h, w) uint8 grey levels;
    ``offsets`` (h, w, 2) work px/frame, the velocity a rolling shutter adds
    to the plane's (:mod:`~motiondetect.constraint_ray.rolling_shutter`).
    Where the view has just entered (:func:`seen_before` false) the previous
    frame has nothing to give, and the difference is the grey level itself."""
    return cv2.absdiff(_warped_back(field.previous_grey, field, homography, offsets), field.grey)


def seen_before(
    field: VelocityField, homography: np.ndarray, offsets: np.ndarray | None = None
) -> np.ndarray:
    """(h, w) bool: the current pixels that the plane (plus ``offsets``, as
    :func:`plane_difference`) takes from inside the previous frame, so that
    their plane difference compares two pictures of the same place; the rest
    entered the view with this frame (a fast pan's leading edge)."""
    inside = np.full(field.previous_grey.shape, 255, np.uint8)
    return _warped_back(inside, field, homography, offsets) == 255


def chained_difference(
    oldest: np.ndarray, homographies: list[np.ndarray], grey: np.ndarray
) -> np.ndarray:
    """``|grey - oldest warped by the chained planes|``, (h, w) uint8 grey
    levels, at matched exposure.

    Parameters
    ----------
    oldest : (h, w) ndarray of uint8
        The working frame ``k`` frames back.
    homographies : list of (3, 3) ndarray
        Each frame's plane, current work pixels to the previous frame's,
        oldest first (``k`` of them, the current frame's last).
    grey : (h, w) ndarray of uint8
        The current working frame.
    """
    warped = _through(oldest, _chain(homographies))
    return cv2.absdiff(matched_exposure(warped, grey), grey)


def chained_seen(homographies: list[np.ndarray], shape: tuple[int, int]) -> np.ndarray:
    """(h, w) bool: the current pixels the chained planes (as
    :func:`chained_difference`) take from inside the frame ``k`` back, so
    that their chained difference compares two pictures of one place; the
    rest entered the view since (``k`` frames of a pan's leading edge)."""
    return _through(np.full(shape, 255, np.uint8), _chain(homographies)) == 255


def _chain(homographies: list[np.ndarray]) -> np.ndarray:
    """The product mapping current pixels to the frame ``k`` back."""
    chain = np.eye(3)
    for homography in homographies:  # p_{t-k} = H_{t-k+1} ... H_t p_t
        chain = chain @ homography
    return chain


def difference_noise(difference: np.ndarray, where: np.ndarray | None = None) -> float:
    """Robust sigma of a (h, w) uint8 difference image plus one grey level of
    quantisation, grey levels: most of a frame is explained by the plane, so
    the median difference is its noise (found by histogram). ``where``, a
    (h, w) bool mask, limits it to those pixels."""
    mask = None if where is None else where.view(np.uint8)
    counts = cv2.calcHist([difference], [0], mask, [256], [0, 256]).ravel()
    cumulative = np.cumsum(counts)
    median = int(np.searchsorted(cumulative, cumulative[-1] / 2))
    return median * _ABS_MEDIAN_TO_SIGMA + 1.0


def sharpness(grey: np.ndarray) -> float:
    """Variance of the Laplacian of a (h, w) uint8 frame, grey levels squared:
    fine texture, which motion blur removes."""
    return float(cv2.Laplacian(grey, cv2.CV_32F).var())
