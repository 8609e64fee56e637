"""Annotated frames: boxes, flagged cells, observer class, the coarse field
and, outlined in grey, any caption or logo left out as fixed to the screen.

Kept apart from detection (DVR-Scan's overlays): one ``annotate`` call per
frame draws a :class:`~motiondetect.detection.detector.FrameResult` onto an image.
"""

from __future__ import annotations

import cv2
import numpy as np

from motiondetect.constraint_ray.hough import REGIONS, STILL, UNKNOWN
from motiondetect.detection.detector import FrameResult
from motiondetect.io.colours import CLASS_COLOURS, DETECTOR_COLOURS, LEGEND, OWN_MOTION
from motiondetect.io.source import fitted

_FONT = cv2.FONT_HERSHEY_SIMPLEX
_LEFT_OUT = (160, 160, 160)  # the outline of a caption or logo left out


#: Frames of a track's path drawn behind its box (:class:`Trails`): a second
#: at 30 frames/s.
TRAIL_FRAMES = 30

#: Seconds of a detection's own motion (its velocity against what lies behind
#: it) drawn as an arrow from its box's centre (:func:`draw_boxes`).
OWN_ARROW_S = 0.5

#: The overlay's text is readable from this width up (:func:`_text_size`): a
#: narrower input (QCIF, the UCSD clips) is enlarged to it for the annotated
#: video, within ``--video-size``.
MIN_WIDTH = 320


def annotated_size(width: int, height: int, long_side: int) -> tuple[int, int]:
    """The annotated video's (width, height): the input's, reduced to a long
    side of ``long_side`` or enlarged to :data:`MIN_WIDTH` (never beyond
    ``long_side``); even, as H.264's 4:2:0 needs."""
    limit = long_side / max(width, height)
    scale = min(1.0, limit)
    if width * scale < MIN_WIDTH:
        scale = min(MIN_WIDTH / width, limit)
    return (max(2, int(round(width * scale / 2)) * 2), max(2, int(round(height * scale / 2)) * 2))


def _box_colour(detection: dict) -> tuple[int, int, int]:
    """A detection's colour, by the detectors that found it (BGR)."""
    return DETECTOR_COLOURS.get(tuple(detection["detectors"]), (0, 255, 255))


class Trails:
    """Each track's recent path, drawn behind its box: the centres of its
    boxes over the last ``frames`` frames, joined, in the colour of its box.

    The one piece of the overlay with a memory (which way a mover went), so
    it lives in this small object, fed the frames in order; a track unseen
    for ``frames`` frames is forgotten.
    """

    def __init__(self, frames: int = TRAIL_FRAMES) -> None:
        self.frames = frames
        self._paths: dict[int, list[tuple[int, tuple[float, float]]]] = {}

    def update(self, index: int, detections: list[dict]) -> None:
        """Take frame ``index``'s detections (frames.jsonl records, input px)."""
        for det in detections:
            if "track" in det:
                x, y, w, h = det["bbox"]
                self._paths.setdefault(det["track"], []).append((index, (x + w / 2, y + h / 2)))
        for track, path in list(self._paths.items()):
            path[:] = [p for p in path if p[0] > index - self.frames]
            if not path:
                del self._paths[track]

    def draw(self, out: np.ndarray, detections: list[dict], sx: float, sy: float) -> None:
        """The paths of the tracks in ``detections``, in place, scaled by ``sx, sy``."""
        for det in detections:
            path = self._paths.get(det.get("track"), [])
            if len(path) < 2:
                continue
            points = np.array([(cx * sx, cy * sy) for _, (cx, cy) in path], np.int32)
            colour = _box_colour(det)
            cv2.polylines(out, [points], False, colour, 2, cv2.LINE_AA)


def annotate(
    image: np.ndarray,
    result: FrameResult,
    size: tuple[int, int],
    trails: Trails | None = None,
    input_size: tuple[int, int] | None = None,
) -> np.ndarray:
    """Draw ``result`` on a copy of ``image`` resized to ``size`` (width, height);
    with ``trails``, fed this frame first, each track's recent path too.
    ``input_size``: the input's (width, height), when ``image`` is not at it
    (already reduced: :meth:`~motiondetect.io.source.SourceFrame.picture`)."""
    out = fitted(image, size)
    out = out.copy() if out is image else out
    w0, h0 = input_size or (image.shape[1], image.shape[0])
    sx, sy = size[0] / w0, size[1] / h0
    if result.flagged_pixels.any():
        flagged = result.input_mask(*size)
        tint = out.copy()
        tint[flagged > 0] = (0, 0, 255)
        out = cv2.addWeighted(tint, 0.35, out, 0.65, 0)
    overlay = _overlay_mask(out, result.overlay)
    _draw_overlay(out, overlay)
    detections = [r.to_json() for r in result.regions]
    if trails is not None:
        trails.update(result.index, detections)
        trails.draw(out, detections, sx, sy)
    draw_boxes(out, detections, sx, sy)
    _draw_coarse(out, result)
    if not result.reliable:
        cv2.rectangle(out, (0, 0), (out.shape[1] - 1, out.shape[0] - 1), (0, 200, 255), 4)
    _draw_label(out, result)
    _draw_legend(out, overlay)
    return out


def draw_boxes(
    out: np.ndarray, detections: list[dict], sx: float = 1.0, sy: float = 1.0
) -> np.ndarray:
    """Draw detection records (as in frames.jsonl) on ``out`` in place: a box
    coloured by detector, the track id and the score (a held track's box
    thin, labelled "held"), and from its centre a cyan arrow as long as its
    own motion over :data:`OWN_ARROW_S` (its velocity against what lies
    behind it, the camera's taken out); ``sx, sy`` scale the input-pixel
    boxes to ``out``."""
    for det in detections:
        x, y, w, h = det["bbox"]
        colour = _box_colour(det)
        p0 = (int(x * sx), int(y * sy))
        p1 = (int((x + w) * sx) - 1, int((y + h) * sy) - 1)
        cv2.rectangle(out, p0, p1, colour, 1 if det.get("held") else 2)
        own = det.get("own_velocity_px_s")
        if own is not None:
            cx, cy = (x + w / 2) * sx, (y + h / 2) * sy
            tip = (cx + own[0] * OWN_ARROW_S * sx, cy + own[1] * OWN_ARROW_S * sy)
            if np.hypot(tip[0] - cx, tip[1] - cy) >= 3:
                start, end = (int(round(cx)), int(round(cy))), tuple(int(round(v)) for v in tip)
                cv2.arrowedLine(out, start, end, (0, 0, 0), 3, tipLength=0.25)
                cv2.arrowedLine(out, start, end, OWN_MOTION, 1, tipLength=0.25)
        label = f"#{det['track']} " if "track" in det else ""
        score = "held" if det.get("held") else f"{det['score']:.2f}"
        _text(out, f"{label}{score}", (p0[0] + 2, p0[1] + 14), colour)
    return out


def _overlay_mask(out: np.ndarray, overlay: np.ndarray | None) -> np.ndarray | None:
    """Content fixed to the screen that was left out (a burnt-in caption or
    logo; ``FrameResult.overlay``, work pixels) at ``out``'s size, grown by
    2 px, (h, w) uint8 0/1; None when there is none."""
    if overlay is None:
        return None
    h, w = out.shape[:2]
    mask = cv2.resize(overlay.view(np.uint8), (w, h), interpolation=cv2.INTER_NEAREST)
    return cv2.dilate(mask, np.ones((5, 5), np.uint8))


def _draw_overlay(out: np.ndarray, mask: np.ndarray | None) -> None:
    """Outline, in grey, the overlay left out (:func:`_overlay_mask`)."""
    if mask is None:
        return
    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    cv2.drawContours(out, contours, -1, _LEFT_OUT, 1, cv2.LINE_AA)


def _text_size(out: np.ndarray) -> tuple[float, int]:
    """Font scale and stroke of the overlay's text, readable at any frame
    width (320 px and up)."""
    scale = max(0.4, out.shape[1] / 800)
    return scale, max(1, round(scale * 1.5))


def _text(out: np.ndarray, text: str, origin: tuple[int, int], colour) -> None:
    """Outlined, at :func:`_text_size`."""
    scale, thick = _text_size(out)
    x, y = origin
    for dx, dy in ((-1, -1), (1, -1), (-1, 1), (1, 1)):  # an outline of the same glyph widths
        cv2.putText(out, text, (x + dx, y + dy), _FONT, scale, (0, 0, 0), thick, cv2.LINE_AA)
    cv2.putText(out, text, origin, _FONT, scale, colour, thick, cv2.LINE_AA)


def _draw_legend(out: np.ndarray, overlay: np.ndarray | None = None) -> None:
    """Box colours by detector, on one line at the bottom left (stacked, the
    three entries covered a third of a small frame's height); at the bottom
    right, or under the label, when a caption or logo left out as fixed to
    the screen (``overlay``, :func:`_overlay_mask`) lies there."""
    scale, thick = _text_size(out)
    swatch = int(round(10 * scale / 0.4))
    widths = [cv2.getTextSize(name, _FONT, scale, thick)[0][0] for name, _ in LEGEND]
    width = sum(widths) + len(LEGEND) * (swatch + 4 + 3 * swatch // 2)
    x, y = _legend_origin(out.shape, width, swatch, overlay)
    for name, colour in LEGEND:
        cv2.rectangle(out, (x, y - swatch), (x + swatch, y), colour, -1)
        x += swatch + 4
        _text(out, name, (x, y), colour)
        x += cv2.getTextSize(name, _FONT, scale, thick)[0][0] + 3 * swatch // 2


def _legend_origin(shape, width: int, height: int, overlay: np.ndarray | None) -> tuple[int, int]:
    """The legend's bottom-left corner: the frame's bottom left, else its
    bottom right, else under the label, the first that leaves ``overlay`` clear."""
    h, w = shape[:2]
    places = [(6, h - 6), (max(6, w - 6 - width), h - 6), (6, 26 + height)]
    for x, y in places:
        if overlay is None or not overlay[max(0, y - height) : y + 1, x : x + width].any():
            return x, y
    return places[0]


def _draw_coarse(out: np.ndarray, result: FrameResult) -> None:
    """Figure 5, live: the 4x4 coarse field as arrows."""
    coarse = result.coarse
    if coarse is None:
        return
    h, w = out.shape[:2]
    cell_w, cell_h = w / REGIONS, h / REGIONS
    length = 0.35 * min(cell_w, cell_h)
    for r in range(REGIONS):
        for c in range(REGIONS):
            centre = (int((c + 0.5) * cell_w), int((r + 0.5) * cell_h))
            code = int(coarse.direction_index[r, c])
            if code == UNKNOWN:
                continue
            if code == STILL:
                cv2.circle(out, centre, 3, (255, 255, 255), -1)
                continue
            angle = code * np.pi / 4
            tip = (int(centre[0] + length * np.cos(angle)), int(centre[1] + length * np.sin(angle)))
            cv2.arrowedLine(out, centre, tip, (0, 0, 0), 3, cv2.LINE_AA, tipLength=0.3)
            cv2.arrowedLine(out, centre, tip, (255, 255, 255), 1, cv2.LINE_AA, tipLength=0.3)


def _observer_label(result: FrameResult) -> tuple[str, int]:
    if result.observer is not None:
        obs = result.observer
        return f"{obs.name} {obs.confidence:.2f}", obs.class_id
    if result.camera is not None:
        cam = result.camera
        if not result.reliable:
            return f"UNRELIABLE: {result.reason}", -1
        return f"{cam.label} {cam.inlier_share:.2f}", cam.class_id
    return ("warm-up" if result.warm_up else "-"), -1


def _draw_label(out: np.ndarray, result: FrameResult) -> None:
    name, class_id = _observer_label(result)
    text = f"#{result.index} {result.time_s:.2f}s {name}"
    if result.held_from is not None:
        text += f" ({'repeats' if result.repeat else 'held from'} #{result.held_from})"
    colour = CLASS_COLOURS.get(class_id, (255, 255, 255))
    cv2.circle(out, (out.shape[1] - 10, 10), 6, colour, -1)
    white = (255, 255, 255) if result.reliable else (0, 200, 255)
    _text(out, text, (4, 16), white)
