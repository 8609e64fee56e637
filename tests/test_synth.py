"""The scene synthesizer against analytic answers (issue 6)."""

from __future__ import annotations

import cv2
import numpy as np

from motiondetect.tools import synth
from motiondetect.tools.synth import Quad, Renderer, SynthConfig


def test_textured_plane_translation_matches_the_analytic_shift():
    config = SynthConfig(camera="static", movers=(), width=160, height=120, supersample=2)
    renderer = Renderer(config)
    plane = [
        Quad(
            np.array([-20.0, -20.0, 10.0]), np.array([40.0, 0, 0]), np.array([0, 40.0, 0]), 0, 40.0
        )
    ]
    f = config.intrinsics.fx
    shifts = []
    images = []
    for t in range(3):
        pose = np.eye(4)
        pose[0, 3] = 0.05 * t  # camera moves right 5 cm/frame
        image, owner, nearest = renderer.render(plane, pose)
        assert nearest == np.float32(10.0) or abs(nearest - 10.0) < 1e-6
        images.append(
            cv2.cvtColor(
                cv2.resize(image, (160, 120), interpolation=cv2.INTER_AREA), cv2.COLOR_BGR2GRAY
            )
        )
    window = cv2.createHanningWindow((160, 120), cv2.CV_64F)
    for a, b in zip(images, images[1:]):
        (dx, dy), _ = cv2.phaseCorrelate(a.astype(np.float64), b.astype(np.float64), window)
        shifts.append((dx, dy))
    expected = -f * 0.05 / 10.0  # the image moves left by f * t / Z = 1.10 px
    for dx, dy in shifts:  # tolerance: 0.08 px, the sub-pixel accuracy of phase correlation
        assert abs(dx - expected) < 0.08 and abs(dy) < 0.05


def test_mover_masks_match_the_rendered_pixels():
    frames = list(
        synth.render_frames(
            SynthConfig(
                camera="pan",
                movers=("smooth", "animate"),
                frames=3,
                width=160,
                height=120,
                supersample=1,
                noise_grey=0.0,
            )
        )
    )
    config = SynthConfig(
        camera="pan", movers=(), frames=3, width=160, height=120, supersample=1, noise_grey=0.0
    )
    rigid = list(synth.render_frames(config))
    for with_movers, without in zip(frames, rigid):
        differs = np.abs(with_movers.image.astype(int) - without.image.astype(int)).max(2) > 0
        moving = with_movers.mask == 255
        assert not (moving & ~differs).sum() > 0.02 * moving.sum()  # mover pixels changed
        static = with_movers.mask == 0
        assert not differs[static].any()  # nothing outside the mask changed
        assert set(np.unique(with_movers.mask)) <= {0, 170, 255}
        assert with_movers.visible and sum(with_movers.visible.values()) == int(
            (with_movers.movers > 0).sum()
        )


def test_scene_file_is_valid_egomotion(tmp_path):
    from motiondetect.constraint_ray.egomotion import EgoMotion
    from motiondetect.measurement.normal_flow import GridGeometry

    config = SynthConfig(camera="uniform", movers=(), frames=3, width=96, height=72, supersample=1)
    info = synth.write_sequence(config, tmp_path)
    assert info["paper_class"] == 1
    ego = EgoMotion.load(tmp_path / "scene.json")
    model = ego(1, GridGeometry((96, 72), (512, 384)))
    assert model.class_id == 6
    # Camera moves right: a rigid point's flow points left, at every cell.
    assert (model.translation_px[..., 0] < 0).all()
    np.testing.assert_allclose(model.rotation_px, 0, atol=1e-3)  # poses stored to 1e-9
    assert 2.5 < ego.min_depth < 3.5  # the near post


def test_the_default_world_is_the_committed_samples_world():
    """World seed 0 renders the committed samples' ground truth, pixel for pixel."""
    from itertools import islice
    from pathlib import Path

    sample = Path(__file__).resolve().parents[1] / "sample_videos" / "uniform_mixed"
    # 60 frames, as rendered: the animate mover sways about the mid-sequence view.
    config = SynthConfig(camera="uniform", movers=("smooth", "animate"), frames=60, seed=1)
    for frame in islice(synth.render_frames(config), 3):
        truth = cv2.imread(str(sample / "truth" / f"{frame.index:06d}.png"), cv2.IMREAD_GRAYSCALE)
        assert np.array_equal(frame.mask, truth)


def test_a_world_seed_lays_the_boxes_and_the_post_out_anew(tmp_path):
    default = synth.world()  # seed 0: the samples' world (the test above)
    moved = synth.world(5)
    assert len(moved) == len(default)
    assert [q.corner.tolist() for q in moved[:2]] == [q.corner.tolist() for q in default[:2]]
    assert all(  # every box and the post moved; wall and ground did not
        not np.allclose(a.corner, b.corner) for a, b in zip(moved[2::4], default[2::4])
    )
    config = SynthConfig(
        camera="uniform", movers=("smooth",), frames=3, width=96, height=72, supersample=1,
        world_seed=5,
    )  # fmt: skip
    info = synth.write_sequence(config, tmp_path)
    assert info["world_seed"] == 5
    from motiondetect.constraint_ray.egomotion import EgoMotion

    assert 0.95 * 2.8 - 1e-3 <= EgoMotion.load(tmp_path / "scene.json").min_depth <= 4.0
