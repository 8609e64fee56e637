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

from motiondetect.tools.scene import (  # noqa: F401 - the synthesizer's public names
    CAMERA_CLASS,
    CAMERAS,
    MIP_LEVELS,
    MOVERS,
    UNKNOWN_GT,
    Quad,
    SynthConfig,
    camera_pose,
    mover_quads,
    textures,
    world,
)


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


# ----------------------------------------------------------------------------
# Rendering
# ----------------------------------------------------------------------------


#: Pixels around a quad's projected box that are ray-cast too: np.gradient's
#: central differences at the quad's own pixels then match the whole frame's.
_WINDOW_MARGIN = 3


class Renderer:
    """Ray-casts quads through a pinhole camera with trilinear mip-mapping."""

    def __init__(self, config: SynthConfig) -> None:
        self.config = config
        self.textures = textures()
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
            window = self._window(quad, pose)
            if window is None:
                coords.append(None)
                continue
            a, b = self._intersect(quad, dirs[window], origin, best_t[window], best_q[window], qi)
            coords.append((window, a, b))
        image = np.zeros((*self.shape, 3), np.float32)
        owner = np.zeros(self.shape, np.uint8)
        for qi, quad in enumerate(quads):
            if coords[qi] is None:
                continue
            window, a, b = coords[qi]
            sel = best_q[window] == qi
            if not sel.any():
                continue
            image[window][sel] = self._sample(quad, a, b, sel)
            owner[window][sel] = quad.mover
        rigid = np.isfinite(best_t) & (owner == 0)
        nearest = float(best_t[rigid].min()) if rigid.any() else np.inf
        return image, owner, nearest

    @staticmethod
    def _intersect(quad, dirs, origin, best_t, best_q, qi):
        """Hit the quad's plane with ``dirs``; where it is the nearest so far,
        record depth and index in the views ``best_t``/``best_q``; return the
        plane coordinates (a, b) of every ray."""
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
        return a, b

    def _window(self, quad: Quad, pose: np.ndarray) -> tuple[slice, slice] | None:
        """The pixels (supersampled) a quad can cover: the box of its projected
        corners plus a margin that keeps :meth:`_sample`'s texel gradients
        those of the whole frame; the whole frame when a corner is behind the
        camera; None when the box misses the frame."""
        h, w = self.shape
        corners = quad.corner + np.array([[0, 0], [1, 0], [0, 1], [1, 1]]) @ np.stack(
            [quad.u, quad.v]
        )
        cam = (corners - pose[:3, 3]) @ pose[:3, :3]  # world to camera: R^T (X - o)
        if (cam[:, 2] <= 1e-3).any():
            return slice(0, h), slice(0, w)
        intr, ss = self.config.intrinsics, self.config.supersample
        cols = (cam[:, 0] / cam[:, 2] * intr.fx + intr.cx) * ss - 0.5  # inverse of self.rays
        rows = (cam[:, 1] / cam[:, 2] * intr.fy + intr.cy) * ss - 0.5
        m = _WINDOW_MARGIN
        x0, x1 = max(int(np.floor(cols.min())) - m, 0), min(int(np.ceil(cols.max())) + m + 1, w)
        y0, y1 = max(int(np.floor(rows.min())) - m, 0), min(int(np.ceil(rows.max())) + m + 1, h)
        if x0 >= x1 or y0 >= y1:
            return None
        return slice(y0, y1), slice(x0, x1)

    def _sample(self, quad: Quad, a: np.ndarray, b: np.ndarray, sel: np.ndarray) -> np.ndarray:
        levels = self.textures[quad.texture]
        u = (a * np.linalg.norm(quad.u) * quad.texels_per_m).astype(np.float32)
        v = (b * np.linalg.norm(quad.v) * quad.texels_per_m).astype(np.float32)
        # Texel footprint of one output pixel chooses the mip level.
        ss = self.config.supersample
        du = np.hypot(*np.gradient(u)) * ss
        dv = np.hypot(*np.gradient(v)) * ss
        lod = np.clip(np.log2(np.maximum(np.maximum(du, dv), 1e-6)), 0, MIP_LEVELS - 1.001)
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
    rigid = world(config.world_seed)
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


def smeared(image: np.ndarray, length: float, angle: float) -> np.ndarray:
    """A frame as a camera jolted during its exposure records it.

    Parameters
    ----------
    image : (H, W) or (H, W, C) ndarray of uint8
    length : float
        Length of the smear, px.
    angle : float
        Its direction, radians from the x axis.

    Returns
    -------
    ndarray of uint8, the shape of ``image``: averaged along that line.
    """
    size = int(np.ceil(length)) | 1
    kernel = np.zeros((size, size), np.float32)
    c, r = size // 2, length / 2
    dx, dy = r * np.cos(angle), r * np.sin(angle)
    cv2.line(kernel, (round(c - dx), round(c - dy)), (round(c + dx), round(c + dy)), 1.0, 1)
    return cv2.filter2D(image, -1, kernel / kernel.sum())


def write_sequence(config: SynthConfig, out_dir, *, video_name: str = "video.mp4") -> dict:
    """Render ``config`` to ``out_dir``: video, ``truth/`` masks and ``scene.json``.

    The scene file is in the ego-motion format (usable as ``--egomotion``)
    with the true nearest rigid depth as ``min_depth``.
    """
    from pathlib import Path

    from motiondetect.constraint_ray.egomotion import write_egomotion
    from motiondetect.io.report import atomic_text
    from motiondetect.io.video import VideoSink, write_image

    out = Path(out_dir)
    gt_dir = out / "truth"
    gt_dir.mkdir(parents=True, exist_ok=True)
    poses, nearest, movers = [], np.inf, []
    with VideoSink(out / video_name, config.fps, (config.width, config.height)) as sink:
        for frame in render_frames(config):
            sink.write(frame.image)
            write_image(gt_dir / f"{frame.index:06d}.png", frame.mask)
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
            "world_seed": config.world_seed,
            "speed": config.speed,
            "period_frames": config.period_frames,
            "jitter_deg": config.jitter_deg,
            "visible_mover_px": movers,
        }
    }
    with atomic_text(out / "scene.json") as fp:
        write_egomotion(fp, config.intrinsics, poses, round(0.95 * nearest, 4), extra)
    return extra["synth"]
