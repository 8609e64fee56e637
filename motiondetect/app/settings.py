"""Run settings: one table of defaults, read by the CLI and by TOML config files."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path

try:
    import tomllib
except ModuleNotFoundError:  # pragma: no cover - Python 3.10
    import tomli as tomllib

from motiondetect.animate.normal_footprints import AnimateConfig
from motiondetect.constraint_ray.normal_filter import ConstraintRayConfig
from motiondetect.measurement.normal_flow import StageConfig

#: The defaults, one place. Keys are the long option names with "_" for "-".
DEFAULTS: dict[str, object] = {
    "output": "motiondetect-out",
    "detector": "both",
    "measure": "velocity",
    "persistence": 2,
    "masks": False,
    "video": True,
    "video_format": "webm",
    "work_size": 512,
    "egomotion": None,
    "jobs": 1,
    "overwrite": False,
    "recursive": False,
    "frames_fps": 30.0,
    "ego_model": "fitted",
    "arithmetic": "float",
    "pyramid": True,
    "first_appearance": "ignore",
    "jitter_compensation": True,
    "min_event_frames": 3,
    "merge_gap_frames": 5,
    "pad_frames": 5,
    "extract_clips": False,
    "clips_annotated": False,
    "roi": (),
    "roi_file": None,
    "min_area": 0,
    "timeline": True,
}


class SettingsError(ValueError):
    """A setting or config file is wrong; the message is one line for the user."""


@dataclass(frozen=True)
class Settings:
    """Everything one run needs. Build it with :func:`make_settings`, which fills
    every field from :data:`DEFAULTS` (the one table of defaults)."""

    output: Path
    detector: str
    measure: str
    persistence: int
    masks: bool
    video: bool
    video_format: str
    work_size: int
    egomotion: Path | None
    jobs: int
    overwrite: bool
    recursive: bool
    frames_fps: float
    ego_model: str
    arithmetic: str
    pyramid: bool
    first_appearance: str
    jitter_compensation: bool
    min_event_frames: int
    merge_gap_frames: int
    pad_frames: int
    extract_clips: bool
    clips_annotated: bool
    roi: tuple
    roi_file: Path | None
    min_area: int
    timeline: bool
    extra: dict = field(default_factory=dict)

    def stage_config(self) -> StageConfig:
        return StageConfig(
            work_size=self.work_size, arithmetic=self.arithmetic, pyramid=self.pyramid
        )

    def constraint_ray_config(self) -> ConstraintRayConfig:
        return ConstraintRayConfig(ego_model=self.ego_model)

    def animate_config(self) -> AnimateConfig:
        return AnimateConfig(
            first_appearance=self.first_appearance, jitter_compensation=self.jitter_compensation
        )

    def detector_configs(self) -> tuple:
        """Every config the detector takes, built from these settings."""
        return (self.stage_config(), self.constraint_ray_config(), self.animate_config())

    def to_json(self) -> dict:
        out = {}
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            if isinstance(value, Path):
                value = str(value)
            elif isinstance(value, tuple):
                value = [list(v) if isinstance(v, tuple) else v for v in value]
            out[f.name] = value
        return out


def load_config_file(path: str | Path) -> dict:
    """Read a TOML config whose keys are the option names (``-`` or ``_``)."""
    try:
        with open(path, "rb") as fp:
            doc = tomllib.load(fp)
    except OSError as exc:
        raise SettingsError(f"cannot read config file {path}: {exc.strerror or exc}") from exc
    except tomllib.TOMLDecodeError as exc:
        raise SettingsError(f"config file {path} is not valid TOML: {exc}") from exc
    doc = doc.get("motiondetect", doc)
    out = {}
    for key, value in doc.items():
        name = key.replace("-", "_")
        if name not in DEFAULTS:
            raise SettingsError(f"config file {path}: unknown key {key!r}")
        out[name] = value
    return out


def parse_roi(text: str) -> tuple[int, int, int, int]:
    try:
        x, y, w, h = (int(v) for v in text.split(","))
    except ValueError:
        raise SettingsError(f"--roi must be x,y,w,h in pixels, but got {text!r}") from None
    if w <= 0 or h <= 0 or x < 0 or y < 0:
        raise SettingsError(f"--roi needs a positive width and height, but got {text!r}")
    return (x, y, w, h)


def make_settings(values: dict) -> Settings:
    """Validate and build settings from DEFAULTS overridden by ``values``."""
    merged = {**DEFAULTS, **{k: v for k, v in values.items() if v is not None}}
    merged["output"] = Path(merged["output"])
    for key in ("egomotion", "roi_file"):
        if merged[key] is not None:
            merged[key] = Path(merged[key])
    rois = merged["roi"]
    merged["roi"] = tuple(parse_roi(r) if isinstance(r, str) else tuple(r) for r in rois)
    if merged["measure"] not in ("velocity", "normal"):
        raise SettingsError(f"--measure must be velocity or normal, but got {merged['measure']!r}")
    if merged["video_format"] not in ("webm", "mp4"):
        raise SettingsError(
            f"--video-format must be webm or mp4, but got {merged['video_format']!r}"
        )
    if merged["persistence"] < 1:
        raise SettingsError(f"--persistence must be at least 1, but got {merged['persistence']}")
    if merged["jobs"] < 1:
        raise SettingsError(f"--jobs must be at least 1, but got {merged['jobs']}")
    for key in ("min_event_frames", "merge_gap_frames", "pad_frames", "min_area"):
        if merged[key] < 0:
            raise SettingsError(f"--{key.replace('_', '-')} must not be negative")
    try:
        settings = Settings(**merged)
        settings.stage_config()
        settings.constraint_ray_config()
        settings.animate_config()
    except (TypeError, ValueError) as exc:
        raise SettingsError(str(exc)) from exc
    return settings
