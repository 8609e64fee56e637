"""Known ego-motion: exact constraint rays from camera poses or IMU rates.

File format (JSON, documented in docs/egomotion.md)::

    {
      "format": "motiondetect-egomotion", "version": 1,
      "convention": "opencv",            # or "opengl" (= NeRF: y up, z backwards)
      "intrinsics": {"width": W, "height": H, "fx": .., "fy": .., "cx": .., "cy": ..},
      "min_depth": 2.0,                  # optional: nearest scene depth, pose units
      "frames": [
        {"frame": 0, "camera_to_world": [[4x4]]},                  # a pose, or
        {"frame": 1, "rotation_rad": [wx, wy, wz], "translation": [tx, ty, tz]}
      ]
    }

A relative entry gives the motion from frame t-1 to t in the camera axes of
frame t-1 (what an IMU integrates to). ``motiondetect synth`` writes this
format; NeRF/instant-ngp ``transforms.json`` files are read as they are, with
frames matched by the number in their file names.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from motiondetect.constraint_ray.observer_motion import UNBOUNDED, ObserverMotion
from motiondetect.io.files import last_number
from motiondetect.measurement.normal_flow import GridGeometry

FORMAT = "motiondetect-egomotion"
_GL_TO_CV = np.diag([1.0, -1.0, -1.0])


class EgoMotionError(ValueError):
    """The ego-motion file cannot be used."""


@dataclass(frozen=True)
class Intrinsics:
    width: float
    height: float
    fx: float
    fy: float
    cx: float
    cy: float

    @property
    def matrix(self) -> np.ndarray:
        return np.array([[self.fx, 0, self.cx], [0, self.fy, self.cy], [0, 0, 1.0]])


class EgoMotion:
    """Per-frame relative camera motion; call it to get a constraint model.

    Parameters
    ----------
    intrinsics : Intrinsics
    relative : dict[int, (R, t)]
        For frame t, the rotation (3, 3) and translation (3,) taking points
        from camera t-1 coordinates to camera t coordinates (OpenCV axes).
    min_depth : float or None
    """

    def __init__(self, intrinsics: Intrinsics, relative: dict, min_depth: float | None) -> None:
        self.intrinsics = intrinsics
        self.relative = relative
        self.min_depth = min_depth

    # -- loading -----------------------------------------------------------

    @classmethod
    def load(cls, path: str | Path, frame_numbers: list[int] | None = None) -> EgoMotion:
        """Read an ego-motion file.

        ``frame_numbers`` are the numbers in the input's frame file names, in
        processing order (for matching NeRF ``file_path`` entries).
        """
        try:
            doc = json.loads(Path(path).read_text(encoding="utf-8"))
        except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
            raise EgoMotionError(f"cannot read ego-motion file {path}: {exc}") from exc
        try:
            if "fl_x" in doc or "camera_angle_x" in doc:
                return cls._from_nerf(doc, frame_numbers)
            return cls._from_native(doc)
        except (KeyError, TypeError, ValueError, IndexError) as exc:
            raise EgoMotionError(f"ego-motion file {path} is malformed: {exc}") from exc

    @classmethod
    def _from_native(cls, doc: dict) -> EgoMotion:
        if doc.get("format") != FORMAT:
            raise ValueError(f"'format' must be {FORMAT!r}")
        intr = Intrinsics(**{k: float(doc["intrinsics"][k]) for k in Intrinsics.__annotations__})
        flip = _GL_TO_CV if doc.get("convention", "opencv") in ("opengl", "nerf") else np.eye(3)
        poses, relative = {}, {}
        for entry in doc["frames"]:
            index = int(entry["frame"])
            if "camera_to_world" in entry:
                poses[index] = np.asarray(entry["camera_to_world"], float).reshape(4, 4)
            else:
                rvec = np.asarray(entry["rotation_rad"], float).reshape(3)
                rot, _ = cv2.Rodrigues(rvec)
                relative[index] = (rot, np.asarray(entry["translation"], float).reshape(3))
        relative.update(_relative_from_poses(poses, flip))
        min_depth = doc.get("min_depth")
        return cls(intr, relative, float(min_depth) if min_depth else None)

    @classmethod
    def _from_nerf(cls, doc: dict, frame_numbers: list[int] | None) -> EgoMotion:
        w, h = float(doc["w"]), float(doc["h"])
        fx = float(doc.get("fl_x") or 0.5 * w / np.tan(0.5 * doc["camera_angle_x"]))
        fy = float(doc.get("fl_y") or fx)
        intr = Intrinsics(w, h, fx, fy, float(doc.get("cx", w / 2)), float(doc.get("cy", h / 2)))
        by_number = {}
        for entry in doc["frames"]:
            number = last_number(entry["file_path"])
            if number is not None:
                by_number[number] = np.asarray(entry["transform_matrix"], float).reshape(4, 4)
        numbers = frame_numbers if frame_numbers is not None else sorted(by_number)
        poses = {i: by_number[n] for i, n in enumerate(numbers) if n in by_number}
        return cls(intr, _relative_from_poses(poses, _GL_TO_CV), None)

    # -- use ---------------------------------------------------------------

    def __call__(
        self, frame_index: int, geometry: GridGeometry, since: int | None = None
    ) -> ObserverMotion | None:
        """The exact constraint model for the motion from frame ``since``
        (by default ``frame_index - 1``) to ``frame_index``: over a gap (a
        frame file skipped as unreadable, a repeated frame) the steps are
        composed (:meth:`spanning`). None where a step is unknown."""
        motion = self.spanning(frame_index - 1 if since is None else since, frame_index)
        if motion is None:
            return None
        rotation, translation = motion
        v_w, v_xy = self.flow_basis(rotation, translation, geometry)
        bound = 1.0 / self.min_depth if self.min_depth else UNBOUNDED
        params = {
            "rotation_deg": round(float(np.degrees(np.linalg.norm(cv2.Rodrigues(rotation)[0]))), 4),
            "translation": [round(float(v), 5) for v in translation],
            "min_depth": self.min_depth,
        }
        return ObserverMotion(6, params, 1.0, v_w, v_xy, bound)

    def spanning(self, first: int, last: int) -> tuple[np.ndarray, np.ndarray] | None:
        """(R, t) taking frame ``first``'s camera coordinates to frame
        ``last``'s (``x_last = R x_first + t``), the steps between composed;
        None when ``last`` is not after ``first`` or a step is unknown."""
        if last <= first:
            return None
        rotation, translation = np.eye(3), np.zeros(3)
        for index in range(first + 1, last + 1):
            step = self.relative.get(index)
            if step is None:
                return None
            rotation, translation = step[0] @ rotation, step[0] @ translation + step[1]
        return rotation, translation

    def flow_basis(
        self, rotation: np.ndarray, translation: np.ndarray, geometry: GridGeometry
    ) -> tuple[np.ndarray, np.ndarray]:
        """``V_w`` and ``V_XY`` at every cell centre, work px/frame.

        A point at depth Z on the ray r = K^-1 p moves to the projection of
        ``R r + t / Z``: rotation alone gives ``V_w``; the derivative in
        ``s = 1/Z`` gives ``V_XY`` (the paper's first-order model).
        """
        intr = self.intrinsics
        sx = geometry.input_size[0] / intr.width
        sy = geometry.input_size[1] / intr.height
        kx, ky = (
            geometry.work_size[0] / geometry.input_size[0],
            geometry.work_size[1] / geometry.input_size[1],
        )
        x, y = geometry.cell_centres_px()
        px = x / kx / sx  # intrinsics pixels
        py = y / ky / sy
        ray = np.stack([(px - intr.cx) / intr.fx, (py - intr.cy) / intr.fy, np.ones_like(px)], -1)
        q = ray @ rotation.T
        qz = np.where(np.abs(q[..., 2]) < 1e-6, 1e-6, q[..., 2])
        proj_x = intr.fx * q[..., 0] / qz + intr.cx
        proj_y = intr.fy * q[..., 1] / qz + intr.cy
        tx, ty, tz = translation
        dx = intr.fx * (tx * qz - q[..., 0] * tz) / qz**2
        dy = intr.fy * (ty * qz - q[..., 1] * tz) / qz**2
        to_work = np.array([sx * kx, sy * ky])
        v_w = np.stack([proj_x - px, proj_y - py], -1) * to_work
        v_xy = np.stack([dx, dy], -1) * to_work
        return v_w.astype(np.float32), v_xy.astype(np.float32)


def known_motion(egomotion, field, frame_index: int) -> ObserverMotion | None:
    """``egomotion``'s model over the frames ``field`` spans: from its
    ``since`` (the frame it was measured from) to ``frame_index``.
    ``since`` is passed only across a gap, so any callable taking
    ``(frame_index, geometry)`` serves where frames follow one another."""
    since = getattr(field, "since", None)
    if since is None or since == frame_index - 1:
        return egomotion(frame_index, field.geometry)
    return egomotion(frame_index, field.geometry, since=since)


def _relative_from_poses(poses: dict[int, np.ndarray], flip: np.ndarray) -> dict:
    """Relative (R, t) for each frame whose predecessor also has a pose."""
    out = {}
    for index, current in poses.items():
        previous = poses.get(index - 1)
        if previous is None:
            continue
        # x_cur = F inv(T_cur) T_prev F x_prev, with F the axis flip.
        m = np.linalg.inv(current) @ previous
        rot = flip @ m[:3, :3] @ flip
        trans = flip @ m[:3, 3]
        out[index] = (rot, trans)
    return out


def write_egomotion(
    fp,
    intrinsics: Intrinsics,
    camera_to_world: list[np.ndarray],
    min_depth: float | None,
    extra: dict | None = None,
) -> None:
    """Write a native ego-motion document (OpenCV axes) to an open text file."""
    doc = {
        "format": FORMAT,
        "version": 1,
        "convention": "opencv",
        "intrinsics": {k: getattr(intrinsics, k) for k in Intrinsics.__annotations__},
        "min_depth": min_depth,
        "frames": [
            {"frame": i, "camera_to_world": np.round(pose, 9).tolist()}
            for i, pose in enumerate(camera_to_world)
        ],
    }
    if extra:
        doc.update(extra)
    json.dump(doc, fp, indent=1)
    fp.write("\n")
