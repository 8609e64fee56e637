"""A moving-observer scene synthesizer with exact ground truth.

A rigid 3-D world of textured planar quads (a far wall, a ground plane,
boxes, and a post close to the camera for strong parallax) is ray-cast
through a moving pinhole camera. Textures are real photographs bundled with
scikit-image, sampled through a mip-map with trilinear filtering (and
optional supersampling) so the rigid world does not shimmer.

Independent movers are textured billboards with their own trajectories:
``smooth`` (constant velocity, off the constraint ray), ``on-ray`` (moving
along the background flow, the paper's blind spot), ``animate`` (oscillating,
a reversal every ``period / 2`` frames) and ``emerging`` (smooth, starting
behind an occluder).

Axes are OpenCV's: x right, y down, z forward; units are metres.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field

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
_MIP_LEVELS = 7


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


@dataclass(frozen=True)
class Frame:
    """One rendered frame with its ground truth."""

    index: int
    image: np.ndarray  # (H, W, 3) uint8 BGR
    mask: np.ndarray  # (H, W) uint8: 0 static, 255 moving, 170 unknown border
    movers: np.ndarray  # (H, W) uint8 mover id (0 = rigid world)
    camera_to_world: np.ndarray  # (4, 4)
    visible: dict = field(default_factory=dict)  # mover id -> pixel count
    nearest_rigid_m: float = np.inf  # nearest depth of the rigid world in view


def _rot_y(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def _rot_x(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def _textures() -> list[list[np.ndarray]]:
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
        for _ in range(_MIP_LEVELS - 1):
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


def world() -> list[Quad]:
    """The rigid scene: wall at 25 m, ground, three boxes and a near post."""
    p = np.array
    quads = [
        Quad(p([-40.0, -20.0, 25.0]), p([80.0, 0, 0]), p([0, 20.0 + GROUND_Y, 0]), 0, 40.0),
        Quad(p([-40.0, GROUND_Y, 0.3]), p([80.0, 0, 0]), p([0, 0, 24.7]), 1, 60.0),
    ]
    quads += _box(-3.0, 11.0, (2.5, 2.5, 2.0), 7, 150.0)
    quads += _box(3.5, 8.0, (2.0, 3.0, 1.5), 6, 150.0)
    quads += _box(0.8, 14.0, (1.6, 1.8, 1.6), 4, 150.0)
    quads += _box(-1.3, 3.2, (0.35, 3.5, 0.35), 2, 300.0)  # the near post: strong parallax
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


# ----------------------------------------------------------------------------
# Rendering
# ----------------------------------------------------------------------------


class Renderer:
    """Ray-casts quads through a pinhole camera with trilinear mip-mapping."""

    def __init__(self, config: SynthConfig) -> None:
        self.config = config
        self.textures = _textures()
        ss = config.supersample
        intr = config.intrinsics
        w, h = config.width * ss, config.height * ss
        xs = (np.arange(w) + 0.5) / ss - 0.5
        ys = (np.arange(h) + 0.5) / ss - 0.5
        px, py = np.meshgrid(xs, ys)
        self.rays = np.stack(
            [(px - intr.cx + 0.5) / intr.fx, (py - intr.cy + 0.5) / intr.fy, np.ones_like(px)], -1
        )
        self.shape = (h, w)

    def render(self, quads: list[Quad], pose: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
        """Colour (h, w, 3) float32, owner mover id (h, w) at supersampled size,
        and the nearest depth of the rigid world in view (m)."""
        dirs = self.rays @ pose[:3, :3].T
        origin = pose[:3, 3]
        best_t = np.full(self.shape, np.inf)
        best_q = np.full(self.shape, -1, np.int32)
        coords = []
        for qi, quad in enumerate(quads):
            normal = np.cross(quad.u, quad.v)
            denom = dirs @ normal
            with np.errstate(divide="ignore", invalid="ignore"):
                t = ((quad.corner - origin) @ normal) / denom
            hit = origin + dirs * t[..., None]
            rel = hit - quad.corner
            a = rel @ quad.u / (quad.u @ quad.u)
            b = rel @ quad.v / (quad.v @ quad.v)
            inside = (t > 1e-3) & (a >= 0) & (a <= 1) & (b >= 0) & (b <= 1) & (t < best_t)
            best_t[inside] = t[inside]
            best_q[inside] = qi
            coords.append((a, b))
        image = np.zeros((*self.shape, 3), np.float32)
        owner = np.zeros(self.shape, np.uint8)
        for qi, quad in enumerate(quads):
            sel = best_q == qi
            if not sel.any():
                continue
            a, b = coords[qi]
            image[sel] = self._sample(quad, a, b, sel)
            owner[sel] = quad.mover
        rigid = np.isfinite(best_t) & (owner == 0)
        nearest = float(best_t[rigid].min()) if rigid.any() else np.inf
        return image, owner, nearest

    def _sample(self, quad: Quad, a: np.ndarray, b: np.ndarray, sel: np.ndarray) -> np.ndarray:
        levels = self.textures[quad.texture]
        u = (a * np.linalg.norm(quad.u) * quad.texels_per_m).astype(np.float32)
        v = (b * np.linalg.norm(quad.v) * quad.texels_per_m).astype(np.float32)
        # Texel footprint of one output pixel chooses the mip level.
        ss = self.config.supersample
        du = np.hypot(*np.gradient(u)) * ss
        dv = np.hypot(*np.gradient(v)) * ss
        lod = np.clip(np.log2(np.maximum(np.maximum(du, dv), 1e-6)), 0, _MIP_LEVELS - 1.001)
        u, v, lod = u[sel], v[sel], lod[sel]
        out = np.empty((u.size, 3), np.float32)
        base = np.floor(lod).astype(int)
        for level in np.unique(base):
            pick = base == level
            frac = (lod[pick] - level)[:, None]
            lo = self._fetch(levels[level], u[pick] / 2**level, v[pick] / 2**level)
            hi = self._fetch(
                levels[level + 1], u[pick] / 2 ** (level + 1), v[pick] / 2 ** (level + 1)
            )
            out[pick] = (1 - frac) * lo + frac * hi
        return out

    @staticmethod
    def _fetch(texture: np.ndarray, u: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Bilinear samples at texel coords (u, v), the texture mirrored to tile the plane."""
        h, w = texture.shape[:2]
        coords = []
        for c, size in ((u, w), (v, h)):
            c = np.mod(c.astype(np.float64), 2 * size)
            coords.append(np.where(c > size, 2 * size - c, c) - 0.5)
        n = u.size
        width = 1024
        rows = -(-n // width)
        maps = [np.zeros(rows * width, np.float32) for _ in range(2)]
        for m, c in zip(maps, coords):
            m[:n] = c
        out = cv2.remap(
            texture,
            maps[0].reshape(rows, width),
            maps[1].reshape(rows, width),
            cv2.INTER_LINEAR,
            borderMode=cv2.BORDER_REFLECT_101,
        )
        return out.reshape(-1, 3)[:n]


def ground_truth(
    owner: np.ndarray, supersample: int, size: tuple[int, int]
) -> tuple[np.ndarray, np.ndarray]:
    """CDnet mask and per-pixel mover id at output size from supersampled owners."""
    moving = (owner > 0).astype(np.float32)
    cover = cv2.resize(moving, size, interpolation=cv2.INTER_AREA) if supersample > 1 else moving
    ids = owner[supersample // 2 :: supersample, supersample // 2 :: supersample]
    mask = np.where(cover >= 0.5, 255, 0).astype(np.uint8)
    kernel = np.ones((3, 3), np.uint8)
    band = (cv2.dilate(mask, kernel) != cv2.erode(mask, kernel)) | ((cover > 0) & (cover < 1))
    mask[band] = UNKNOWN_GT
    return mask, ids


def render_frames(config: SynthConfig) -> Iterator[Frame]:
    """Render the scene frame by frame (constant memory in length)."""
    rng = np.random.default_rng(config.seed)
    noise_rng = np.random.default_rng(config.seed + 1)
    renderer = Renderer(config)
    rigid = world()
    size = (config.width, config.height)
    for t in range(config.frames):
        pose = camera_pose(config, t, rng)
        image, owner, nearest = renderer.render(rigid + mover_quads(config, t), pose)
        if config.supersample > 1:
            image = cv2.resize(image, size, interpolation=cv2.INTER_AREA)
        if config.noise_grey > 0:
            image = image + noise_rng.normal(0, config.noise_grey, image.shape).astype(np.float32)
        mask, ids = ground_truth(owner, config.supersample, size)
        visible = {int(i): int((ids == i).sum()) for i in np.unique(ids) if i}
        image = np.clip(np.rint(image), 0, 255).astype(np.uint8)
        yield Frame(t, image, mask, ids, pose, visible, nearest)


def write_sequence(config: SynthConfig, out_dir, *, video_name: str = "video.mp4") -> dict:
    """Render ``config`` to ``out_dir``: video, ``truth/`` masks and ``scene.json``.

    The scene file is in the ego-motion format (usable as ``--egomotion``)
    with the true nearest rigid depth as ``min_depth``.
    """
    from pathlib import Path

    from motiondetect.constraint_ray.egomotion import write_egomotion
    from motiondetect.io.report import atomic_text
    from motiondetect.io.video import VideoSink, write_png

    out = Path(out_dir)
    gt_dir = out / "truth"
    gt_dir.mkdir(parents=True, exist_ok=True)
    poses, nearest, movers = [], np.inf, []
    with VideoSink(out / video_name, config.fps, (config.width, config.height)) as sink:
        for frame in render_frames(config):
            sink.write(frame.image)
            write_png(gt_dir / f"{frame.index:06d}.png", frame.mask)
            poses.append(frame.camera_to_world)
            nearest = min(nearest, frame.nearest_rigid_m)
            movers.append({str(k): v for k, v in frame.visible.items()})
    extra = {
        "synth": {
            "camera": config.camera,
            "movers": list(config.movers),
            "paper_class": CAMERA_CLASS[config.camera],
            "frames": config.frames,
            "fps": config.fps,
            "noise_grey": config.noise_grey,
            "seed": config.seed,
            "speed": config.speed,
            "period_frames": config.period_frames,
            "jitter_deg": config.jitter_deg,
            "visible_mover_px": movers,
        }
    }
    with atomic_text(out / "scene.json") as fp:
        write_egomotion(fp, config.intrinsics, poses, round(0.95 * nearest, 4), extra)
    return extra["synth"]
