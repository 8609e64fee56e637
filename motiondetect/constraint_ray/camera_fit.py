"""The observer's motion fitted to the 2-D velocity field: plane plus parallax.

In a rigid world the image velocity of each point lies on a 1-D locus set
by the observer's motion (section 3; Figure 2). With the full velocity we
can fit that motion instead of matching the five canonical classes:

1. **Dominant plane.** A homography, fitted by RANSAC to the velocity
   sampled on a grid, absorbs the rotation and the motion of the dominant
   surface (or of the plane at infinity).
2. **Parallax.** What a rigid point has left over lies on the line through
   it and the epipole (the focus of expansion), its length set by the
   point's depth off the plane (Irani & Anandan 1998; docs/maths.md). That
   line *is* Nelson's constraint ray with the rotation taken out.
3. **Degenerate cases.** A planar scene or a pure rotation leaves no
   parallax; then any residual is independent motion. A single mover's
   residuals are parallel and so fit *some* epipole; an epipole is
   therefore accepted only when its support is spread over the frame.

Everything here is a pure function of one frame's field and, for the
epipole, the previous frame's estimate.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import cv2
import numpy as np

from motiondetect.constraint_ray.ahead import Ahead, ahead_of, plane_maps, wobble_removed
from motiondetect.constraint_ray.epipole import fit_epipole, off_ray
from motiondetect.constraint_ray.fit_config import FitConfig
from motiondetect.constraint_ray.plane import (
    MEDIAN_TO_SIGMA,
    fit_homography_without,
    frame_spread,
    plane_error,
)
from motiondetect.detection.regions import true_pixels
from motiondetect.measurement.aperture import determined
from motiondetect.measurement.dense_flow import VelocityField, vector_length
from motiondetect.measurement.image_change import difference_noise

#: The plane's median speed below which a frame without parallax counts as
#: static, px/frame.
STATIC_SPEED_PX = 0.3


@dataclass(frozen=True)
class CameraFit:
    """One frame's fitted observer motion.

    Attributes
    ----------
    homography : (3, 3) ndarray of float64 or None
        Maps current work pixels to previous ones for the dominant plane.
    residual_px : (h, w, 2) ndarray of float32 or None
        Velocity minus the plane's velocity, work px/frame.
    noise_px : float
        Robust sigma of one residual component, from the RANSAC inliers.
    inlier_share : float
        Share of samples the homography explains, as far as the image
        determines their motion (:func:`explained_share`): the fit's
        confidence. The noise is measured on the RANSAC inliers alone.
    epipole : (3,) ndarray of float64 or None
        Homogeneous epipole in work pixels (third component 0: at infinity);
        None when there is no usable parallax.
    reason : str
        Empty when the frame can be judged; otherwise why not.
    median_speed_px : float
        Median speed of the sampled velocities, work px/frame.
    plane_difference : (h, w) ndarray of uint8 or None
        ``|grey - previous grey warped by the plane|``, grey levels: where the
        image changed once the camera's motion is undone.
    spread_px : float
        Robust sigma of the plane residual over the whole frame (inliers or
        not), work px/frame: the noise plus the rigid parallax the plane
        leaves (:func:`~.plane.frame_spread`: movers are mostly a minority
        of the samples, so the median ignores them; tracked movers that
        hold about half of them are left out).
    edge_band_px : float
        ``FitConfig.edge_px`` plus the median speed: the band along the
        frame edge where this frame's flow is extrapolated, work px.
    change_noise : float or None
        :func:`difference_noise` of ``plane_difference`` over the pixels
        ``seen`` before, grey levels
        (measured once per frame; None: measured when first needed).
    sharpness : float
        :func:`sharpness` of this frame (0 while the blur test is off).
    aperture_energy : float
        Gradient energy a velocity component needs to count half in
        :meth:`determined_beyond`, grey levels^2/px^2 (0: every component
        counts whole).
    plane_speed_px : float
        Median speed of the plane's own velocity at the samples, work
        px/frame: the image's motion without the measurement's noise, which
        ``median_speed_px`` includes (DIS's noise alone gives a still camera
        a median speed of about 1.2 sigmas).
    voted : (3, 3) ndarray of float64 or None
        The plane all the samples vote for, before known movers or an
        occluder are left out (:mod:`.layer_order` tests its layer).
    voted_inliers : (N,) ndarray of bool or None
        Its RANSAC inliers among the samples (:func:`~.plane.samples`).
    plane_sampled : (N, 2) ndarray of float32 or None
        The plane's residual at the samples before a rolling shutter's
        wobble is taken out: the next frame's fit reads it
        (:func:`~.ahead.wobble_removed`).
    seen : (h, w) ndarray of bool or None
        The pixels the plane takes from inside the previous frame
        (:func:`~motiondetect.measurement.image_change.seen_before`); the
        rest entered the view with this frame, and DIS extrapolates their
        flow from their neighbours'.

    Derived maps that several detectors read (:meth:`image_changed`,
    :meth:`residual_length`) are computed once per fit and kept.
    """

    homography: np.ndarray | None
    residual_px: np.ndarray | None
    noise_px: float
    inlier_share: float
    epipole: np.ndarray | None
    reason: str = ""
    median_speed_px: float = 0.0
    plane_difference: np.ndarray | None = None
    spread_px: float = 0.0
    edge_band_px: float = 0.0
    change_noise: float | None = None
    sharpness: float = 0.0
    aperture_energy: float = 0.0
    plane_speed_px: float = 0.0
    voted: np.ndarray | None = None
    voted_inliers: np.ndarray | None = None
    plane_sampled: np.ndarray | None = None
    seen: np.ndarray | None = None
    _memo: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    def difference_sigma(self) -> float:
        """``change_noise``, measured on ``plane_difference`` when not given,
        grey levels."""
        if self.change_noise is not None:
            return self.change_noise
        if "noise" not in self._memo:
            self._memo["noise"] = difference_noise(self.plane_difference, self.seen)
        return self._memo["noise"]

    def change_level(self, sigmas: float) -> float:
        """The grey-level change :meth:`image_changed` counts as seen:
        ``sigmas`` times :meth:`difference_sigma`."""
        return sigmas * self.difference_sigma()

    def image_changed(self, sigmas: float, box: int) -> np.ndarray:
        """Where the image changed beyond noise once the camera's motion is
        undone: the ``box``-px mean of ``plane_difference`` above ``sigmas``
        times :meth:`difference_sigma`, (h, w) bool. Do not modify the
        result: it is shared."""
        key = ("changed", sigmas, box)
        if key not in self._memo:
            level = self.change_level(sigmas)
            self._memo[key] = cv2.blur(self.plane_difference, (box, box)) > level
        return self._memo[key]

    def determined_beyond(
        self, field: VelocityField, candidates: np.ndarray, tolerance: float,
        epipole: np.ndarray | None = None, residual: np.ndarray | None = None,
    ) -> np.ndarray:  # fmt: skip
        """``candidates`` (h, w) narrowed by :meth:`determined_beyond_at`, a new array."""
        out = np.zeros_like(candidates)
        ys, xs = true_pixels(candidates)
        out[ys, xs] = self.determined_beyond_at(field, ys, xs, tolerance, epipole, residual)
        return out

    def determined_beyond_at(
        self, field: VelocityField, ys: np.ndarray, xs: np.ndarray, tolerance: float,
        epipole: np.ndarray | None = None, residual: np.ndarray | None = None,
    ) -> np.ndarray:  # fmt: skip
        """Whether the *determined* residual at each pixel ``(ys, xs)``
        (:func:`~motiondetect.measurement.aperture.determined` over the
        field's patch) lies off the ray through ``epipole`` by more than
        ``tolerance`` px/frame, (N,) bool; each pixel's answer is its own.
        A velocity the flow measured the other way does not confirm
        (:meth:`VelocityField.confirmed_at`) is DIS's error, not a residual,
        and is never beyond.
        """
        out = np.zeros(len(ys), bool)
        if not len(ys):
            return out
        confirmed = field.confirmed_at(ys, xs)
        if not confirmed.all():
            ys, xs = ys[confirmed], xs[confirmed]
        if not len(ys):
            return out
        residual = (self.residual_px if residual is None else residual)[ys, xs]
        if self.aperture_energy > 0:
            tensor = tuple(t[ys, xs] for t in field.structure)
            residual = determined(residual, tensor, self.aperture_energy)
        out[confirmed] = off_ray(residual, field.pixel_grid[ys, xs], epipole) > tolerance
        return out

    def residual_length(self) -> np.ndarray:
        """``|residual_px|``, (h, w) float32 work px/frame (shared: do not modify)."""
        if "length" not in self._memo:
            self._memo["length"] = vector_length(self.residual_px)
        return self._memo["length"]

    @property
    def reliable(self) -> bool:
        return not self.reason

    @property
    def class_id(self) -> int:
        """The canonical class (section 3.1) this fitted motion falls in.

        0 static (the plane's own speed, ``plane_speed_px``, below
        :data:`STATIC_SPEED_PX`: DIS's noise does not make a still camera
        move); 1 no parallax (rotation, or a planar scene) or parallax
        from a distant epipole (translation across the view); 2 parallax
        toward an epipole inside the frame (forward motion, with or without
        rotation: classes 2 and 4 differ only in the part the plane fit
        removes); -1 when the frame cannot be judged.
        """
        if self.homography is None or self.reason:
            return -1
        if self.epipole is None:
            return 0 if self.plane_speed_px < STATIC_SPEED_PX else 1
        return 2 if abs(self.epipole[2]) > 1e-6 else 1

    @property
    def label(self) -> str:
        """A short name of the fitted motion."""
        if self.class_id < 0:
            return "unreliable"
        if self.epipole is None:
            return "static" if self.class_id == 0 else "plane (no parallax)"
        return "parallax, epipole " + ("ahead" if self.class_id == 2 else "at infinity")

    def to_json(self) -> dict:
        return {
            "name": self.label,
            "confidence": round(float(self.inlier_share), 4),
            "noise_px": round(float(self.noise_px), 4),
            "epipole": None if self.epipole is None else [round(float(v), 4) for v in self.epipole],
        }


#: The reason of a frame that starts a new shot (nothing carries across it).
CUT = "cut"


def _reason(homography, share, speed, searched_px, cut, blurred, config: FitConfig) -> str:
    """Why the frame cannot be judged, or ""; ``searched_px``: how far DIS
    searched from its start (``VelocityField.searched_px``), None: from rest."""
    if homography is None or share < config.min_inlier_share:
        return "too few inliers"
    if (speed if searched_px is None else searched_px) > config.max_speed_px:
        return "motion beyond the band"
    if cut > config.cut_grey:
        return CUT
    if blurred:
        return "heavy blur"
    return ""


def fit_camera(
    field: VelocityField,
    config: FitConfig,
    previous_epipole: np.ndarray | None = None,
    reference_sharpness: float | None = None,
    movers: np.ndarray | None = None,
    occluder: tuple[np.ndarray, np.ndarray] | None = None,
    previous_sampled: np.ndarray | None = None,
    finer_movers: Callable[[], np.ndarray | None] | None = None,
) -> CameraFit:
    """Fit the observer's motion to one frame's velocity field.

    Parameters
    ----------
    field, config : VelocityField, FitConfig
    previous_epipole, previous_sampled : the last fit's ``epipole`` and ``plane_sampled``
    reference_sharpness : float, optional
        The recent frames' median :func:`sharpness`; none: no blur test.
    movers : (h, w) ndarray of bool, optional
        Where the confirmed tracks are predicted: their samples stop voting
        where they carry the plane (:func:`~.plane.fit_homography_without`).
    finer_movers : callable, optional
        Their own pixels ((h, w) bool or None), asked for where ``movers`` leaves too few.
    occluder : ((3, 3) ndarray, (3, 3) ndarray), optional
        The last motions of a mover in front that carried the plane and of the layer
        behind it (:class:`~.layer_order.LayerOrder`): the samples nearer the first stop voting.

    Returns
    -------
    CameraFit
        With ``reason`` set (and no residual) when the frame cannot be judged.
    """
    ahead = ahead_of(field, config, maps=False)  # prepared with its maps, or without
    points, velocity, speed = ahead.points, ahead.velocity, ahead.speed
    homography, inliers, voted, voters = _plane(ahead, movers, finer_movers, occluder, config)
    kept = homography is ahead.voted[0] and ahead.maps is not None  # most frames keep it
    maps = ahead.maps if kept else plane_maps(field, homography, inliers, config)
    plain = maps.sampled
    homography, inliers, maps = wobble_removed(
        field, ahead, homography, inliers, maps, movers, previous_sampled
    )
    residual, sampled, share = maps.residual, maps.sampled, maps.share
    sharp = ahead.sharpness
    blurred = reference_sharpness is not None and sharp < config.blur_ratio * reference_sharpness
    reason = _reason(homography, share, speed, field.searched_px, maps.cut, blurred, config)
    edge = config.edge_px + speed
    if reason:
        return CameraFit(
            homography, None, 0.0, share, None, reason, speed, edge_band_px=edge, sharpness=sharp,
            voted=voted[0], voted_inliers=voted[1], plane_sampled=plain,
        )  # fmt: skip
    magnitude = np.hypot(sampled[:, 0], sampled[:, 1])
    noise = float(np.median(magnitude[inliers]) * MEDIAN_TO_SIGMA) if inliers.any() else 0.0
    epipole = _epipole(field, points, sampled, magnitude, noise, config, previous_epipole)
    spread = _spread(points, magnitude, voters, movers, config)
    return CameraFit(
        homography, residual, noise, share, epipole, "", speed, maps.difference, spread, edge,
        maps.change_noise, sharp, maps.energy, float(np.median(vector_length(velocity - sampled))),
        voted[0], voted[1], plain, maps.seen,
    )  # fmt: skip


def _spread(
    points: np.ndarray,
    magnitude: np.ndarray,
    voters: np.ndarray,
    movers: np.ndarray | None,
    config: FitConfig,
) -> float:
    """:func:`~.plane.frame_spread` of the samples' residual lengths, the
    samples in the tracks' predicted boxes (``movers``) known."""
    return frame_spread(
        magnitude, voters, _at_samples(movers, points), config.rest_spread_quantile,
        config.rest_spread_ratio, config.min_inlier_share,
    )  # fmt: skip


def _at_samples(mask: np.ndarray | None, points: np.ndarray) -> np.ndarray | None:
    """``mask``, (h, w) bool, read at the sample ``points``: (N,) bool; None without one."""
    return None if mask is None else mask[points[:, 1].astype(int), points[:, 0].astype(int)]


def _plane(
    ahead: Ahead,
    movers: np.ndarray | None,
    finer: Callable[[], np.ndarray | None] | None,
    occluder: tuple[np.ndarray, np.ndarray] | None,
    config: FitConfig,
) -> tuple[np.ndarray | None, np.ndarray, tuple[np.ndarray | None, np.ndarray], np.ndarray]:
    """RANSAC's plane and its inliers, the samples on ``movers`` (the
    tracks' boxes, or their own pixels, ``finer()``, where the boxes leave too few; with
    ``occluder``, those nearer its motion instead) not voting where they
    carry the plane (:func:`~.plane.fit_homography_without`); the plane all
    samples vote for, with its inliers; and the samples the plane kept was
    fitted to (all of them unless it is the refit without the movers)."""
    kwargs = {"outlier_px": config.max_speed_px, "tight_px": config.tight_px, "seed": config.seed}
    points, velocity, voted = ahead.points, ahead.velocity, ahead.voted
    on_movers = np.zeros(len(points), bool)
    if occluder is not None:  # the tracks found while it held the plane lie off it
        front, behind = (plane_error(points, velocity, h) for h in occluder)
        on_movers = front < behind
    elif movers is not None and config.exclude_tracks:
        on_movers = _at_samples(movers, points)
        if finer is not None and (~on_movers).mean() < config.min_inlier_share:
            pixels = finer()
            if pixels is not None:
                on_movers = _at_samples(pixels, points)
    homography, inliers = fit_homography_without(
        points, velocity, on_movers, config.ransac_px, min_rest=config.min_inlier_share,
        voted=voted, **kwargs,
    )  # fmt: skip
    voters = ~on_movers if homography is not voted[0] else np.ones(len(points), bool)
    return homography, inliers, voted, voters


def _epipole(
    field: VelocityField,
    points: np.ndarray,
    sampled: np.ndarray,
    magnitude: np.ndarray,
    noise: float,
    config: FitConfig,
    previous: np.ndarray | None,
) -> np.ndarray | None:
    """The epipole that the samples' large residuals (``sampled``, of
    length ``magnitude``) point to or from; None without ``config.parallax``."""
    if not config.parallax:
        return None
    big = magnitude > config.parallax_sigmas * max(noise, 0.05)
    return fit_epipole(
        points[big], sampled[big], 2.0 * max(noise, 0.1), field.shape,
        config.min_parallax_blocks, previous, np.random.default_rng(config.seed),
    )  # fmt: skip
