"""docs/make_figures.py keeps drawing the documented views."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SAMPLE = ROOT / "sample_videos" / "handheld_emerging" / "video.mp4"


def _figures():
    spec = importlib.util.spec_from_file_location("make_figures", ROOT / "docs" / "make_figures.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_withheld_pixels_view_shows_only_the_normal_flow():
    """For clips whose pixels may not be redistributed: a grey canvas with
    the flow the detector saw as arrows (yellow fine level, blue coarse)."""
    out = _figures().detection_figure(SAMPLE, 6, "animate", withhold_pixels=True)
    assert out.shape[1] == 640
    arrows = np.all(out == (80, 220, 255), axis=2) | np.all(out == (255, 160, 60), axis=2)
    assert arrows.sum() > 500
    grey = np.all(out == 70, axis=2)
    assert grey.mean() > 0.5  # the footage itself is not there


def test_the_normal_path_figure_draws_its_coarse_field():
    """The paper's coarse 4x4 field (Figure 5, live) as white arrows on black."""
    figures = _figures()
    forward = ROOT / "sample_videos" / "forward_crossing" / "video.mp4"
    normal = figures.detection_figure(forward, 10, "constraint-ray", measure="normal")
    velocity = figures.detection_figure(forward, 10, "constraint-ray")  # no coarse field
    white = [np.all(img == 255, axis=2).sum() for img in (normal, velocity)]
    assert white[0] > 4 * white[1]  # measured 149 against 21 (the label's text)
