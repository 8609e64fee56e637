"""An object's mask shaped: outlined by the image change, trimmed of
uncovered background, closed over its gaps and its holes filled, and its
rim judged by its look.

Pure functions on (h, w) uint8 0/1 masks at working size; the settings are
:class:`~.objects.TrackConfig`'s, passed in as values.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from motiondetect.detection.regions import components_with_stats, true_pixels

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
    look: np.ndarray | None = None,
    rim_px: int = 0,
) -> np.ndarray:
    """An object's mask outlined (with ``near``, :func:`outlined`), trimmed
    (with ``kept``, :func:`trimmed`), closed, its holes filled, and its rim
    ``rim_px`` wide judged by the grey frame ``look`` (:func:`rim_by_look`),
    (h, w) uint8 0/1; a step whose mask is None is skipped."""
    if near is not None:
        own = outlined(own, near, close)
    if kept is not None:
        own = trimmed(own, kept, close, trim_share)
    if close is not None:
        own = cv2.morphologyEx(own, cv2.MORPH_CLOSE, close)
    own = filled(own)
    return own if look is None else rim_by_look(own, look, rim_px)


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
        the previous frame (a plain interior put back, which cannot show
        the latter: from the remembered background alone).
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


#: Grey levels are binned by this shift (16 bins) for the appearance test of
#: :func:`interior_grown`: coarse enough that a few hundred pixels fill them.
_GREY_SHIFT = 4

#: Width of the unflagged ring round a flagged region whose grey levels are
#: taken as its background's (:func:`interior_grown`), work px: about one DIS
#: patch, past the smear.
RING_PX = 8


@dataclass(frozen=True)
class InteriorMotion:
    """What the frame's motion says about a pixel the support gate took out.

    Attributes
    ----------
    residual : (h, w, 2) ndarray of float32
        Velocity minus the plane's, work px/frame.
    tensor : (a, b, c) of (h, w) ndarray of float32
        :func:`~motiondetect.measurement.aperture.structure_tensor` over the
        flow's patch, grey levels^2/px^2.
    seen_level : float
        The support gate's threshold, grey levels: a change of this size
        would have been seen.
    """

    residual: np.ndarray
    tensor: tuple[np.ndarray, ...]
    seen_level: float

    def unseen_and_with(self, ys, xs, mover: np.ndarray) -> np.ndarray:
        """(N,) bool at pixels ``(ys, xs)``: moving by its residual, the pixel
        would have changed the image by less than ``seen_level`` (RMS of
        ``grad I . r`` over the patch), and its residual is nearer ``mover``
        ((N, 2), its region's) than the plane's (zero)."""
        r = self.residual[ys, xs]
        a, b, c = (t[ys, xs] for t in self.tensor)
        change = np.sqrt(r[:, 0] ** 2 * a + 2 * r[:, 0] * r[:, 1] * b + r[:, 1] ** 2 * c)
        nearer = np.hypot(*(r - mover).T) < np.hypot(*r.T)
        return (change < self.seen_level) & nearer


def interior_grown(
    supported: np.ndarray,
    flagged: np.ndarray,
    grey: np.ndarray | None,
    inset_px: int,
    motion: InteriorMotion | None = None,
) -> np.ndarray:
    """The supported pixels, and the flagged ones inside a plain mover.

    A plain surface that moves barely changes the image, so the support gate
    takes out a plain mover's interior, and no closing of a fixed size puts
    back that of one filling much of the view. A flagged pixel the gate took
    out joins when it lies ``inset_px`` inside its flagged region (DIS's
    smear is a band along its edge), inside the convex hull of the region's
    supported pixels, its grey level likelier among those than in the
    unflagged ring ``RING_PX`` wide round the region (16-bin histograms,
    smoothed), and, with ``motion``, :meth:`InteriorMotion.unseen_and_with`.

    Parameters
    ----------
    supported : (h, w) ndarray of uint8, 0/1
        Flagged pixels near an image change (a subset of ``flagged``).
    flagged : (h, w) ndarray of bool
        What the detectors flagged.
    grey : (h, w) ndarray of uint8 or None
        The working frame (None: ``supported`` is returned as it is).
    inset_px : int
        Work px (0: ``supported`` is returned as it is).
    motion : InteriorMotion, optional

    Returns
    -------
    (h, w) ndarray of uint8, 0/1
    """
    if inset_px <= 0 or grey is None or not supported.any():
        return supported
    x, y, w, h = cv2.boundingRect(flagged.view(np.uint8))  # with its ring: all that is read
    x0, y0 = max(x - RING_PX, 0), max(y - RING_PX, 0)
    box = np.s_[y0 : y + h + RING_PX, x0 : x + w + RING_PX]
    flag, own = flagged[box].view(np.uint8), supported[box] > 0
    inner = cv2.erode(flag, np.ones((2 * inset_px + 1,) * 2, np.uint8))
    inner[own] = 0  # nothing left without a gate: every flagged pixel is supported
    if not inner.any():
        return supported
    count, labels, stats = components_with_stats(flag)
    if count > np.iinfo(np.uint16).max:
        return supported
    labels = labels.astype(np.uint16, copy=False)
    bins = grey[box] >> _GREY_SHIFT
    likelier = _likelier_inside(labels, bins, flag, own, count)
    residual = None if motion is None else motion.residual[box]
    hull, mover = _hulls(labels, stats, own, likelier.any(axis=1), residual)
    ys, xs = true_pixels(inner & hull)
    keep = likelier[labels[ys, xs], bins[ys, xs]]
    if motion is not None:
        keep &= motion.unseen_and_with(ys + y0, xs + x0, mover[labels[ys, xs]])
    grown = supported.copy()
    grown[box][ys, xs] = keep
    return grown


def _likelier_inside(
    labels: np.ndarray, bins: np.ndarray, flag: np.ndarray, own: np.ndarray, count: int
) -> np.ndarray:
    """(count, bins) bool: each grey-level bin likelier among the region's
    supported pixels (``own``) than in the unflagged ring round it."""
    inside = _histograms(labels, bins, own, count)
    around = cv2.dilate(labels, np.ones((2 * RING_PX + 1,) * 2, np.uint8))
    ring = _histograms(around, bins, (flag == 0) & (around > 0), count)
    likelier = (_smoothed(inside) > _smoothed(ring)) & (inside.sum(axis=1) > 0)[:, None]
    likelier[0] = False
    return likelier


def _histograms(labels: np.ndarray, bins: np.ndarray, where: np.ndarray, count: int) -> np.ndarray:
    """(count, bins) pixel counts of each label's grey-level bins over ``where``."""
    size = 256 >> _GREY_SHIFT
    keys = (labels.astype(np.int32) * size + bins)[where]
    return np.bincount(keys, minlength=count * size).reshape(count, size).astype(np.float64)


def _smoothed(counts: np.ndarray, prior: float = 0.5) -> np.ndarray:
    """Each row of bin counts as probabilities: spread over neighbouring
    bins (1/4, 1/2, 1/4) and ``prior`` counts added to every bin."""
    spread = 0.5 * counts + prior
    spread[:, 1:] += 0.25 * counts[:, :-1]
    spread[:, :-1] += 0.25 * counts[:, 1:]
    spread[:, [0, -1]] += 0.25 * counts[:, [0, -1]]  # the edge bins keep their share
    return spread / spread.sum(axis=1, keepdims=True)


def _hulls(
    labels: np.ndarray,
    stats: np.ndarray,
    own: np.ndarray,
    chosen: np.ndarray,
    residual: np.ndarray | None,
) -> tuple[np.ndarray, np.ndarray]:
    """The convex hull of each ``chosen`` region's supported pixels (``own``),
    (h, w) uint8 0/1, and their median ``residual``, (count, 2) (zeros
    without one)."""
    hull, medians = np.zeros(labels.shape, np.uint8), np.zeros((len(stats), 2), np.float32)
    for label in np.flatnonzero(chosen):
        x, y, w, h = stats[label, :4]
        part = (labels[y : y + h, x : x + w] == label) & own[y : y + h, x : x + w]
        if residual is not None:
            medians[label] = np.median(residual[y : y + h, x : x + w][part], axis=0)
        outlines, _ = cv2.findContours(
            part.view(np.uint8), cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE, offset=(int(x), int(y))
        )
        if outlines:  # the hull of a point set is that of its parts' outlines
            cv2.fillConvexPoly(hull, cv2.convexHull(np.concatenate(outlines)), 1)
    return hull, medians


def rim_by_look(own: np.ndarray, grey: np.ndarray, rim_px: int) -> np.ndarray:
    """An object's mask without the rim pixels that look like what lies round it.

    The support gate keeps a flagged pixel within ``support_px`` of an image
    change, so wherever dense flow smears a mover's velocity into the
    background, a band about that wide survives along the mover's edge.
    Each pixel of the rim (within ``rim_px`` of the mask's edge) is given
    to the likelier of the two looks it lies between: the core's (the mask
    eroded by ``rim_px``) or the ring ``RING_PX`` wide round the mask
    (16-bin grey-level histograms spread over neighbouring bins, no
    count added, so that a tie, a look both share as much, keeps the pixel;
    equal priors).

    Parameters
    ----------
    own : (h, w) ndarray of uint8, 0/1
        The object's shaped mask.
    grey : (h, w) ndarray of uint8
        The working frame over the same pixels.
    rim_px : int
        Width of the rim, work px (0: ``own`` is returned as it is).

    Returns
    -------
    (h, w) ndarray of uint8, 0/1
        The parts of the re-judged mask that hold some of the core, holes
        filled; or ``own`` when there is no core or no ring, or when the
        cut leaves more such parts than ``own`` had (it went through the
        mover, not round it).
    """
    if rim_px <= 0:
        return own
    core = cv2.erode(own, np.ones((2 * rim_px + 1,) * 2, np.uint8))
    ring = cv2.dilate(own, np.ones((2 * RING_PX + 1,) * 2, np.uint8)) & (1 - own)
    if not core.any() or not ring.any():
        return own
    bins = grey >> _GREY_SHIFT
    looks = _smoothed(_histograms(ring + 2 * core, bins, (ring | core) > 0, 3)[1:], prior=0.0)
    kept = own.copy()
    kept[(own > core) & (looks[0, bins] > looks[1, bins])] = 0  # the rim, looking like the ring
    count, labels = cv2.connectedComponents(kept, connectivity=8)
    held = np.zeros(count, bool)
    held[labels[core > 0]] = True
    held[0] = False
    parts = np.count_nonzero(held)  # one part cannot be more than own had
    if parts > 1 and parts > cv2.connectedComponents(own, connectivity=8)[0] - 1:
        return own
    return filled(held[labels].astype(np.uint8))
