"""Settings of the observer-motion fit (:mod:`.camera_fit`): the plane's
RANSAC, when a frame cannot be judged, the parallax and the lens prior.

One frozen config, the ``[fit]`` section of a config file
(:data:`motiondetect.app.settings.SECTIONS`).
"""

from __future__ import annotations

from dataclasses import dataclass

from motiondetect.config_checks import check_fields
from motiondetect.measurement.flow_config import DIS_REACH_PX


@dataclass(frozen=True)
class FitConfig:
    """Settings of the observer-motion fit.

    Attributes
    ----------
    sample_step_px : int
        Grid step of the velocity samples fed to RANSAC, work px.
    ransac_px : float
        RANSAC inlier threshold, work px/frame: what counts as explained by
        the plane (the inlier share, the noise).
    tight_px : float
        RANSAC also runs at this threshold (three times DIS's 0.1 px error;
        0: off), and the plane under which the velocities are likelier is
        kept (:func:`~.plane.fit_homography`): at 1 px a slow mover or a
        near surface pulls the plane toward itself (docs/detectors.md).
        The outliers of that likelihood spread over ``max_speed_px``.
    min_inlier_share : float
        Below this share of samples the homography explains (as far as the
        image determines them: :func:`~.plane.explained_share`) the frame cannot be
        judged.
    max_speed_px : float
        Median distance of the velocities from where DIS's search started
        (rest, or the last field on a steady fast pan:
        ``VelocityField.searched_px``) above which the motion is outside
        the measurable band; by default DIS's reach,
        :data:`~motiondetect.measurement.flow_config.DIS_REACH_PX`.
    cut_grey : float
        Mean absolute grey difference between the frame and the previous
        one warped by the fit, over the pixels both frames show (not the
        strip a pan brings into view), above which the frame is taken as a
        cut.
    parallax_sigmas : float
        Residuals above this many noise sigmas count as parallax evidence.
    min_parallax_blocks : int
        The epipole's support must cover at least this many of the 4x4
        blocks of the frame (a mover's parallel residuals cover few).
    max_flagged_share : float
        A frame whose grouped objects cover more than this share of it
        cannot be judged: the fit's premise, that the rigid world is the
        dominant motion, has failed (fast turns, heavy blur). Off (1.0) by
        default: at 0.4 it marks woman.mp4's fast turn (frames 447-450)
        unreliable, but it also discards most frames of parallax-rich scenes
        and of moving water, where the mover is still found (sample
        fixation_waving object recall 0.90 -> 0.09; UCSD birds 0.75 -> 0).
    blur_ratio : float
        A frame whose sharpness (variance of its Laplacian) falls below this
        share of the median of the last ``blur_history`` frames is heavily
        blurred (a fast turn, a shake) and is not judged. 0 (the default):
        every frame is judged however soft. A smear keeps the coarse
        texture the flow measures with, and the objects' gates keep its
        false alarms few: with 15 % of the DAVIS frames smeared by a jolt
        (``benchmarks/degrade.py --shake 0.15``) 1/3 finds 0.594 of the
        objects against 0.721 judged, at 0.15 against 0.19 false-alarm
        regions a frame, and it also took woman.mp4's zoom (frames
        453-462, soft, the woman found on each when judged) for blur
        (docs/detectors.md, "Soft frames are judged").
    blur_history : int
        Frames the sharpness reference is the median of.
    aperture_noise : float
        A residual velocity component counts half where the flow patch's
        gradient energy along it equals the square of this many robust
        sigmas of the frame's image difference (``change_noise``); less
        where the image leaves it undetermined (a straight edge, stripes),
        more where it pins it down (:mod:`~motiondetect.measurement.aperture`).
        Seeds of both detectors are tested on that determined residual
        (0: on the whole residual); under known ego-motion the constraint
        ray keeps its depth-bounded test on the whole residual.
    edge_px : float
        Width of the band along the frame edge where content enters or
        leaves and the flow is extrapolated, work px, on top of the frame's
        median speed (``CameraFit.edge_band_px``); detectors do not test it.
    parallax : bool
        Fit an epipole and test only the residual across each point's ray.
        Off by default: measured on every data set, the fitted epipole was
        captured by movers (one mover's parallel residuals fit an epipole
        at infinity) more often than it explained real parallax, and cost
        recall everywhere (docs/detectors.md). Without it the ray of every
        point is the plane's velocity alone, and any residual is tested.
    exclude_tracks : bool
        The samples inside the confirmed tracks' predicted boxes stop voting
        for the plane where they carry it (the plane fitted to all explains
        them at least as well as the rest) and the rest of the samples are
        likelier without them (:func:`~.plane.fit_homography_without`), as
        long as at least ``min_inlier_share`` of the samples remains (a
        plane explaining fewer could not be judged anyway; where the boxes
        leave less, the tracks' own pixels are left out instead:
        :meth:`~motiondetect.detection.tracking.Tracker.predicted_pixels`).
        Off: every sample votes, and a
        mover the camera follows takes the plane once it covers about as
        much of the view as the background (docs/detectors.md, "Tracked
        movers do not vote for the camera's motion").
    occluder_frames : int
        Frames on which the plane's own layer must be seen in front of a
        second layer (the boundary between them moves with it;
        :mod:`~.layer_order`) before the samples that move with it stop
        voting, as a tracked mover's do: a mover the camera follows that
        fills about half the view from the first frame, and so carries the
        plane before any track exists (0: off). Frames that decide nothing
        do not count; one that puts the other layer in front, or as many
        frames without one that puts the plane's there, start again. Set
        above the longest false run measured (``benchmarks/layer_order.py``):
        3 on the shared real clips, 5 on the renders of ``synth_set.py``
        (forward motion past near surfaces); on the shared DAVIS clips
        cropped so that the mover fills a third or half of the view, the
        true runs last 5-48 frames.
    occluder_margin : float
        How much better one plane's motion must predict the layers'
        boundary than the other's (a share of the pixels compared) for a
        frame to decide.
    occluder_coherence : float
        Share of the samples off the plane that one second plane must
        explain for the two to be tested as layers (water, smoke and the
        parallax of many depths are not one layer). A background of water
        or motion-blurred ground is one layer whose flow DIS measures
        loosely: 0.3-0.7 of it fits one plane (DAVIS blackswan and surf
        close up), so the bar is kept low and the outlines decide.
    rest_spread_quantile : float
        Where the confirmed tracks' predicted boxes hold so much of the
        view that their residual sets the spread (``CameraFit.spread_px``),
        the spread is measured on the samples outside them instead: this
        quantile of their residual lengths over a 2-D Gaussian's
        (``sqrt(-2 ln(1 - q))`` sigmas), a high one so that the heavy tail
        of the rigid parallax round the movers still passes
        (:func:`~.plane.frame_spread`). A mover the camera follows close
        up otherwise raises the ray's tolerance above its own residual
        (DAVIS hockey at half the view: 20-44 px against the player's
        3-9). 0: off.
    rest_spread_ratio : float
        The spread outside the boxes is kept only when it is below this
        share of the spread over all the samples. At 0.5 the movers have
        broken the median: under a Gaussian background they must hold
        about 47 % of the samples to double it. Below that the median is
        the background's, and leaving boxes out would only lower the
        tolerance where a false track sits on near parallax (the samples'
        fixation_waving, the fox clip).
    focal_share : float
        Lens prior: the focal length as a share of the frame's long side
        (0.75: a phone's main camera, 26 mm equivalent), for decomposing
        the plane's motion into the constraint ray
        (:mod:`~.plane_ray`; 0: no decomposition).
    line_gain : float
        A rolling shutter's wobble (:mod:`~.rolling_shutter`) is taken out
        of the plane's residual when a function of the sensor line alone
        takes at least this share off the residual's median length in each
        strip across the lines (0, the default: never; 0.15 measured in
        docs/detectors.md, "A rolling shutter's wobble").
    seed : int
        Which random samples RANSAC draws (and the epipole's hypotheses):
        0, the default, is OpenCV's own draw. Another seed gives another,
        equally valid fit; the spread of the results over seeds is the
        benchmarks' noise (``benchmarks/sweep.py --seeds``).
    """

    sample_step_px: int = 8
    ransac_px: float = 1.0
    tight_px: float = 0.3
    min_inlier_share: float = 0.25
    max_speed_px: float = DIS_REACH_PX
    cut_grey: float = 40.0
    parallax_sigmas: float = 4.0
    min_parallax_blocks: int = 6
    max_flagged_share: float = 1.0
    blur_ratio: float = 0.0
    blur_history: int = 30
    aperture_noise: float = 1.0
    edge_px: float = 4.0
    parallax: bool = False
    exclude_tracks: bool = True
    occluder_frames: int = 6
    occluder_margin: float = 0.3
    occluder_coherence: float = 0.4
    rest_spread_quantile: float = 0.9
    rest_spread_ratio: float = 0.5
    focal_share: float = 0.75
    line_gain: float = 0.0
    seed: int = 0

    def __post_init__(self) -> None:
        check_fields(
            self,
            positive=(
                "sample_step_px",
                "ransac_px",
                "max_speed_px",
                "cut_grey",
                "parallax_sigmas",
                "blur_history",
            ),
            non_negative=(
                "min_inlier_share",
                "tight_px",
                "min_parallax_blocks",
                "aperture_noise",
                "edge_px",
                "focal_share",
                "seed",
                "occluder_frames",
            ),
            shares=(
                "max_flagged_share",
                "blur_ratio",
                "occluder_margin",
                "occluder_coherence",
                "rest_spread_ratio",
                "line_gain",
            ),
        )
        if not 0 <= self.rest_spread_quantile < 1:
            raise ValueError(
                f"rest_spread_quantile must be in [0, 1), got {self.rest_spread_quantile}"
            )
        if self.min_inlier_share >= 1:
            raise ValueError(f"min_inlier_share must be below 1, got {self.min_inlier_share}")
