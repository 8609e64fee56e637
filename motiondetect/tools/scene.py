"""The synthesizer's world: a rigid 3-D scene, the camera's and the movers' paths.

A rigid world of textured planar quads (a far wall, a ground plane, boxes,
and a post close to the camera for strong parallax); independent movers are
textured billboards with their own trajectories (see :mod:`.synth`). Axes
are OpenCV's: x right, y down, z forward; units are metres.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from skimage import data as skdata

from motiondetect.constraint_ray.egomotion import Intrinsics

CAMERAS = (
    "static",
    "uniform",
    "pan",
    "forward",
    "oblique",
    "forward-yaw",
    "fixation",
    "jitter",
)
#: The paper's class that each camera preset produces (0 = static observer).
CAMERA_CLASS = {
    "static": 0,
    "uniform": 1,
    "pan": 1,
    "forward": 2,
    "oblique": 3,
    "forward-yaw": 4,
    "fixation": 5,
    "jitter": 1,
}
MOVERS = ("smooth", "on-ray", "animate", "emerging")
GROUND_Y = 1.5
UNKNOWN_GT = 170
MIP_LEVELS = 7


@dataclass(frozen=True)
class SynthConfig:
    """What to render.

    Attributes
    ----------
    camera : str
        One of :data:`CAMERAS`.
    movers : tuple of str
        Any of :data:`MOVERS`.
    width, height, frames : int
    fps : float
    hfov_deg : float
        Horizontal field of view.
    noise_grey : float
        Standard deviation of Gaussian sensor noise, grey levels.
    supersample : int
        Rays per pixel per axis.
    speed : float
        Scales every camera and mover speed.
    period_frames : int
        Oscillation period of ``animate`` movers (a reversal every half).
    jitter_deg : float
        Per-frame rotational jitter (standard deviation), for ``jitter`` or
        added to any camera when ``jitter_deg > 0``.
    seed : int
        Of the sensor noise and the jitter.
    world_seed : int
        The layout of the rigid world (:func:`world`); 0: the samples' world.
    """

    camera: str = "uniform"
    movers: tuple[str, ...] = ("smooth",)
    width: int = 320
    height: int = 240
    frames: int = 60
    fps: float = 30.0
    hfov_deg: float = 40.0
    noise_grey: float = 1.0
    supersample: int = 2
    speed: float = 1.0
    period_frames: int = 20
    jitter_deg: float = 0.0
    seed: int = 0
    world_seed: int = 0

    def __post_init__(self) -> None:
        if self.camera not in CAMERAS:
            raise ValueError(f"camera must be one of {CAMERAS}, but got {self.camera!r}")
        for mover in self.movers:
            if mover not in MOVERS:
                raise ValueError(f"movers must be among {MOVERS}, but got {mover!r}")
        if self.width < 64 or self.height < 64:
            raise ValueError(
                f"width and height must be at least 64, but got {self.width}x{self.height}"
            )
        if self.frames < 2:
            raise ValueError(f"frames must be at least 2, but got {self.frames}")
        if self.supersample < 1:
            raise ValueError(f"supersample must be at least 1, but got {self.supersample}")
        if self.world_seed < 0:
            raise ValueError(f"world_seed must not be negative, but got {self.world_seed}")

    @property
    def intrinsics(self) -> Intrinsics:
        f = 0.5 * self.width / np.tan(np.deg2rad(self.hfov_deg) / 2)
        return Intrinsics(self.width, self.height, f, f, self.width / 2, self.height / 2)


@dataclass
class Quad:
    """A textured parallelogram: corner + s*u + t*v, s and t in [0, 1]."""

    corner: np.ndarray
    u: np.ndarray
    v: np.ndarray
    texture: int
    texels_per_m: float
    mover: int = 0  # 0 for the rigid world


def _rot_y(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def _rot_x(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def textures() -> list[list[np.ndarray]]:
    """Mip-maps of the bundled photographs (BGR float32)."""
    images = [
        skdata.brick(),
        skdata.gravel(),
        skdata.grass(),
        skdata.astronaut(),
        skdata.coffee(),
        skdata.chelsea(),
        skdata.rocket(),
        skdata.immunohistochemistry(),
    ]
    mips = []
    for img in images:
        if img.ndim == 2:
            img = np.repeat(img[..., None], 3, axis=2)
        level = np.ascontiguousarray(img[..., ::-1]).astype(np.float32)
        levels = [level]
        for _ in range(MIP_LEVELS - 1):
            level = cv2.pyrDown(level)
            levels.append(level)
        mips.append(levels)
    return mips


def _box(
    centre_x: float, depth: float, size: tuple[float, float, float], texture: int, density: float
) -> list[Quad]:
    """Front, sides and top of an axis-aligned box standing on the ground."""
    w, h, d = size
    x0, x1 = centre_x - w / 2, centre_x + w / 2
    y0, z0, z1 = GROUND_Y - h, depth, depth + d
    p = np.array
    return [
        Quad(p([x0, y0, z0]), p([w, 0, 0]), p([0, h, 0]), texture, density),
        Quad(p([x0, y0, z1]), p([0, 0, -d]), p([0, h, 0]), texture, density),
        Quad(p([x1, y0, z0]), p([0, 0, d]), p([0, h, 0]), texture, density),
        Quad(p([x0, y0, z1]), p([w, 0, 0]), p([0, 0, -d]), texture, density),
    ]


#: The default world's boxes: (centre x, depth, (width, height, depth), texture).
_BOXES = (
    (-3.0, 11.0, (2.5, 2.5, 2.0), 7),
    (3.5, 8.0, (2.0, 3.0, 1.5), 6),
    (0.8, 14.0, (1.6, 1.8, 1.6), 4),
)
#: The near post, for strong parallax.
_POST = (-1.3, 3.2, (0.35, 3.5, 0.35), 2)


def world(seed: int = 0) -> list[Quad]:
    """The rigid scene: wall at 25 m, ground, three boxes and a near post.

    ``seed`` 0 is the fixed world of the committed samples. Any other seed
    moves each box by up to 1.5 m across and scales its depth by 0.8-1.25 and
    its size by 0.75-1.3, gives the boxes other photographs, and moves the
    post by up to 0.5 m across and to 2.8-4 m away: the same kinds of
    surface and parallax, laid out anew.
    """
    p = np.array
    quads = [
        Quad(p([-40.0, -20.0, 25.0]), p([80.0, 0, 0]), p([0, 20.0 + GROUND_Y, 0]), 0, 40.0),
        Quad(p([-40.0, GROUND_Y, 0.3]), p([80.0, 0, 0]), p([0, 0, 24.7]), 1, 60.0),
    ]
    boxes, post = _BOXES, _POST
    if seed:
        rng = np.random.default_rng(seed)
        photos = rng.permutation([3, 4, 5, 6, 7])
        boxes = [
            (x + rng.uniform(-1.5, 1.5), z * rng.uniform(0.8, 1.25),
             tuple(v * rng.uniform(0.75, 1.3) for v in size), int(photos[i]))
            for i, (x, z, size, _) in enumerate(boxes)
        ]  # fmt: skip
        x, _, size, texture = post
        post = (x + rng.uniform(-0.5, 0.5), rng.uniform(2.8, 4.0), size, texture)
    for x, z, size, texture in boxes:
        quads += _box(x, z, size, texture, 150.0)
    x, z, size, texture = post
    quads += _box(x, z, size, texture, 300.0)
    return quads


# ----------------------------------------------------------------------------
# Trajectories
# ----------------------------------------------------------------------------


def camera_pose(config: SynthConfig, t: int, rng: np.random.Generator | None = None) -> np.ndarray:
    """Camera-to-world 4x4 (OpenCV axes) at frame t."""
    s = config.speed
    rot = np.eye(3)
    centre = np.zeros(3)
    cam = config.camera
    if cam == "uniform":
        centre = np.array([0.04 * s * t, 0, 0])
    elif cam in ("pan", "jitter"):
        rot = _rot_y(np.deg2rad(0.3 * s * t))
    elif cam == "forward":
        centre = np.array([0, 0, 0.08 * s * t])
    elif cam == "oblique":
        centre = np.array([0.02 * s * t, 0.006 * s * t, 0.08 * s * t])
    elif cam == "forward-yaw":
        centre = np.array([0, 0, 0.08 * s * t])
        rot = _rot_y(np.deg2rad(0.35 * s * t))
    elif cam == "fixation":
        centre = np.array([0.06 * s * t - 0.9, 0, 0])
        target = np.array([0.0, 0.0, 9.0])
        rot = _rot_y(np.arctan2(target[0] - centre[0], target[2] - centre[2]))
    jitter = config.jitter_deg if config.jitter_deg > 0 else (0.15 if cam == "jitter" else 0.0)
    if jitter and rng is not None and t > 0:
        a, b = rng.normal(0.0, np.deg2rad(jitter), 2)
        rot = rot @ _rot_y(a) @ _rot_x(b)
    pose = np.eye(4)
    pose[:3, :3], pose[:3, 3] = rot, centre
    return pose


def _aim_x(config: SynthConfig, depth: float) -> float:
    """World x where the optical axis crosses the plane z = depth, mid-sequence."""
    pose = camera_pose(config, config.frames // 2)
    axis, centre = pose[:3, 2], pose[:3, 3]
    if axis[2] < 0.1 or depth <= centre[2]:
        return float(centre[0])
    return float(centre[0] + axis[0] * (depth - centre[2]) / axis[2])


def mover_quads(config: SynthConfig, t: int) -> list[Quad]:
    """The independent movers at frame t, as billboards facing the camera."""
    s = config.speed
    quads = []
    for i, kind in enumerate(config.movers, start=1):
        depth = 6.0 + 1.5 * (i - 1)
        width, height = 0.9, 1.5
        top = GROUND_Y - height - 0.3  # floating a little: no contact ambiguity
        start_x = {1: -1.0, 2: 1.2, 3: -0.2, 4: 0.6}.get(i, 0.0)
        # Every moving preset drifts the background leftwards at the movers'
        # depth: "smooth" crosses it rightwards and downwards (off the ray),
        # "on-ray" moves leftwards, like a rigid point at about 4.8 m.
        if kind == "smooth":
            x = start_x + 0.04 * s * t
            y = top + 0.015 * s * t
        elif kind == "on-ray":
            x = start_x - 0.01 * s * t
            y = top
        elif kind == "animate":
            # Oscillates about the point the camera faces mid-sequence, so
            # that it stays in view while the camera moves.
            centre = _aim_x(config, depth) + 0.3 * start_x
            x = centre + 0.35 * np.sin(2 * np.pi * t / config.period_frames)
            y = top
        else:  # emerging: from behind the box at x=3.5, z=8 (its left edge at 2.5)
            depth = 9.8
            x = 3.9 - 0.035 * s * t
            y = GROUND_Y - height
        corner = np.array([x - width / 2, y, depth])
        quads.append(
            Quad(
                corner,
                np.array([width, 0, 0]),
                np.array([0, height, 0]),
                3 + (i % 3),
                300.0,
                mover=i,
            )
        )
    return quads
