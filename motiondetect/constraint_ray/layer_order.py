"""Which of two motion layers is in front: an occluder's outline moves with it.

The dominant plane (:mod:`.plane`) is the motion most samples share. A
mover the camera follows that covers about half the view from the first
frame carries the plane from the start: the background is flagged and the
mover never is, and leaving tracked movers out of the fit
(``FitConfig.exclude_tracks``) cannot help, since no track is ever on it.
One frame's velocities cannot tell the two apart (a followed mover moves in
the image as a near rigid surface the camera fixates would), but their
outlines can: where one layer hides the other, the boundary between them
moves with the layer in front. A small mover's outline moves with the
mover; the view of the background around a large one moves with that mover.

Each frame with enough samples off the plane (at least
``FitConfig.min_inlier_share``: as many as the rest must keep to be judged),
a second plane is fitted to those samples, and when it explains enough of
them (one layer, ``FitConfig.occluder_coherence``) each pixel is
labelled by the plane it follows. Last frame's labels, moved by either
plane, predict this frame's; where the two predictions differ (the band
the layers' relative motion sweeps), the plane that predicts better is the
one whose layer is in front. After ``FitConfig.occluder_frames`` frames
that put the plane's own layer in front (frames that decide nothing, or
cannot be tested, are skipped; one the other way starts again), the
samples nearer that layer's last motion than the other's stop voting
(:func:`~.camera_fit.fit_camera`, ``occluder``), as a tracked mover's do,
until a frame puts the other layer in front or as many frames pass without
one that puts the plane's there. By then the mover is flagged and tracked,
and its track keeps it out of the fit.
"""

from __future__ import annotations

import cv2
import numpy as np

from motiondetect.constraint_ray.fit_config import FitConfig
from motiondetect.constraint_ray.plane import plane_error, ransac_homography, samples
from motiondetect.measurement.dense_flow import VelocityField

#: Labels are compared on every ``_STEP``-th work pixel each way.
_STEP = 2
#: Fewest compared pixels, as a share of those labelled, for a frame to
#: decide (192 of a 320x240 frame's): fewer are a few stray labels.
_MIN_EVIDENCE_SHARE = 0.0025
#: A label outside the frame, moved in from beyond its edge.
_OUTSIDE = 2


def second_plane(
    points: np.ndarray, velocity: np.ndarray, threshold_px: float, coherence: float
) -> tuple[np.ndarray | None, float]:
    """RANSAC's plane among ``points`` (the samples off the first) and the
    share of them within ``threshold_px`` of it.

    Only a plane explaining at least ``coherence`` of them is of use, and
    one is drawn (four inliers) within ``log(0.001) / log(1 - coherence^4)``
    draws with 99.9 % confidence: 266 at 0.4 (26 at 0.7). OpenCV stops
    sooner once it has drawn a plane explaining more.
    """
    if len(points) < 8:
        return None, 0.0
    draws = int(np.ceil(np.log(1e-3) / np.log(1.0 - coherence**4)))
    homography = ransac_homography(points, velocity, threshold_px, draws, confidence=0.999)
    if homography is None:
        return None, 0.0
    return homography, float((plane_error(points, velocity, homography) < threshold_px).mean())


def _scaled(homography: np.ndarray, step: int) -> np.ndarray:
    """``homography`` on work pixels as one on every ``step``-th pixel."""
    scale = np.diag([1.0 / step, 1.0 / step, 1.0])
    return scale @ homography @ np.linalg.inv(scale)


def follows_second(
    field: VelocityField, first: np.ndarray, second: np.ndarray, threshold_px: float
) -> np.ndarray:
    """Where the velocity is off the ``first`` plane by at least
    ``threshold_px`` and nearer the ``second`` plane's, on every
    :data:`_STEP`-th work pixel.

    Parameters
    ----------
    field : VelocityField
    first, second : (3, 3) ndarray
        Homographies taking current work pixels to previous ones.
    threshold_px : float
        Work px/frame.

    Returns
    -------
    (ceil(h / step), ceil(w / step)) ndarray of bool
    """
    grid = field.pixel_grid[::_STEP, ::_STEP]
    shape = grid.shape[:2]
    points, velocity = grid.reshape(-1, 2), field.velocity_px[::_STEP, ::_STEP].reshape(-1, 2)
    errors = [plane_error(points, velocity, h).reshape(shape) for h in (first, second)]
    return (errors[1] < errors[0]) & (errors[0] >= threshold_px)


def front_verdict(
    previous: np.ndarray,
    current: np.ndarray,
    first: np.ndarray,
    second: np.ndarray,
    edge_px: float,
    margin: float,
) -> int:
    """Which layer's outline moved with it from last frame to this one.

    Parameters
    ----------
    previous, current : (h', w') ndarray of bool
        :func:`follows_second` on last frame's field and this frame's, both
        under this frame's two planes.
    first, second : (3, 3) ndarray
        The two planes (current work pixels to previous ones).
    edge_px : float
        Band along the frame edge left out (where labels move in from
        outside), work px.
    margin : float
        How much better, as a share of the compared pixels, one plane's
        prediction must match this frame's labels.

    Returns
    -------
    int
        1: the first plane's layer is in front (the second's outline moved
        with the first); -1: the second's; 0: the frame does not decide.
    """
    h, w = current.shape
    labels = previous.astype(np.uint8)
    flags = cv2.INTER_NEAREST | cv2.WARP_INVERSE_MAP
    moved = [
        cv2.warpPerspective(labels, _scaled(hom, _STEP), (w, h), flags=flags, borderValue=_OUTSIDE)
        for hom in (first, second)
    ]
    compared = (moved[0] != _OUTSIDE) & (moved[1] != _OUTSIDE) & (moved[0] != moved[1])
    edge = int(np.ceil(edge_px / _STEP))
    if edge > 0:
        compared[:edge], compared[-edge:], compared[:, :edge], compared[:, -edge:] = (False,) * 4
    if compared.sum() < _MIN_EVIDENCE_SHARE * current.size:
        return 0
    truth = current[compared]
    by_first = float((moved[0][compared] == truth).mean())
    by_second = float((moved[1][compared] == truth).mean())
    if by_first - by_second > margin:
        return 1
    return -1 if by_second - by_first > margin else 0


class LayerOrder:
    """Whether the dominant plane's own layer has been seen in front of a
    second, coherent layer on enough frames (:attr:`occluder`)."""

    def __init__(self, config: FitConfig):
        self.config = config
        self.reset()

    def reset(self) -> None:
        self._previous: VelocityField | None = None
        self._run = 0  # frames that put the plane's layer in front
        self._since = 0  # frames since the last of them
        self._layers: tuple[np.ndarray, np.ndarray] | None = None  # on the last of them

    @property
    def run(self) -> int:
        """Frames counted so far toward ``occluder_frames``."""
        return self._run

    @property
    def occluder(self) -> tuple[np.ndarray, np.ndarray] | None:
        """The motions of the layer found in front and of the one behind it
        on the last frame that put it there (homographies, current to
        previous work px), when enough frames have: the samples nearer the
        first are left out of the next frame's fit."""
        return self._layers if 0 < self.config.occluder_frames <= self._run else None

    def _decided(self, verdict: int, layers: tuple[np.ndarray, np.ndarray] | None) -> None:
        if verdict > 0:
            self._run, self._since, self._layers = self._run + 1, 0, layers
            return
        self._since += 1
        if verdict < 0 or self._since > self.config.occluder_frames:
            self._run = 0

    def update(
        self, field: VelocityField, voted: np.ndarray | None, inliers: np.ndarray, edge_px: float
    ) -> int:
        """Take one frame's evidence; returns this frame's verdict
        (:func:`front_verdict`: 1 the plane's layer in front, -1 the
        other's, 0 undecided or not tested).

        Parameters
        ----------
        field : VelocityField
        voted : (3, 3) ndarray or None
            The plane all the samples vote for (``CameraFit.voted``).
        inliers : (N,) ndarray of bool
            Its RANSAC inliers among :func:`~.plane.samples`.
        edge_px : float
            ``CameraFit.edge_band_px``.
        """
        if self.config.occluder_frames <= 0 or voted is None:
            self.reset()
            return 0
        previous, self._previous = self._previous, field
        verdict, layers = self._verdict(previous, field, voted, inliers, edge_px)
        self._decided(verdict, layers)
        return verdict

    def _verdict(
        self, previous: VelocityField | None, field: VelocityField, voted: np.ndarray,
        inliers: np.ndarray, edge_px: float,
    ) -> tuple[int, tuple[np.ndarray, np.ndarray] | None]:  # fmt: skip
        """:func:`front_verdict` of the plane and the second plane fitted to
        its outliers, and the two planes; 0 when those are too few to be the
        world (below ``min_inlier_share``) or not one layer."""
        config = self.config
        off = ~inliers
        if previous is None or previous.shape != field.shape:
            return 0, None
        if off.mean() < config.min_inlier_share:
            return 0, None
        points, velocity = samples(field, config.sample_step_px)
        coherence = config.occluder_coherence
        second, explained = second_plane(points[off], velocity[off], config.ransac_px, coherence)
        if second is None or explained < coherence:
            return 0, None
        labels = [follows_second(f, voted, second, config.ransac_px) for f in (previous, field)]
        verdict = front_verdict(*labels, voted, second, edge_px, config.occluder_margin)
        return verdict, (voted, second)
