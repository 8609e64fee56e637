"""Objects, not fragments: flagged pixels grouped into movers.

1. **Group.** Flagged pixels are kept where the image itself changed (or
   next to such a change), so a mask does not spill over the background
   that dense flow smears the mover's velocity into. Pixels closer than
   ``gap_px`` belong to one object (one walker is one box, not three). Each
   object is then outlined more tightly by the change, its mask closed over
   its gaps and its holes filled.
2. **Track**, **persist**, **hold** and **expect**: :mod:`.tracking`, with
   the settings of both in :class:`TrackConfig`.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from motiondetect.config_checks import check_fields
from motiondetect.detection.regions import components_with_stats
from motiondetect.detection.shaping import InteriorMotion, interior_grown, shaped, within


@dataclass(frozen=True)
class TrackConfig:
    """Settings of grouping and tracking.

    Attributes
    ----------
    gap_px : int
        Flagged pixels this close (work px) join one object.
    min_area_share : float
        Smallest object, as a share of the frame's area.
    persistence : int
        Frames a track must be seen on before its objects are reported.
    max_missed : int
        Frames a track may go unseen before it ends.
    hold_frames : int
        Frames a confirmed track the detectors miss is still reported, at
        its mask moved on by its own velocity and marked held (0: never;
        :mod:`.tracking`).
    hold_age : int
        Frames a track must have been seen on before it is held.
    min_iou : float
        Smallest overlap (IoU) of a predicted track box and an object box
        that continues the track. False alarms wander from frame to frame
        more than movers do: 0.2 against 0.1 has fewer on every data set
        (DAVIS 0.29 to 0.26 a frame, UCSD 0.47 to 0.36, the fox 0.31 to
        0.29, the rigid renders 0.44 to 0.40) for 3 of 1438 DAVIS objects;
        0.3 loses more movers (docs/detectors.md).
    support_sigmas : float
        Flagged pixels are kept only within ``support_px`` of an image change
        above this many robust sigmas once the camera's motion is undone
        (0: off). Dense flow spreads a mover's velocity over its
        surroundings; the image there has not changed, so the mask stops
        at the mover.
    support_px : int
        Reach of that image change, work px, when flagged pixels are joined
        into objects. The change map is a 3x3 mean, so it already reaches a
        pixel past the change; 2 keeps a mover with a plain interior in one
        piece (0 splits and loses movers: DAVIS object recall 0.771 against
        0.807).
    outline_px : int
        Reach of the image change that draws each object's outline once it
        is grouped, work px (at most ``support_px``; equal: off). The reach
        that joins a mover also widens it by that much wherever the flow
        smears its velocity into the background, a band all round it. A
        cut that keeps less than ``shaping.MIN_KEPT`` of the object, or that
        leaves it in more parts once closed, is not taken
        (:func:`.shaping.outlined`). 1 raises cell F1 on every data set at
        equal or fewer false alarms (DAVIS 0.645 to 0.651, UCSD 0.228 to
        0.244; 0 gains more on DAVIS but loses object recall on the renders;
        docs/detectors.md).
    support_frames : int
        Slow movers: for flagged parts whose mean residual speed moves them
        at most ``support_px`` over ``support_frames - 1`` frames, the image
        change is also taken against the frame ``support_frames`` back,
        registered by the chained planes (:mod:`.change_history`; 0 or 1:
        one frame only). A grazing cow's plain body changes the image by
        less than the noise in one frame but not in three; a faster
        mover keeps the one-frame gate, which leaves out its trail.
    close_px : int
        Each object's mask is closed with a square this wide, work px (0:
        not closed): the support gate takes out a mover's plain interior,
        where the image does not change, and the closing puts it back.
    interior_px : int
        A plain mover's interior, which no closing of a fixed size puts back
        once the mover fills much of the view: a flagged pixel the support
        gate took out, at least this far inside its flagged region (work
        px; half a DIS patch, past the smear along its edge), inside the
        hull of the region's supported pixels, that looks like them rather
        than like the ring round the region, could not have shown a change,
        and moves with them rather than with the plane, is kept
        (:func:`.shaping.interior_grown`; 0: off), and neither the outline
        nor the trim, which need an image change, takes it out again (only
        a remembered background that matches it does). DAVIS cropped so that
        its movers fill half the view: cell F1 0.367 to 0.418; on the full
        frames DAVIS's false alarms fall by a quarter (docs/detectors.md,
        "A plain mover's interior").
    background_rate : float
        Trails: each frame's share in a background remembered at each place
        and registered by the planes (:class:`~.change_history.BackgroundMemory`;
        0: off). An object's pixels where the image matches that memory are
        background the mover has just uncovered (the ghost of the one-frame
        change), so its mask is trimmed to the rest, the largest part, when
        that keeps at least ``trim_share`` of it. The default, 1, remembers
        the background last seen at each place; a lower rate averages the
        looks (0.25: a little more precision on DAVIS, but object recall
        0.792 against 0.805; docs/detectors.md).
    background_frames : int
        Looks at a place, neither flagged nor changed, before its
        remembered background is trusted.
    trim_share : float
        Smallest share of an object's mask its trimmed mask may keep; an
        object the memory would cut more is kept whole (a mover the memory
        learned while it was missed, or a plane locked onto a mover).
    layer_sigmas : float
        Each object keeps only the pixels its own velocity predicts no worse
        than the plane does, within this many robust sigmas of the frame's
        plane difference (:mod:`.layers`; 0: off): the background that dense
        flow and the closing add around a mover. Only a cut that leaves one
        part of at least ``min_area_share`` of the frame, and at least half
        the object, is taken.
    prior : bool
        Inside a confirmed track's predicted box, a constraint-ray seed needs
        only the growth threshold (``grow_ratio`` of the tolerance): a
        mover that slows keeps being found where it is expected. Off by
        default: a false track (rigid parallax) feeds itself the same way
        (docs/detectors.md measures both).
    rigid_share : float
        A near rigid object is not a mover: an object is dropped when at
        least this share of its pixels carries a depth on its constraint
        ray from the last frame, and this share of those lies in front of
        the dominant plane where that depth predicts it
        (:mod:`.rigid_depth`; 0: off).
    overlay_frames : int
        Content fixed to the screen while the camera's motion changes the
        image under it, for this many frames, is an overlay (a burnt-in
        caption or logo) and is not flagged (:mod:`.screen_fixed`; 0: off).
    rim_look : bool
        Each object's rim, ``support_px`` wide (the band of smeared flow the
        support gate's reach lets in along a mover's edge), is kept only
        where its grey level is likelier among the object's core than in
        the ring round it (:func:`.shaping.rim_by_look`). Cell F1 over 4
        RANSAC seeds: DAVIS 0.672 to 0.687, UCSD 0.236 to 0.247, SBI 0.952
        to 0.963, the samples 0.896 to 0.901, at equal false alarms
        (docs/detectors.md, "An object's rim judged by its look").
    """

    gap_px: int = 10
    min_area_share: float = 0.0005
    persistence: int = 2
    max_missed: int = 5
    hold_frames: int = 1
    hold_age: int = 8
    min_iou: float = 0.2
    support_sigmas: float = 3.0
    support_px: int = 2
    outline_px: int = 1
    support_frames: int = 3
    close_px: int = 18
    interior_px: int = 4
    background_rate: float = 1.0
    background_frames: int = 2
    trim_share: float = 0.7
    layer_sigmas: float = 3.0
    prior: bool = False
    rigid_share: float = 0.5
    overlay_frames: int = 30
    rim_look: bool = True

    def __post_init__(self) -> None:
        check_fields(
            self,
            positive=("persistence",),
            non_negative=(
                "gap_px",
                "max_missed",
                "hold_frames",
                "hold_age",
                "support_sigmas",
                "support_px",
                "outline_px",
                "support_frames",
                "close_px",
                "interior_px",
                "background_frames",
                "layer_sigmas",
                "overlay_frames",
            ),
            shares=("min_area_share", "min_iou", "background_rate", "trim_share", "rigid_share"),
        )
        if self.outline_px > self.support_px:
            raise ValueError(
                f"outline_px must be at most support_px ({self.support_px}),"
                f" but got {self.outline_px}"
            )

    @property
    def rim_px(self) -> int:
        """Width of the rim :func:`.shaping.rim_by_look` judges, work px: the
        band the support gate's reach lets in (0: ``rim_look`` off)."""
        return self.support_px if self.rim_look else 0


@dataclass(frozen=True)
class MovingObject:
    """One grouped object in one frame (work pixels)."""

    mask: np.ndarray  # (h, w) bool
    box: tuple[float, float, float, float]  # x0, y0, x1, y1
    velocity_px: tuple[float, float]  # mean image velocity
    track: int = 0
    age: int = 1
    held: bool = False  # not found this frame: where its track predicts it


def group_objects(
    flagged: np.ndarray,
    velocity: np.ndarray,
    config: TrackConfig,
    changed: np.ndarray | None = None,
    background: np.ndarray | None = None,
    grey: np.ndarray | None = None,
    motion: InteriorMotion | None = None,
) -> list[MovingObject]:
    """Group flagged pixels into objects.

    Parameters
    ----------
    flagged : (h, w) ndarray of bool
    velocity : (h, w, 2) ndarray of float32
        Image velocity, work px/frame.
    config : TrackConfig
    changed : (h, w) ndarray of bool, optional
        Where the image changed once the camera's motion is undone; flagged
        pixels farther than ``support_px`` from it are dropped, and objects
        are outlined by it (:func:`_shaping_maps`).
    background : (h, w) ndarray of bool, optional
        Where the image differs from the remembered background (or it is
        unknown): the objects are trimmed by it (:func:`_shaping_maps`).
    grey, motion : optional
        The working frame and its motion, for :func:`.shaping.interior_grown` and the rim.

    Returns
    -------
    list of MovingObject, largest first, with holes filled."""
    h, w = flagged.shape
    gated = flagged.astype(np.uint8)
    gated = gated if changed is None else within(gated, changed, config.support_px)
    mask = interior_grown(gated, flagged, grey, config.interior_px, motion)  # gated: put back
    tight, kept = _shaping_maps(gated, mask, config, changed, background)
    kernel, close = _square(config.gap_px), _square(config.close_px)
    joined = mask if kernel is None else cv2.dilate(mask, kernel)
    count, labels, stats = components_with_stats(joined)
    pad = max(0 if c is None else c.shape[0] for c in (kernel, close))  # room inside the box
    min_area = config.min_area_share * h * w
    objects = []
    for label in range(1, count):
        x, y, bw, bh, joined_area = stats[label, :5]
        if joined_area < min_area:  # holds at least the object's own pixels
            continue
        x0, y0 = max(x - pad, 0), max(y - pad, 0)
        x1, y1 = min(x + bw + pad, w), min(y + bh + pad, h)
        own = (labels[y0:y1, x0:x1] == label).astype(np.uint8) & mask[y0:y1, x0:x1]
        if own.sum() < min_area:
            continue
        near, trim, look = (None if m is None else m[y0:y1, x0:x1] for m in (tight, kept, grey))
        own = shaped(own, near, trim, close, config.trim_share, look, config.rim_px)
        bx, by, bw, bh = cv2.boundingRect(own)
        full = np.zeros((h, w), bool)
        full[y0:y1, x0:x1] = own > 0
        v = velocity[y0:y1, x0:x1][own > 0].mean(axis=0)
        box = (int(x0 + bx), int(y0 + by), int(x0 + bx + bw), int(y0 + by + bh))
        objects.append(MovingObject(full, box, (float(v[0]), float(v[1]))))
    objects.sort(key=lambda o: -(o.box[2] - o.box[0]) * (o.box[3] - o.box[1]))
    return objects


def _square(px: int) -> np.ndarray | None:
    """An odd square kernel about ``px`` wide (uint8 ones), None for 0."""
    return np.ones((2 * (px // 2) + 1,) * 2, np.uint8) if px > 0 else None


def _shaping_maps(
    gated: np.ndarray,
    grown: np.ndarray,
    config: TrackConfig,
    changed: np.ndarray | None,
    background: np.ndarray | None,
) -> tuple[np.ndarray | None, np.ndarray | None]:
    """The outline's and the trim's maps, (h, w) uint8 0/1 each: the
    ``gated`` pixels within ``outline_px`` of ``changed``
    (:func:`.shaping.outlined`), and those within ``support_px`` of where the
    image differs from the remembered ``background`` and changed
    (:func:`.shaping.trimmed`). The interior that ``grown`` put back joins
    both, the trim's only within ``support_px`` of ``background``: a plain
    interior shows no change, so the change can neither outline it nor tell
    it from the background the mover uncovered; the memory still can. The
    outline's map is None with ``outline_px`` not below ``support_px``, the
    trim's without a ``background``; both without ``changed``."""
    if changed is None:
        return None, None
    interior = grown & (1 - gated) if grown is not gated else None
    tight = None
    if config.outline_px < config.support_px:
        tight = within(gated, changed, config.outline_px)
        tight = tight if interior is None else tight | interior
    if background is None:
        return tight, None
    kept = within(gated, background & changed, config.support_px)
    if interior is not None:
        kept |= within(interior, background, config.support_px)
    return tight, kept
