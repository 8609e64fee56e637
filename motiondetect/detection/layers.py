"""Each object's pixels assigned to the motion that predicts them better: its own or the plane's.

Dense flow smears a mover's velocity about a patch's width into the
background around it, and the closing that restores a mover's plain
interior also fills the background in its concavities (between the legs,
under an arm). That background moves with the rigid world: the previous
frame warped by the fitted plane predicts it, while the previous frame
moved by the object's own velocity does not. This is the assignment step of
layered motion models (Wang and Adelson 1994): each pixel of an object goes
to whichever of the two motion layers predicts its grey level better, and a
pixel the plane predicts better by more than the noise leaves the object.
Where neither predicts better (a plain surface, a textureless wall), the
pixel stays as grouped: the image cannot tell.
"""

from __future__ import annotations

import dataclasses

import cv2
import numpy as np

from motiondetect.constraint_ray.camera_fit import CameraFit
from motiondetect.detection.objects import MovingObject
from motiondetect.detection.regions import components_with_stats
from motiondetect.detection.shaping import MIN_KEPT, filled
from motiondetect.measurement.dense_flow import VelocityField

#: Side of the window the two prediction errors are averaged over, work px
#: (about the flow's patch at the working size, like ``evidence_box``).
ERROR_BOX = 5


def plane_predicts_better(
    obj: MovingObject, field: VelocityField, plane_difference: np.ndarray, margin: float
) -> np.ndarray:
    """Pixels of the object's box that the plane predicts better than the
    object's own velocity, (bh, bw) bool.

    Parameters
    ----------
    obj : MovingObject
        Its ``box`` (x0, y0, x1, y1) and ``velocity_px``, the mean image
        velocity of its pixels, work px/frame.
    field : VelocityField
        The frame's greys, current and previous, at working size.
    plane_difference : (h, w) ndarray of uint8
        ``|grey - previous grey warped by the plane|``, grey levels: the
        plane's prediction error.
    margin : float
        Grey levels by which the object's mean prediction error over an
        ``ERROR_BOX`` window must exceed the plane's.
    """
    x0, y0, x1, y1 = obj.box
    vx, vy = obj.velocity_px
    # Inverse map: box pixel (x, y) reads the previous frame at (x0 + x - vx, y0 + y - vy).
    shift = np.float32([[1, 0, x0 - vx], [0, 1, y0 - vy]])
    moved = cv2.warpAffine(
        field.previous_grey, shift, (x1 - x0, y1 - y0),
        flags=cv2.WARP_INVERSE_MAP | cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE,
    )  # fmt: skip
    own_error = cv2.absdiff(moved, field.grey[y0:y1, x0:x1])
    window = (ERROR_BOX, ERROR_BOX)
    own_error = cv2.blur(own_error.astype(np.float32), window)
    plane_error = cv2.blur(plane_difference[y0:y1, x0:x1].astype(np.float32), window)
    return own_error > plane_error + margin


def assigned(
    obj: MovingObject,
    field: VelocityField,
    plane_difference: np.ndarray,
    margin: float,
    min_area: float,
) -> MovingObject:
    """The object without the pixels the plane predicts better
    (:func:`plane_predicts_better`), its holes filled.

    Only a clean cut is taken: what remains must be one part of at least
    ``min_area`` work px (parts smaller than that are crumbs and go too), and
    at least ``MIN_KEPT`` of the object. A cut that leaves several such
    parts (two movers grouped as one, a limb joined by a smeared band) or
    that would take more leaves the object as it was.
    """
    x0, y0, x1, y1 = obj.box
    if x1 - x0 < ERROR_BOX or y1 - y0 < ERROR_BOX:
        return obj
    own = obj.mask[y0:y1, x0:x1]
    background = plane_predicts_better(obj, field, plane_difference, margin) & own
    if not background.any():
        return obj
    kept = (own & ~background).view(np.uint8)
    _, labels, stats = components_with_stats(kept)
    parts = np.flatnonzero(stats[1:, cv2.CC_STAT_AREA] >= min_area) + 1
    if len(parts) != 1:
        return obj
    kept = filled((labels == parts[0]).astype(np.uint8))
    if kept.sum() < MIN_KEPT * own.sum():
        return obj
    bx, by, bw, bh = cv2.boundingRect(kept)
    mask = np.zeros_like(obj.mask)
    mask[y0:y1, x0:x1] = kept > 0
    box = (x0 + bx, y0 + by, x0 + bx + bw, y0 + by + bh)
    return dataclasses.replace(obj, mask=mask, box=box)


def assigned_objects(
    objects: list[MovingObject], field: VelocityField, fit: CameraFit, sigmas: float,
    min_area_share: float,
) -> list[MovingObject]:  # fmt: skip
    """Each object :func:`assigned`, with a margin of ``sigmas`` robust sigmas
    of the frame's plane difference and parts of at least ``min_area_share``
    of the frame; the objects unchanged when ``sigmas`` is 0 or the frame has
    no plane difference."""
    if sigmas <= 0 or fit.plane_difference is None or not objects:
        return objects
    margin = sigmas * fit.difference_sigma()
    min_area = min_area_share * fit.plane_difference.size
    return [assigned(o, field, fit.plane_difference, margin, min_area) for o in objects]
