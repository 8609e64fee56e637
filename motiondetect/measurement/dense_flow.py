"""2-D image velocity: the full flow the paper's section 3 is stated for.

Nelson measured only normal flow because full flow was too expensive in
1991 (section 3.2). Here each frame gets a dense velocity field from
OpenCV's DIS optical flow (Kroeger et al., ECCV 2016), coarse to fine, so
large motions are measured too. docs/stages.md compares it with the
least-squares velocity from the normal-flow stages (NOTES section 6).

:class:`DenseFlow` holds the one-frame delay, like the normal-flow
pipeline; the field is given at the *current* frame's pixels, so masks
built from it line up with the frame being reported.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from functools import cached_property
from typing import Any, Literal

import cv2
import numpy as np

from motiondetect.config_checks import check_fields
from motiondetect.measurement import stages
from motiondetect.measurement.aperture import structure_tensor
from motiondetect.measurement.normal_flow import GridGeometry
from motiondetect.measurement.picture import BAR_LIMIT, Picture, PictureArea
from motiondetect.measurement.repeats import REPEAT, Repeat, RepeatedFrames

_REMAP_COLUMNS = 4096  # points per row when remapping a list of points

PRESETS = {
    "ultrafast": cv2.DISOPTICAL_FLOW_PRESET_ULTRAFAST,
    "fast": cv2.DISOPTICAL_FLOW_PRESET_FAST,
    "medium": cv2.DISOPTICAL_FLOW_PRESET_MEDIUM,
}


@dataclass(frozen=True)
class DenseFlowConfig:
    """Settings of the 2-D velocity measurement.

    Attributes
    ----------
    work_size : int
        Long side of the working resolution, px; never above the input's
        (frames are only ever reduced). Velocities are in work px/frame.
    preset : {"ultrafast", "fast", "medium"}
        DIS preset (docs/detectors.md measures each on every data set).
    descent_iterations : int or None
        Gradient-descent iterations per patch, replacing the preset's (25
        for "medium"): 8 measured as good on every data set, for less time.
    patch_stride : int
        Step between DIS patches, work px (the "medium" preset's is 3): 4
        changed no data set's pooled cell F1 by more than 0.015 and costs 23 %
        less (docs/detectors.md).
    refinement_iterations : int or None
        Variational refinement iterations, replacing the preset's (5 for
        "medium"); None keeps the preset's. Fewer are faster (3: about a
        fifth less flow time) but left DAVIS's flow noisier: lower cell F1 on
        most of its clips (docs/detectors.md), so the default keeps 5.
    check_preset : {"ultrafast", "fast", "medium", "off"}
        DIS preset of the flow measured the other way, from the previous
        frame to this one, for the forward-backward check
        (:func:`confirmed_both_ways`); "off" skips it. "ultrafast" costs
        about 1 ms a frame at 320 px and caught as many of DIS's errors as
        "fast" (docs/detectors.md).
    bar_limit : int
        Grey level (of 255) at or below which a band along a frame edge that
        has stayed dark is a black bar (FFmpeg cropdetect's 24; a band
        without detail, a blurred panel, is one too), left out of the
        measurement (:mod:`~motiondetect.measurement.picture`); 0 measures
        the whole frame.
    repeat_level : float
        Mean absolute difference from the last frame, grey levels at working
        size, at or below which a frame may repeat it (and then also at most
        a quarter of the usual difference between frames;
        :mod:`~motiondetect.measurement.repeats`); 0: every frame is measured.
    """

    work_size: int = 320
    preset: Literal["ultrafast", "fast", "medium"] = "medium"
    descent_iterations: int | None = 8
    patch_stride: int = 4
    refinement_iterations: int | None = None
    check_preset: Literal["ultrafast", "fast", "medium", "off"] = "ultrafast"
    bar_limit: int = BAR_LIMIT
    repeat_level: float = 1.0

    def __post_init__(self) -> None:
        check_fields(
            self,
            positive=("work_size", "patch_stride"),
            non_negative=("bar_limit", "repeat_level"),
            choices={"preset": tuple(PRESETS), "check_preset": (*PRESETS, "off")},
        )
        if self.descent_iterations is not None:
            check_fields(self, positive=("descent_iterations",))
        if self.refinement_iterations is not None:
            check_fields(self, non_negative=("refinement_iterations",))
        if self.work_size < stages.MIN_FRAME_SIDE:
            raise ValueError(f"work_size must be at least 64, but got {self.work_size}")


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

    @property
    def shape(self) -> tuple[int, int]:
        return self.grey.shape

    def judged(
        self, camera: Any, tracked: np.ndarray | None = None, interval_s: float | None = None
    ) -> VelocityField:
        """This field with its observer motion (track prior, interval) attached,
        keeping every map already computed from the velocity and the frame
        (the cached properties, ``source_px`` and ``structure``): they
        depend on neither."""
        out = dataclasses.replace(self, camera=camera, tracked=tracked, interval_s=interval_s)
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
        self._dis = cv2.DISOpticalFlow_create(PRESETS[self.config.preset])
        if self.config.descent_iterations is not None:
            self._dis.setGradientDescentIterations(self.config.descent_iterations)
        self._dis.setPatchStride(self.config.patch_stride)
        if self.config.refinement_iterations is not None:
            self._dis.setVariationalRefinementIterations(self.config.refinement_iterations)
        # The finest pyramid level DIS measures on is 2^finest_scale coarser.
        self._patch_px = self._dis.getPatchSize() * 2 ** self._dis.getFinestScale()
        check = self.config.check_preset
        self._check = None if check == "off" else cv2.DISOpticalFlow_create(PRESETS[check])
        self._previous: np.ndarray | None = None
        self._pictures = PictureArea(self.config.bar_limit) if self.config.bar_limit > 0 else None
        self._picture: Picture | None = None
        self._repeats = RepeatedFrames(self.config.repeat_level)
        self._geometry: GridGeometry | None = None
        self._grid: np.ndarray | None = None

    def reset(self) -> None:
        """Forget the delayed frame, the picture area and the usual difference between frames."""
        self._previous = None
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
            self._picture, self._previous = picture, None
        if picture is not None:
            frame = picture.crop(frame)
        h, w = frame.shape[:2]
        if self._geometry is None or self._geometry.input_size != (w, h):
            self._geometry = self.geometry_for(w, h)
            self._grid = pixel_grid(*self._geometry.work_size)
            self._previous = None
        grey = working_grey(frame, self._geometry.work_size)
        if self._previous is not None and self._repeats.repeats(grey, self._previous):
            return REPEAT
        previous, self._previous = self._previous, grey
        if previous is None:
            return None
        # Flow from the current frame back to the previous one, at current pixels.
        velocity = -self._dis.calc(grey, previous, None)
        forward = None if self._check is None else self._check.calc(previous, grey, None)
        return VelocityField(
            velocity, grey, previous, self._geometry, self._grid,
            patch_px=self._patch_px, forward_px=forward, picture=picture,
        )  # fmt: skip
