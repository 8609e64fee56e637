"""2-D image velocity: the full flow the paper's section 3 is stated for.

Nelson measured only normal flow because full flow was too expensive in
1991 (section 3.2). Here each frame gets a dense velocity field from
OpenCV's DIS optical flow (Kroeger et al., ECCV 2016), coarse to fine, so
large motions are measured too. docs/stages.md compares it with the
least-squares velocity from the normal-flow stages (NOTES section 6).

:class:`DenseFlow` holds the one-frame delay, like the normal-flow
pipeline; the field is given at the *current* frame's pixels, so masks
built from it line up with the frame being reported. On a steady fast pan
DIS starts its search from the last field instead of from rest
(``DenseFlowConfig.start_speed_px``), which carries it past the reach of
its search, :data:`~.flow_config.DIS_REACH_PX`.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import cv2
import numpy as np

from motiondetect.measurement import stages
from motiondetect.measurement.aperture import structure_tensor
from motiondetect.measurement.flow_config import DIS_REACH_PX, PRESETS, DenseFlowConfig
from motiondetect.measurement.normal_flow import GridGeometry
from motiondetect.measurement.picture import Picture, PictureArea
from motiondetect.measurement.repeats import REPEAT, Repeat, RepeatedFrames

_REMAP_COLUMNS = 4096  # points per row when remapping a list of points


@dataclass(frozen=True)
class VelocityField:
    """One frame's dense image velocity.

    Attributes
    ----------
    velocity_px : (h, w, 2) ndarray of float32
        (vx, vy) of each current-frame pixel, work px/frame: the pixel was at
        ``p - velocity`` in the previous frame.
    grey : (h, w) ndarray of uint8
        The current frame at working size.
    previous_grey : (h, w) ndarray of uint8
    geometry : GridGeometry
        Input and working sizes; the 64x64 grid maps onto both.
    pixel_grid : (h, w, 2) ndarray of float32
        (x, y) of every work pixel (made once per geometry, shared).
    camera : CameraFit, optional
        The observer motion fitted to this field, attached once per frame
        so that every detector shares it.
    tracked : (h, w) ndarray of bool, optional
        Where the confirmed tracks are predicted to be in this frame.
    patch_px : int
        Side of the patch each velocity is measured over, work px (DIS's
        patch at its finest pyramid level, scaled to the working size).
    forward_px : (h, w, 2) ndarray of float32, optional
        The flow measured the other way, from the previous frame to this
        one, at previous-frame pixels, for :meth:`confirmed_at`; None: no
        check.
    picture : Picture, optional
        The part of the frame measured, when it has black bars
        (:mod:`~motiondetect.measurement.picture`); ``geometry.input_size``
        is then the picture's size. None: the whole frame.
    interval_s : float, optional
        Seconds between the two frames measured, attached with the camera
        when the frames' times are known; None: one frame step.
    since : int, optional
        Index of the frame the velocities were measured from (the last
        frame measured that differed), attached with the camera; None: the
        frame before. Known ego-motion spans the same frames.
    searched_px : float, optional
        How far DIS searched, work px/frame: the median distance of the
        velocities from the last field it started from on a steady fast pan
        (``DenseFlowConfig.start_speed_px``); None: it started from rest, and
        the velocities' speed is that distance (``FitConfig.max_speed_px``).
    ahead : object, optional
        What the observer-motion fit reads of this field alone, computed
        before the frame is judged, on the measuring thread when it has time
        (:func:`motiondetect.constraint_ray.ahead.fitted_ahead`); None: it is
        computed when the frame is judged.
    """

    velocity_px: np.ndarray
    grey: np.ndarray
    previous_grey: np.ndarray
    geometry: GridGeometry
    pixel_grid: np.ndarray
    camera: Any = None
    tracked: np.ndarray | None = None
    patch_px: int = 8
    forward_px: np.ndarray | None = None
    picture: Picture | None = None
    interval_s: float | None = None
    since: int | None = None
    searched_px: float | None = None
    ahead: Any = None

    @property
    def shape(self) -> tuple[int, int]:
        return self.grey.shape

    def judged(
        self,
        camera: Any,
        tracked: np.ndarray | None = None,
        interval_s: float | None = None,
        since: int | None = None,
    ) -> VelocityField:
        """This field with its observer motion (track prior, interval, first
        frame) attached, keeping every map already computed from the
        velocity and the frame (the cached properties, ``source_px`` and
        ``structure``): they depend on none of them."""
        return self.replaced(camera=camera, tracked=tracked, interval_s=interval_s, since=since)

    def replaced(self, **changes: Any) -> VelocityField:
        """:func:`dataclasses.replace`, keeping the maps already computed (the
        cached properties): only for ``changes`` they do not depend on, which
        are those outside the measurement (``camera``, ``tracked``,
        ``interval_s``, ``since``, ``ahead``)."""
        out = dataclasses.replace(self, **changes)
        for name, value in self.__dict__.items():
            out.__dict__.setdefault(name, value)  # fields are set; only caches are missing
        return out

    def prepared(self) -> VelocityField:
        """This field, with the maps every judgement reads (``source_px``,
        ``structure``) computed now: the detector makes them with the
        measurement, on the measuring thread when it runs ahead, so that the
        judging thread does not."""
        for name in ("source_px", "structure"):
            getattr(self, name)
        return self

    @cached_property
    def source_px(self) -> np.ndarray:
        """(h, w, 2) float32: where each pixel was in the previous frame,
        ``pixel_grid - velocity_px`` (computed once, shared: do not modify)."""
        return self.pixel_grid - self.velocity_px

    def confirmed_at(self, ys: np.ndarray, xs: np.ndarray) -> np.ndarray:
        """(N,) bool: whether the flow measured the other way confirms the
        velocity at each pixel (:func:`confirmed_both_ways`); all True
        without ``forward_px``."""
        if self.forward_px is None:
            return np.ones(len(ys), bool)
        return confirmed_both_ways(
            self.velocity_px[ys, xs], self.forward_px, self.source_px[ys, xs]
        )

    @cached_property
    def structure(self) -> tuple[np.ndarray, ...]:
        """:func:`~motiondetect.measurement.aperture.structure_tensor` of the
        current frame over the flow's patch (computed once, shared)."""
        return structure_tensor(self.grey, self.patch_px | 1)


def vector_length(vectors: np.ndarray) -> np.ndarray:
    """Length of each 2-D vector, (...) float32 from (..., 2).

    A contiguous float32 field is read as complex numbers, whose absolute
    value is the length: about 7x faster than ``np.hypot`` on the strided
    components and 2.5x faster than splitting it for ``cv2.magnitude``.
    """
    if vectors.dtype == np.float32 and vectors.flags.c_contiguous and vectors.ndim:
        return np.abs(vectors.view(np.complex64))[..., 0]
    return np.hypot(vectors[..., 0], vectors[..., 1]).astype(np.float32)


def confirmed_both_ways(
    velocity: np.ndarray, forward: np.ndarray, source: np.ndarray
) -> np.ndarray:
    """Which velocities the flow measured the other way confirms.

    The forward-backward check of Sundaram, Brox and Keutzer (ECCV 2010):
    a velocity ``v`` at ``p`` is confirmed when the forward flow ``w`` at
    ``p - v`` in the previous frame brings the point back, ``|w - v|^2 <=
    0.01 (|w|^2 + |v|^2) + 0.5`` (their constants). Occlusions, content
    entering the view and matches to the wrong repeat of a periodic texture
    fail it; a mover tracked both ways passes.

    Parameters
    ----------
    velocity : (..., 2) ndarray of float32
        Work px/frame of the points tested (current-frame pixels).
    forward : (h, w, 2) ndarray of float32
        Flow from the previous frame to this one, at previous-frame pixels.
    source : (..., 2) ndarray of float32
        ``p - velocity``, where each point was (:attr:`VelocityField.source_px`).

    Returns
    -------
    (...) ndarray of bool
    """
    shape = velocity.shape[:-1]
    velocity = velocity.reshape(-1, 2)
    n = len(velocity)
    if n == 0:
        return np.zeros(shape, bool)
    cols = min(n, _REMAP_COLUMNS)  # remap's map holds under 2^15 columns and rows
    points = np.zeros((-(-n // cols) * cols, 2), np.float32)
    points[:n] = source.reshape(-1, 2)
    back = cv2.remap(
        forward, points.reshape(-1, cols, 2), None, cv2.INTER_LINEAR,
        borderMode=cv2.BORDER_REPLICATE,
    ).reshape(-1, 2)[:n]  # fmt: skip
    bx, by = back.T  # planes: NumPy sums over a last axis of 2 slowly
    vx, vy = velocity.T
    gx, gy = bx - vx, by - vy
    gap2 = gx * gx + gy * gy
    allowed = 0.01 * ((bx * bx + by * by) + (vx * vx + vy * vy)) + 0.5
    return (gap2 <= allowed).reshape(shape)


def pixel_grid(width: int, height: int) -> np.ndarray:
    """(height, width, 2) float32: the (x, y) of every pixel."""
    ys, xs = np.mgrid[0:height, 0:width].astype(np.float32)
    return np.stack([xs, ys], axis=-1)


def working_grey(frame: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """An input frame as 8-bit grey at ``size`` (width, height), area-reduced.

    Parameters
    ----------
    frame : (H, W) or (H, W, C) ndarray of uint8 or uint16
    size : (width, height)
        At most the frame's own size.

    Returns
    -------
    (height, width) ndarray of uint8
    """
    grey = stages.to_grey(frame)
    if grey.dtype != np.uint8:
        grey = np.clip(grey, 0, 255).astype(np.uint8)
    if (grey.shape[1], grey.shape[0]) != size:
        grey = cv2.resize(grey, size, interpolation=cv2.INTER_AREA)
    return np.ascontiguousarray(grey)  # a grey picture cropped from its bars is a view


class DenseFlow:
    """Frames in, dense velocity fields out; the first frame gives ``None``."""

    def __init__(self, config: DenseFlowConfig | None = None) -> None:
        self.config = config or DenseFlowConfig()
        # OpenCV's DIS keeps an initial flow it was given for its later calls,
        # so the searches from the last field have DIS objects of their own
        # and those from rest stay from rest.
        self._dis, self._started_dis = _main_dis(self.config), _main_dis(self.config)
        # The finest pyramid level DIS measures on is 2^finest_scale coarser.
        self._patch_px = self._dis.getPatchSize() * 2 ** self._dis.getFinestScale()
        check = self.config.check_preset
        self._check = self._started_check = None
        if check != "off":
            self._check = cv2.DISOpticalFlow_create(PRESETS[check])
            self._started_check = cv2.DISOpticalFlow_create(PRESETS[check])
        self._previous: np.ndarray | None = None
        self._pictures = PictureArea(self.config.bar_limit) if self.config.bar_limit > 0 else None
        self._picture: Picture | None = None
        self._repeats = RepeatedFrames(self.config.repeat_level)
        self._geometry: GridGeometry | None = None
        self._grid: np.ndarray | None = None
        self._start: np.ndarray | None = None
        self._last_median: np.ndarray | None = None

    def reset(self) -> None:
        """Forget the delayed frame, the picture area and the usual difference between frames."""
        self._forget_frames()
        self._repeats.reset()
        if self._pictures is not None:
            self._pictures.reset()

    def geometry_for(self, width: int, height: int) -> GridGeometry:
        work = stages.working_size(width, height, min(self.config.work_size, max(width, height)))
        return GridGeometry((width, height), work)

    def process(self, frame: np.ndarray) -> VelocityField | Repeat | None:
        """Measure the velocity between the previous frame and ``frame``.

        Only the picture inside black bars is measured, when the frame has
        them (:attr:`VelocityField.picture`; ``bar_limit`` 0: the whole
        frame); a change of picture starts afresh, like a change of size.
        A frame that repeats the last one is not measured: it gives
        :data:`~motiondetect.measurement.repeats.REPEAT`, and the next frame
        is measured against the last that differed.

        Parameters
        ----------
        frame : (H, W) or (H, W, C) ndarray of uint8 or uint16

        Returns
        -------
        VelocityField, REPEAT or None
            None for the first frame (of this size and picture).
        """
        stages.validate_frame(frame)
        picture = None if self._pictures is None else self._pictures.update(frame)
        if picture != self._picture:
            self._picture = picture
            self._forget_frames()
        if picture is not None:
            frame = picture.crop(frame)
        h, w = frame.shape[:2]
        if self._geometry is None or self._geometry.input_size != (w, h):
            self._geometry = self.geometry_for(w, h)
            self._grid = pixel_grid(*self._geometry.work_size)
            self._forget_frames()
        grey = working_grey(frame, self._geometry.work_size)
        if self._previous is not None and self._repeats.repeats(grey, self._previous):
            return REPEAT
        previous, self._previous = self._previous, grey
        if previous is None:
            return None
        velocity, forward, searched = self._measured(grey, previous)
        return VelocityField(
            velocity, grey, previous, self._geometry, self._grid,
            patch_px=self._patch_px, forward_px=forward, picture=picture, searched_px=searched,
        )  # fmt: skip

    def _forget_frames(self) -> None:
        self._previous = self._start = self._last_median = None

    def _measured(self, grey: np.ndarray, previous: np.ndarray) -> tuple:
        """(velocity, the flow the other way or None, how far DIS searched
        from its start or None when it started from rest): started from the
        last field on a steady fast pan, from rest when the search from it
        went beyond DIS's reach (the pan broke off)."""
        # Flow from the current frame back to the previous one, at current pixels.
        start, searched = self._start, None
        if start is not None:
            velocity = -self._started_dis.calc(grey, previous, np.ascontiguousarray(-start))
            searched = float(np.median(vector_length(_lattice(velocity - start))))
            if searched > DIS_REACH_PX:
                start, searched = None, None
        if start is None:
            velocity = -self._dis.calc(grey, previous, None)
        forward = None
        if self._check is not None:  # DIS writes into the flow it starts from: a copy
            check, init = (
                (self._check, None) if start is None else (self._started_check, start.copy())
            )
            forward = check.calc(previous, grey, init)
        self._start = self._next_start(velocity)
        return velocity, forward, searched

    def _next_start(self, velocity: np.ndarray) -> np.ndarray | None:
        """The next search's start: this field, when its median speed passes
        ``start_speed_px`` and its median velocity changed by less than half
        its length since the last field (a steady pan, not a jerk)."""
        sampled = _lattice(velocity)
        median, last = np.median(sampled, axis=0), self._last_median
        self._last_median = median
        if float(np.median(vector_length(sampled))) <= self.config.start_speed_px or last is None:
            return None
        return velocity if np.hypot(*(median - last)) < 0.5 * np.hypot(*median) else None


def _main_dis(config: DenseFlowConfig):
    """The main flow's DIS, set up by ``config``."""
    dis = cv2.DISOpticalFlow_create(PRESETS[config.preset])
    if config.descent_iterations is not None:
        dis.setGradientDescentIterations(config.descent_iterations)
    dis.setPatchStride(config.patch_stride)
    if config.refinement_iterations is not None:
        dis.setVariationalRefinementIterations(config.refinement_iterations)
    return dis


def _lattice(vectors: np.ndarray) -> np.ndarray:
    """(N, 2): ``vectors`` ((h, w, 2)) on an 8-px lattice, for their medians."""
    return vectors[4::8, 4::8].reshape(-1, 2)
