"""One input's detection, frame by frame: measurement, detectors, fusion, objects.

:class:`MotionDetector` runs the measurement its detectors consume (the
normal-flow stages of Appendix A, or the dense 2-D velocity), the
detectors chosen by name from the registry, and then:

* **velocity path** (default): the observer motion is fitted once per
  frame and shared; the detectors' pixel masks are united, grouped into
  objects and tracked (:mod:`.objects`); a frame whose fit cannot be
  trusted is reported as unreliable and flags nothing;
* **normal path** (the paper's): the detectors' 64x64 cells are united and
  regrouped into regions, kept when they persist in place.
"""

from __future__ import annotations

import collections
import contextlib
import dataclasses
import functools
from collections.abc import Callable, Iterable, Iterator

import cv2
import numpy as np

from motiondetect.constraint_ray.ahead import fitted_ahead
from motiondetect.constraint_ray.camera_fit import CUT, CameraFit, fit_camera
from motiondetect.constraint_ray.fit_config import FitConfig
from motiondetect.constraint_ray.layer_order import LayerOrder
from motiondetect.constraint_ray.velocity_filter import VelocityRayConfig
from motiondetect.detection import streaming
from motiondetect.detection.base import DETECTOR_SETS, registry
from motiondetect.detection.change_history import BackgroundMemory, ChangeHistory, slow_parts
from motiondetect.detection.frame_result import FrameResult
from motiondetect.detection.framing import Framing
from motiondetect.detection.fusion import FrameMotion, fuse, object_region
from motiondetect.detection.layers import assigned_objects
from motiondetect.detection.objects import MovingObject, TrackConfig, group_objects
from motiondetect.detection.regions import Region, regions_mask
from motiondetect.detection.rigid_depth import RigidDepth
from motiondetect.detection.screen_fixed import ScreenFixed, without_overlay
from motiondetect.detection.shaping import CHANGE_BOX, InteriorMotion
from motiondetect.detection.streaming import F
from motiondetect.detection.tracking import Tracker
from motiondetect.measurement.dense_flow import DenseFlow, DenseFlowConfig, VelocityField
from motiondetect.measurement.normal_flow import NormalFlowPipeline, StageConfig
from motiondetect.measurement.picture import Picture
from motiondetect.measurement.repeats import REPEAT
from motiondetect.measurement.stages import GRID

_GROW = np.ones((3, 3), np.uint8)


class MotionDetector:
    """Measurement + detectors for one input.

    Parameters
    ----------
    detector : {"constraint-ray", "animate", "both"}
    measure : {"velocity", "normal"}
        The 2-D velocity (default) or the paper's normal flow.
    configs : config dataclasses, optional
        Any of the detectors', the stages' (``StageConfig``), the dense
        flow's, the fit's and the tracker's; each replaces its defaults.
    egomotion : callable, optional
        Known camera motion, ``egomotion(frame_index, geometry)`` for the
        step from the frame before; across a gap (a frame not given, or a
        repeat) it is called with ``since=`` the frame measured from
        (:class:`~motiondetect.constraint_ray.egomotion.EgoMotion` composes
        the steps).
    persistence : int, optional
        Frames an object (or, on the normal path, a region) must persist;
        replaces the ``TrackConfig``'s.
    """

    def __init__(
        self,
        detector: str = "both",
        *configs,
        measure: str = "velocity",
        egomotion=None,
        persistence: int | None = None,
    ) -> None:
        if measure not in DETECTOR_SETS:
            raise ValueError(f"measure must be one of {sorted(DETECTOR_SETS)}, got {measure!r}")
        if detector not in DETECTOR_SETS[measure]:
            raise ValueError(
                f"detector must be one of {sorted(DETECTOR_SETS[measure])}, but got {detector!r}"
            )
        by_type = {type(c): c for c in configs if c is not None}
        track = by_type.get(TrackConfig, TrackConfig())
        if persistence is not None:
            track = dataclasses.replace(track, persistence=persistence)
        classes = registry()
        self.measure = measure
        self.egomotion = egomotion
        self.persistence = track.persistence
        self.detectors = {
            name: classes[name](by_type.get(classes[name].config_type), egomotion)
            for name in DETECTOR_SETS[measure][detector]
        }
        self.min_cells = min(getattr(d.config, "min_cells", 3) for d in self.detectors.values())
        self.fit_config = by_type.get(FitConfig, FitConfig())
        self.ray_config = by_type.get(VelocityRayConfig, VelocityRayConfig())
        share = 0.0 if egomotion is not None else track.rigid_share  # known rays are exact
        self._rigid = RigidDepth(share, self.fit_config.focal_share)
        self.tracker = Tracker(track)
        self._history = ChangeHistory(track.support_frames)
        self._overlay = ScreenFixed(track.overlay_frames)
        self._order = LayerOrder(self.fit_config)
        rate = track.background_rate
        self._background = BackgroundMemory(rate, track.background_frames) if rate > 0 else None
        if measure == "velocity":
            flow_config = by_type.get(DenseFlowConfig, DenseFlowConfig())
            if egomotion is not None:  # known poses describe the whole recorded frame
                flow_config = dataclasses.replace(flow_config, bar_limit=0)
            self.pipeline = DenseFlow(flow_config)
        else:
            self.pipeline = NormalFlowPipeline(by_type.get(StageConfig))
        self._epipole: np.ndarray | None = None
        self._sampled: np.ndarray | None = None  # the last plane residual at the samples
        self._recent: list[np.ndarray] = []
        self._sharpness: collections.deque = collections.deque(maxlen=self.fit_config.blur_history)
        self._picture: Picture | None = None
        self._last: FrameResult | None = None  # held for a repeated frame
        self._last_time: float | None = None  # of the last frame measured
        self._measured_at: int | None = None  # index of the last frame measured that differed
        self._before: dict[int, Region] = {}  # each reported track's last region

    def reset(self) -> None:
        """Start afresh (a new input, or after a gap in the frames)."""
        self.pipeline.reset()
        self._reset_judging()

    def _reset_judging(self) -> None:
        """Forget what :meth:`judge` keeps (not the measurement's state,
        which the measuring thread owns)."""
        self._last = self._last_time = None
        self._before = {}
        self.tracker.reset()
        for det in self.detectors.values():
            det.reset()
        self._epipole, self._sampled, self._recent = None, None, []
        self._order.reset()
        self._sharpness.clear()
        self._history.reset()
        self._rigid.reset()
        self._overlay.reset()
        if self._background is not None:
            self._background.reset()

    def process(self, frame: np.ndarray, index: int, time_s: float) -> FrameResult:
        """Run one frame through the measurement and the detectors."""
        return self.judge(self.measure_frame(frame), index, time_s)

    def stream(self, frames: Iterable[F], frame_skip: int = 0) -> Iterator[tuple[F, FrameResult]]:
        """Each frame (anything with ``image``, ``index`` and ``time_s``) with its result.

        With ``frame_skip`` n, only every (n+1)-th frame is measured and
        judged (velocities then span n+1 frames); each skipped frame comes
        with the last judged frame's result, marked ``held_from`` (like
        DVR-Scan's ``--frame-skip``: faster, coarser in time). The skipped
        frames are held in memory until the next judged frame is measured.
        Known ego-motion, given frame to frame, refuses it.

        When OpenCV may use more than one thread (``cv2.getNumThreads()``),
        the next frame to judge is read and measured on a second thread
        while this one is judged: the results are those of :meth:`process`,
        in order. Reading ``frames`` then happens on that thread too.
        """
        if frame_skip < 0:
            raise ValueError(f"frame_skip must be at least 0, but got {frame_skip}")
        if frame_skip and self.egomotion is not None:
            raise ValueError("frame_skip cannot be used with known ego-motion (frame to frame)")
        groups = streaming.judged_groups(frames, frame_skip + 1)
        if cv2.getNumThreads() <= 1:
            measured = (streaming.measured(group, self.measure_frame) for group in groups)
        else:
            measured = streaming.measured_ahead(groups, self.measure_frame, self.prepare)
        last = None
        # Closed on any exit, so that the reading thread has stopped before an
        # error here leaves the caller to close the source it reads.
        with contextlib.closing(measured):
            for held, frame, flow in measured:
                for skipped in held:
                    yield skipped, last.held(skipped.index, skipped.time_s)
                if frame is not None:
                    last = self.judge(flow, frame.index, frame.time_s)
                    yield frame, last

    def measure_frame(self, frame: np.ndarray) -> object | None:
        """The first half of :meth:`process`: the frame's measurement alone.

        It depends only on the frames measured before, so the next frame's
        can run on another thread while :meth:`judge` handles this one
        (:meth:`stream`). None for the first frame.
        """
        return self.pipeline.process(frame)

    def prepare(self, flow: object | None, stop: Callable[[], bool] | None = None) -> object | None:
        """What :meth:`judge` reads of a measurement that depends on it alone,
        computed now: the field's shared maps, then the observer-motion fit's
        first part (:func:`~motiondetect.constraint_ray.ahead.fitted_ahead`),
        unless ``stop()`` says to stop between the two. :meth:`stream` has
        the measuring thread do it while the judging one is busy, and stop
        once that waits; :meth:`judge` does what is left."""
        if not isinstance(flow, VelocityField):
            return flow
        flow = flow.prepared()
        return flow if stop is not None and stop() else fitted_ahead(flow, self.fit_config)

    def judge(self, flow: object | None, index: int, time_s: float) -> FrameResult:
        """The second half of :meth:`process`: detectors, fusion and objects
        on a measurement from :meth:`measure_frame`, given in frame order.

        A frame that repeats the last one (``REPEAT``) carries the last
        result, marked ``repeat`` and ``held_from``."""
        since = self._measured_at  # the frame this one was measured from
        if flow is not REPEAT:
            self._measured_at = index
        if flow is REPEAT:  # no time passes in what it shows
            self._last_time = time_s
            if self._last is not None:
                return dataclasses.replace(self._last.held(index, time_s), repeat=True)
        if flow is None or flow is REPEAT:
            result = FrameResult(index, time_s, [], np.zeros((GRID, GRID), bool), None, None, None)
        elif self.measure == "velocity":
            result = self._velocity_frame(flow, index, time_s, since)
        else:
            result = self._normal_frame(dataclasses.replace(flow, since=since), index, time_s)
        self._last = result
        return result

    def _normal_frame(self, flow, index: int, time_s: float) -> FrameResult:
        outputs = {name: det.process(flow, index) for name, det in self.detectors.items()}
        flagged, regions = fuse(outputs, flow.geometry, self.min_cells)
        flagged, regions = self._persistent(flagged, regions)
        ray = outputs.get("constraint-ray")
        observer = ray.observer if ray else None
        coarse = ray.coarse if ray else None
        return FrameResult(index, time_s, regions, flagged, observer, coarse, flow, outputs)

    def _velocity_frame(
        self, flow: VelocityField, index: int, time_s: float, since: int | None
    ) -> FrameResult:
        if flow.picture != self._picture:  # black bars found or lit: other work pixels
            self._reset_judging()
            self._picture = flow.picture
        predicted = self.tracker.predicted_mask(flow.shape)  # where confirmed tracks should be
        fit = self._fitted(flow, predicted)
        tracked = predicted if self.tracker.config.prior else None
        flow = flow.judged(fit, tracked, self._interval(time_s), since)
        outputs = {name: det.process(flow, index) for name, det in self.detectors.items()}
        judged = [out.camera for out in outputs.values() if out.camera is not None]
        camera = judged[0] if judged else fit
        known = next((out.observer for out in outputs.values() if out.observer), None)
        union = np.zeros(flow.shape, bool)
        for out in outputs.values():
            union |= out.mask
        self._history.update(flow, fit)
        tolerance = self.ray_config.tolerance(fit.noise_px, fit.spread_px)
        self._rigid.update(flow, fit, tolerance)
        track = self.tracker.config
        overlay = self._overlay.update(flow, fit, tolerance)
        if overlay is not None and union.any():
            union = without_overlay(union, overlay, flow.patch_px)
        objects = self._grouped(flow, fit, union, self._remembered(flow, fit, union, predicted))
        objects = assigned_objects(objects, flow, fit, track.layer_sigmas, track.min_area_share)
        objects = self._rigid.without_rigid(objects)
        covered = sum(float(o.mask.mean()) for o in objects)
        reason = camera.reason
        if not reason and covered > self.fit_config.max_flagged_share:
            reason = "most of the frame off the fitted motion"
        empty = np.zeros((GRID, GRID), bool)
        if reason:
            self.tracker.coast(cut=reason == CUT)  # no track is predicted across a cut
            if reason == CUT:
                self._order.reset()
            return FrameResult(
                index, time_s, [], empty, known, None, flow, outputs, camera=camera, reason=reason
            )
        confirmed = self.tracker.update(objects, fit.homography)
        motion = _frame_motion(flow, fit)
        regions = [
            object_region(obj, outputs, flow.geometry, self._before.get(obj.track), motion)
            for obj in confirmed
        ]
        self._before = {r.track: r for r in regions if r.detectors}
        mask = np.zeros(flow.shape, bool)
        for obj in confirmed:
            mask |= obj.mask
        if flow.picture is not None:
            framing = Framing(flow.picture, flow.geometry)
            regions, mask, overlay = framing.placed(
                regions, [o.mask for o in confirmed], mask, overlay
            )
        flagged = regions_mask(regions) if regions else empty
        return FrameResult(
            index, time_s, regions, flagged, known, None, flow, outputs,
            mask=mask, camera=camera, overlay=overlay,
        )  # fmt: skip

    def _fitted(self, flow: VelocityField, predicted: np.ndarray) -> CameraFit:
        """The frame's :func:`fit_camera`, the ``predicted`` tracks' samples (their
        own pixels where their boxes leave too few) or an occluder's
        (:class:`LayerOrder`) left out where they carry the plane;
        the blur reference, the epipole and the layer order learn from it."""
        reference = float(np.median(self._sharpness)) if self._sharpness else None
        occluder = self._order.occluder  # a mover that fills the view and took the plane
        # Where the boxes leave too little to fit the plane to: the tracks' own pixels,
        # grown by half a flow patch (how far a mover's velocity reaches past it).
        pixels = functools.partial(self.tracker.predicted_pixels, flow.shape, flow.patch_px // 2)
        fit = fit_camera(
            flow, self.fit_config, self._epipole, reference, predicted, occluder, self._sampled,
            finer_movers=pixels,
        )  # fmt: skip
        self._order.update(flow, fit.voted, fit.voted_inliers, fit.edge_band_px)
        if self.fit_config.blur_ratio > 0:  # the blur test's reference
            self._sharpness.append(fit.sharpness)
        self._epipole, self._sampled = fit.epipole, fit.plane_sampled
        return fit

    def _interval(self, time_s: float) -> float | None:
        """Seconds since the last frame measured; None when not known or not
        increasing (a source without times gives every frame 0)."""
        last, self._last_time = self._last_time, time_s
        return time_s - last if last is not None and time_s > last else None

    def _grouped(
        self, flow: VelocityField, fit: CameraFit, flagged: np.ndarray, unlike: np.ndarray | None
    ) -> list[MovingObject]:
        """:func:`group_objects` with the frame's support, its difference from
        the remembered background (``unlike``) and what its motion says of a
        plain mover's interior (:class:`InteriorMotion`)."""
        track, support = self.tracker.config, self._support(fit, flagged)
        motion = None
        if support is not None and fit.residual_px is not None:
            seen = fit.change_level(track.support_sigmas)  # the support gate's level
            motion = InteriorMotion(fit.residual_px, flow.structure, seen)
        return group_objects(flagged, flow.velocity_px, track, support, unlike, flow.grey, motion)

    def _support(self, fit: CameraFit, flagged: np.ndarray) -> np.ndarray | None:
        """Where the image changed once the camera's motion is undone: over one
        frame, and for slow flagged parts also over ``support_frames``."""
        track = self.tracker.config
        if track.support_sigmas <= 0 or fit.plane_difference is None:
            return None
        changed = fit.image_changed(track.support_sigmas, CHANGE_BOX)
        if track.support_frames < 2 or fit.residual_px is None or not flagged.any():
            return changed
        slow = slow_parts(flagged, fit.residual_length(), track.support_frames, track.support_px)
        if not slow.any():
            return changed
        longer = self._history.changed(track.support_sigmas, CHANGE_BOX)
        return changed if longer is None else changed | (longer & slow)

    def _remembered(
        self, flow: VelocityField, fit: CameraFit, flagged: np.ndarray, tracked: np.ndarray | None
    ):
        """Where the frame differs from the remembered background (None: no memory,
        or nothing known yet); it then learns this frame outside the flagged
        pixels and ``tracked``, the boxes where confirmed tracks are predicted
        (a mover missed this frame)."""
        if self._background is None:
            return None
        sigmas = self.tracker.config.support_sigmas
        differs = self._background.differs(flow, fit, sigmas, CHANGE_BOX)
        changed = None if fit.plane_difference is None else fit.image_changed(sigmas, CHANGE_BOX)
        self._background.learn(flagged if tracked is None else flagged | tracked, changed)
        return differs

    def _persistent(
        self, flagged: np.ndarray, regions: list[Region]
    ) -> tuple[np.ndarray, list[Region]]:
        """Normal path: keep regions whose cells (grown by one) touched flagged
        cells in each of the previous ``persistence - 1`` frames."""
        recent, self._recent = self._recent, [*self._recent, flagged][-(self.persistence - 1) :]
        if self.persistence <= 1:
            return flagged, regions
        if len(recent) < self.persistence - 1:
            return np.zeros_like(flagged), []
        grown = [cv2.dilate(r.astype(np.uint8), _GROW) > 0 for r in recent]
        kept = [r for r in regions if all(g[r.cells[:, 0], r.cells[:, 1]].any() for g in grown)]
        return (regions_mask(kept) if kept else np.zeros_like(flagged)), kept


def _frame_motion(flow: VelocityField, fit: CameraFit) -> FrameMotion | None:
    """What the frame's objects' velocities are read from: its image velocity
    and the fitted plane's residual over the time since the last frame
    measured, leaving out half a flow patch round each object (how far DIS
    smears a mover's velocity); None where that time is not known."""
    if flow.interval_s is None or fit.residual_px is None:
        return None
    return FrameMotion(flow.velocity_px, fit.residual_px, flow.interval_s, flow.patch_px // 2)
