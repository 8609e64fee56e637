"""An object's mask shaped: outlined by the image change, trimmed of
uncovered background, closed over its gaps and its holes filled.

Pure functions on (h, w) uint8 0/1 masks at working size; the settings are
:class:`~.objects.TrackConfig`'s, passed in as values.
"""

from __future__ import annotations

import cv2
import numpy as np

from motiondetect.detection.regions import components_with_stats

#: Side of the window an image change is averaged over when it supports an
#: object, work px.
CHANGE_BOX = 3

#: Smallest share of an object a cut may keep: here its outline, in
#: :mod:`.layers` the pixels its own velocity predicts. A cut that would
#: take more is not trimming a band of background off a mover; it tells of
#: an object the cut does not fit: one whose image barely changes (a
#: followed, plain mover) or one its own velocity describes poorly (a
#: turning or deforming mover).
MIN_KEPT = 0.5


def within(mask: np.ndarray, near: np.ndarray, reach: int) -> np.ndarray:
    """The pixels of a (h, w) uint8 0/1 ``mask`` within ``reach`` px (a
    square) of the (h, w) bool ``near``."""
    near = near.astype(np.uint8)
    if reach > 0:
        near = cv2.dilate(near, np.ones((2 * reach + 1,) * 2, np.uint8))
    return mask & near


def outlined(own: np.ndarray, near: np.ndarray, close: np.ndarray | None) -> np.ndarray:
    """An object's pixels that lie near the image change.

    Parameters
    ----------
    own : (h, w) ndarray of uint8, 0/1
        The object's flagged pixels.
    near : (h, w) ndarray of uint8, 0/1
        Pixels within ``outline_px`` of the image change.
    close : (k, k) ndarray of uint8 or None
        The object's closing kernel.

    Returns
    -------
    (h, w) ndarray of uint8, 0/1
        ``own & near`` without the crumbs the cut leaves (parts smaller than
        the change map's ``CHANGE_BOX`` square, which the change cannot
        outline); or ``own`` when that keeps less than ``MIN_KEPT`` of it,
        or when it leaves the closed object in more parts than before (the
        cut went through the mover, not round it).
    """
    kept = own & near
    size, cut = int(cv2.countNonZero(own)), int(cv2.countNonZero(kept))
    if cut == size or cut < MIN_KEPT * size:  # nothing to cut, or too much
        return own
    count, labels, stats = components_with_stats(kept)
    crumbs = np.flatnonzero(stats[1:, cv2.CC_STAT_AREA] < CHANGE_BOX**2) + 1
    if len(crumbs):
        kept[np.isin(labels, crumbs)] = 0
        if cv2.countNonZero(kept) < MIN_KEPT * size:
            return own
    if count - 1 - len(crumbs) > 1 and _parts(kept, close) > _parts(own, close):
        return own  # (one part stays one part when closed: no need to look)
    return kept


def _parts(mask: np.ndarray, close: np.ndarray | None) -> int:
    """Parts of a (h, w) uint8 0/1 mask once closed with ``close``, crumbs
    (smaller than ``CHANGE_BOX`` squared) not counted."""
    if close is not None:
        mask = cv2.morphologyEx(mask, cv2.MORPH_CLOSE, close)
    _, _, stats = components_with_stats(mask)
    return int(np.count_nonzero(stats[1:, cv2.CC_STAT_AREA] >= CHANGE_BOX**2))


def shaped(
    own: np.ndarray,
    near: np.ndarray | None,
    kept: np.ndarray | None,
    close: np.ndarray | None,
    trim_share: float,
) -> np.ndarray:
    """An object's mask outlined (with ``near``, :func:`outlined`), trimmed
    (with ``kept``, :func:`trimmed`), closed and its holes filled, (h, w)
    uint8 0/1; a step whose mask is None is skipped."""
    if near is not None:
        own = outlined(own, near, close)
    if kept is not None:
        own = trimmed(own, kept, close, trim_share)
    if close is not None:
        own = cv2.morphologyEx(own, cv2.MORPH_CLOSE, close)
    return filled(own)


def filled(mask: np.ndarray) -> np.ndarray:
    """A (h, w) uint8 0/1 mask with the holes of its parts filled, in place."""
    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    cv2.drawContours(mask, contours, -1, 1, thickness=cv2.FILLED)
    return mask


def trimmed(
    own: np.ndarray, kept: np.ndarray, close: np.ndarray | None, share: float
) -> np.ndarray:
    """An object's mask without the background it has just uncovered.

    Parameters
    ----------
    own : (h, w) ndarray of uint8, 0/1
        The object's flagged pixels.
    kept : (h, w) ndarray of uint8, 0/1
        Pixels that differ from the remembered background as well as from
        the previous frame.
    close : (k, k) ndarray of uint8 or None
        The object's closing kernel, applied to the kept part first.
    share : float
        The trimmed mask must keep at least this share of ``own``.

    Returns
    -------
    (h, w) ndarray of uint8, 0/1
        The largest connected part of ``own & kept`` (closed), or ``own``
        when that part is smaller than ``share`` of it.
    """
    cut = own & kept
    if close is not None:
        cut = cv2.morphologyEx(cut, cv2.MORPH_CLOSE, close)
    count, labels, stats = components_with_stats(cut)
    if count < 2:
        return own
    largest = 1 + int(np.argmax(stats[1:, cv2.CC_STAT_AREA]))
    cut = (labels == largest).astype(np.uint8)
    return cut if cut.sum() >= share * own.sum() else own
