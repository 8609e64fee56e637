"""Shared fixtures: exact synthetic motion, a short panning clip with a mover,
and the location of real clips."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest
from skimage import data

from .cli_outputs import write_video
from .scenes import scene

#: The real clips: $MOTIONDETECT_DATA, else ../shared/data beside the checkout.
SHARED_DATA = Path(
    os.environ.get("MOTIONDETECT_DATA") or Path(__file__).resolve().parents[2] / "shared" / "data"
)


def fourier_shift(image: np.ndarray, dx: float, dy: float) -> np.ndarray:
    """Translate ``image`` by (dx, dy) px exactly (band-limited, periodic)."""
    f = np.fft.fft2(image.astype(np.float64))
    ky = np.fft.fftfreq(image.shape[0])[:, None]
    kx = np.fft.fftfreq(image.shape[1])[None, :]
    return np.real(np.fft.ifft2(f * np.exp(-2j * np.pi * (kx * dx + ky * dy))))


def as_uint8(image: np.ndarray) -> np.ndarray:
    return np.clip(np.rint(image), 0, 255).astype(np.uint8)


@pytest.fixture(scope="session")
def photo() -> np.ndarray:
    """A real 512x512 grey photograph (skimage's astronaut, green channel)."""
    return data.astronaut()[..., 1].copy()


def shared_path(*parts: str) -> Path:
    """A path under ../shared/data, skipping the test when it is absent."""
    path = SHARED_DATA.joinpath(*parts)
    if not path.exists():
        pytest.skip(f"real data not present: {path}")
    return path


@pytest.fixture(scope="session")
def clip_frames():
    """16 frames of a panning camera with a smooth mover (exact ground truth)."""
    return [fr.image for fr in scene("pan", ("smooth",), frames=16)]


@pytest.fixture(scope="session")
def clip(tmp_path_factory, clip_frames) -> Path:
    return write_video(tmp_path_factory.mktemp("clip") / "pan.mp4", clip_frames)
