"""Objects kept across frames: stable ids, persistence and held tracks.

1. **Track.** Tracks choose objects in order of age: each takes the free
   object that overlaps most its box moved on by the track's own image
   velocity (which includes the camera's motion; carried by this frame's
   fitted camera motion instead, as held masks are below, the boxes also
   keep false tracks on near surfaces alive: docs/detectors.md, "Tracks
   carried by this frame's camera motion"). Tracks keep a stable integer
   id; a part split from a confirmed track starts one that is confirmed at
   once.
2. **Persist.** An object is reported once its track has been seen on
   ``persistence`` frames; a track survives ``max_missed`` frames unseen,
   frames that cannot be judged included, but not a cut: the shot after it
   starts with no tracks (a box there overlaps one before it only by chance).
3. **Hold.** A mover does not vanish for one frame, though its detection
   may: the flow blurs, the image-change gate finds no change on a plain
   stretch, a limb stops as it turns. A track seen on ``hold_age`` frames
   that the detectors miss on a judged frame is still reported for
   ``hold_frames`` frames, its last mask carried by each frame's fitted
   camera motion (the plane's homography) and moved on by its own
   velocity less the camera's, and marked ``held`` (docs/detectors.md,
   "Held tracks"): where the camera turns back, its image velocity would
   put it twice the pan's speed from the mover. A frame that cannot be
   judged holds nothing.
4. **Expect** (optional, ``prior``). Where a confirmed track is predicted,
   the constraint ray needs less evidence to seed.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import cv2
import numpy as np

from motiondetect.detection.objects import MovingObject, TrackConfig
from motiondetect.detection.regions import true_pixels


def box_iou(a: tuple, b: tuple) -> float:
    """Intersection over union of two (x0, y0, x1, y1) boxes."""
    ix = max(0.0, min(a[2], b[2]) - max(a[0], b[0]))
    iy = max(0.0, min(a[3], b[3]) - max(a[1], b[1]))
    inter = ix * iy
    union = (a[2] - a[0]) * (a[3] - a[1]) + (b[2] - b[0]) * (b[3] - b[1]) - inter
    return inter / union if union > 0 else 0.0


def _shift(dx: float, dy: float) -> np.ndarray:
    return np.array([[1.0, 0.0, dx], [0.0, 1.0, dy], [0.0, 0.0, 1.0]])


def _own_velocity(
    velocity: tuple[float, float], box: tuple, camera: np.ndarray
) -> tuple[float, float]:
    """An object's image ``velocity`` less the camera's at the centre of its
    (x0, y0, x1, y1) ``box``, px/frame (``camera``: the plane's homography,
    current to previous pixels: it moved the plane's point at ``c`` from
    ``camera(c)``)."""
    x0, y0, x1, y1 = box
    centre = np.array([[[(x0 + x1) / 2, (y0 + y1) / 2]]], np.float64)
    (cx, cy), (wx, wy) = centre[0, 0], cv2.perspectiveTransform(centre, camera)[0, 0]
    return float(velocity[0] - (cx - wx)), float(velocity[1] - (cy - wy))


@dataclass
class _Track:
    id: int
    box: tuple[float, float, float, float]
    velocity: tuple[float, float]
    age: int = 1
    missed: int = 0
    mask: np.ndarray | None = None  # (h, w) bool: as last seen
    own: tuple[float, float] | None = None  # velocity less the camera's (None: not known)
    carried: np.ndarray = field(default_factory=lambda: np.eye(3))  # last seen -> this frame

    def carry(self, camera: np.ndarray | None) -> None:
        """Move ``carried`` on by one frame: by the camera's motion (``camera``,
        current to previous pixels) and the track's own, or where either is
        not known by its image velocity."""
        if camera is None or self.own is None:
            step = _shift(*self.velocity)
        else:
            step = _shift(*self.own) @ np.linalg.inv(camera)
        self.carried = step @ self.carried

    def predicted(self) -> tuple[float, float, float, float]:
        """The box moved on by its velocity over the frames since it was seen."""
        dx, dy = (v * (self.missed + 1) for v in self.velocity)
        x0, y0, x1, y1 = self.box
        return (x0 + dx, y0 + dy, x1 + dx, y1 + dy)


class Tracker:
    """Stable ids for objects across frames. State: the live tracks."""

    def __init__(self, config: TrackConfig | None = None) -> None:
        self.config = config or TrackConfig()
        self.reset()

    def reset(self) -> None:
        self._tracks: list[_Track] = []
        self._next_id = 1

    def coast(self, cut: bool = False) -> None:
        """A frame without judgement: tracks age toward their end, none is
        matched; a ``cut`` ends them all (ids stay unique within the input)."""
        if cut:
            self._tracks = []
            return
        for track in self._tracks:
            track.missed += 1
            track.carry(None)
        self._tracks = [t for t in self._tracks if t.missed <= self.config.max_missed]

    def predicted_mask(self, shape: tuple[int, int]) -> np.ndarray | None:
        """Where the confirmed tracks should be now: their boxes moved by their
        own velocity, (h, w) bool; None without any."""
        confirmed = self._confirmed()
        if not confirmed:
            return None
        mask = np.zeros(shape, bool)
        for track in confirmed:
            x0, y0, x1, y1 = track.predicted()
            rows = slice(max(int(y0), 0), max(int(np.ceil(y1)), 0))
            mask[rows, max(int(x0), 0) : max(int(np.ceil(x1)), 0)] = True
        return mask

    def predicted_pixels(self, shape: tuple[int, int], grow_px: int) -> np.ndarray | None:
        """Where the confirmed tracks' own pixels should be now: each last
        mask moved on by its velocity, dilated by ``grow_px``, (h, w) bool;
        None without any. Finer than :meth:`predicted_mask`'s boxes, which
        a large or oblique mover can fill to the frame's edges."""
        kept = [t for t in self._confirmed() if t.mask is not None and t.mask.shape == shape]
        masks = [_moved(t.mask, _shift(*(v * (t.missed + 1) for v in t.velocity))) for t in kept]
        if not masks:
            return None
        side = 2 * grow_px + 1
        union = np.logical_or.reduce(masks).view(np.uint8)
        return cv2.dilate(union, np.ones((side, side), np.uint8)) > 0

    def _confirmed(self) -> list[_Track]:
        """The tracks seen on ``persistence`` frames: those reported."""
        return [t for t in self._tracks if t.age >= self.config.persistence]

    def _assign(self, objects: list[MovingObject], predicted: list[tuple]) -> list[int | None]:
        """For each object, the index of the track it continues, or None.

        Established tracks choose first: in order of age (then of frames
        missed), each track takes the free object whose box overlaps its
        ``predicted`` box most, at least ``min_iou``. Where a mover's parts
        part and rejoin, a young track made of one part then cannot take
        the whole mover's id from the track that has followed it for long.
        """
        owner: list[int | None] = [None] * len(objects)
        order = sorted(
            range(len(self._tracks)), key=lambda i: (-self._tracks[i].age, self._tracks[i].missed)
        )
        for i in order:
            best, best_iou = None, self.config.min_iou
            for j, obj in enumerate(objects):
                if owner[j] is None:
                    iou = box_iou(predicted[i], obj.box)
                    if iou >= best_iou:
                        best, best_iou = j, iou
            if best is not None:
                owner[best] = i
        return owner

    def _born_age(self, obj: MovingObject, predicted: list[tuple]) -> int:
        """Age of the track a new object starts: 1, or ``persistence`` when
        it is a part split from a confirmed track: its box overlaps the
        track's ``predicted`` box by ``min_iou`` (the track, choosing before
        any new object starts, then took another part). Such a part has
        been seen, within the whole, so it is reported at once."""
        cfg = self.config
        for track, box in zip(self._tracks, predicted):
            if track.age >= cfg.persistence and box_iou(box, obj.box) >= cfg.min_iou:
                return cfg.persistence
        return 1

    def update(
        self, objects: list[MovingObject], camera: np.ndarray | None = None
    ) -> list[MovingObject]:
        """Match this frame's objects to tracks; return the confirmed ones with ids.

        ``camera``: the frame's fitted plane, (3, 3) homography from its
        pixels to the last frame's; it carries held tracks (None: they move
        by their image velocity)."""
        cfg = self.config
        predicted = [t.predicted() for t in self._tracks]
        owners = self._assign(objects, predicted)
        born = [self._born_age(o, predicted) if i is None else 0 for o, i in zip(objects, owners)]
        free = [i for i in range(len(self._tracks)) if i not in owners]
        confirmed = []
        for obj, best, age in zip(objects, owners, born):
            if best is None:
                track = _Track(self._next_id, obj.box, obj.velocity_px, age)
                self._next_id += 1
                self._tracks.append(track)
            else:
                track = self._tracks[best]
                track.box, track.velocity = obj.box, obj.velocity_px
                track.age, track.missed = track.age + 1, 0
            track.mask, track.carried = obj.mask, np.eye(3)
            track.own = None if camera is None else _own_velocity(obj.velocity_px, obj.box, camera)
            if track.age >= cfg.persistence:
                confirmed.append(
                    MovingObject(obj.mask, obj.box, obj.velocity_px, track.id, track.age)
                )
        matched = {t.id for t in self._tracks} - {self._tracks[i].id for i in free}
        for i in free:
            self._tracks[i].missed += 1
            self._tracks[i].carry(camera)
            held = _held(self._tracks[i], cfg)
            if held is not None:
                confirmed.append(held)
        self._tracks = [t for t in self._tracks if t.id in matched or t.missed <= cfg.max_missed]
        return confirmed


def _held(track: _Track, config: TrackConfig) -> MovingObject | None:
    """A missed track's last mask moved on by its velocity over the frames
    since it was seen, as a held object; None when it is too young, missed
    too long, or moved out of the frame."""
    established = max(config.hold_age, config.persistence)  # a held track is a confirmed one
    if track.mask is None or track.missed > config.hold_frames or track.age < established:
        return None
    mask = _moved(track.mask, track.carried)
    if not mask.any():
        return None
    ys, xs = true_pixels(mask)
    box = (int(xs.min()), int(ys.min()), int(xs.max()) + 1, int(ys.max()) + 1)
    return MovingObject(mask, box, track.velocity, track.id, track.age, held=True)


def _moved(mask: np.ndarray, motion: np.ndarray) -> np.ndarray:
    """``mask``, (h, w) bool, carried by ``motion``, (3, 3): its pixels to the new ones."""
    h, w = mask.shape
    if np.array_equal(motion[2], (0.0, 0.0, 1.0)):  # a shift, as by the image velocity
        moved = cv2.warpAffine(mask.view(np.uint8), motion[:2], (w, h), flags=cv2.INTER_NEAREST)
    else:
        moved = cv2.warpPerspective(mask.view(np.uint8), motion, (w, h), flags=cv2.INTER_NEAREST)
    return moved > 0
