"""Run settings: one source for every setting and default.

* **Detector settings** are the fields of the frozen config dataclasses
  (:data:`SECTIONS`); their defaults are written there and nowhere else.
  A TOML file reaches every field through a section named after its
  config, e.g. ``[velocity_ray] floor_px = 1.2``.
* A few of them also have a **command-line option** (:data:`CONFIG_OPTIONS`);
  the option's default is the field's.
* **Run settings** (outputs, batch, events) are :data:`RUN_DEFAULTS`.

Command line and TOML go through the same :func:`make_settings`, so both get
the same range checks and the same one-line messages.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import typing
from dataclasses import dataclass
from pathlib import Path

try:
    import tomllib
except ModuleNotFoundError:  # pragma: no cover - Python 3.10
    import tomli as tomllib

from motiondetect.animate.normal_footprints import AnimateConfig
from motiondetect.animate.velocity_footprints import VelocityAnimateConfig
from motiondetect.app.times import TimeSpec, parse_time
from motiondetect.constraint_ray.fit_config import FitConfig
from motiondetect.constraint_ray.normal_filter import ConstraintRayConfig
from motiondetect.constraint_ray.velocity_filter import VelocityRayConfig
from motiondetect.detection.events import EventRules
from motiondetect.detection.objects import TrackConfig
from motiondetect.detection.streaming import AUTO, frames_to_skip
from motiondetect.measurement.dense_flow import DenseFlowConfig
from motiondetect.measurement.normal_flow import StageConfig

#: TOML section -> the config dataclass it builds.
SECTIONS: dict[str, type] = {
    "stages": StageConfig,
    "dense_flow": DenseFlowConfig,
    "fit": FitConfig,
    "constraint_ray": ConstraintRayConfig,
    "animate": AnimateConfig,
    "velocity_ray": VelocityRayConfig,
    "velocity_animate": VelocityAnimateConfig,
    "track": TrackConfig,
}

#: Options that set one config field: option -> (section, field). ``work_size``
#: sets the working size of whichever measurement ``measure`` chooses.
CONFIG_OPTIONS: dict[str, tuple[str, str]] = {
    "persistence": ("track", "persistence"),
    "focal_share": ("fit", "focal_share"),
    "rolling_shutter": ("fit", "line_gain"),
    "flow_preset": ("dense_flow", "preset"),
    "ego_model": ("constraint_ray", "ego_model"),
    "arithmetic": ("stages", "arithmetic"),
    "pyramid": ("stages", "pyramid"),
    "first_appearance": ("animate", "first_appearance"),
    "jitter_compensation": ("animate", "jitter_compensation"),
}
_WORK_SIZE = {"velocity": "dense_flow", "normal": "stages"}

#: Run settings and their defaults. Keys are the long option names, "_" for "-".
RUN_DEFAULTS: dict[str, object] = {
    "output": "motiondetect-out",
    "detector": "both",
    "measure": "velocity",
    "work_size": None,  # the chosen measurement's own default (see _WORK_SIZE)
    "masks": False,
    "video": True,
    "video_format": "mp4",
    "video_size": 512,
    "egomotion": None,
    "jobs": 1,
    "scheduler": None,  # "local" or "tcp://HOST:PORT": run the batch on Dask
    "overwrite": False,
    "recursive": False,
    "include": (),  # globs on paths relative to a scanned directory
    "exclude": (),
    "frames_fps": None,  # None: the video module's assumed rate, marked "assumed"
    "frame_skip": "auto",  # frames after each judged one that carry its result
    "min_event_frames": 3,
    "merge_gap_frames": 5,
    "pad_frames": 5,
    "min_event": None,  # a time (docs/cli.md); replaces min_event_frames when given
    "merge_gap": None,
    "pad": None,
    "start": None,
    "end": None,
    "thumbnails": False,
    "extract_clips": False,
    "clips_annotated": False,
    "roi": (),
    "roi_file": None,
    "min_area": 0,
    "timeline": True,
}

#: The checks of run settings: key -> (type, lowest, highest) or a tuple of choices.
RUN_CHECKS: dict[str, tuple] = {
    "detector": ("constraint-ray", "animate", "both"),
    "measure": ("velocity", "normal"),
    "video_format": ("mp4", "webm", "mkv"),
    "work_size": (int, 64, 4096),
    "video_size": (int, 64, 4096),
    "jobs": (int, 1, 64),
    "frames_fps": (float, 0.1, 1000.0),
    "frame_skip": (int, 0, None),
    "min_event_frames": (int, 0, None),
    "merge_gap_frames": (int, 0, None),
    "pad_frames": (int, 0, None),
    "min_area": (int, 0, None),
}
_FLAGS = ("masks", "video", "overwrite", "recursive", "extract_clips", "clips_annotated")
_FLAGS += ("timeline", "thumbnails")
_TIMES = ("min_event", "merge_gap", "pad", "start", "end")


class SettingsError(ValueError):
    """A setting or config file is wrong; the message is one line for the user."""


def default_of(key: str) -> object:
    """The default of a run setting or of an option that sets a config field."""
    if key in CONFIG_OPTIONS:
        section, name = CONFIG_OPTIONS[key]
        return SECTIONS[section].__dataclass_fields__[name].default
    if key == "work_size":
        return {m: default_of_field(s, "work_size") for m, s in _WORK_SIZE.items()}
    return RUN_DEFAULTS[key]


def default_of_field(section: str, name: str) -> object:
    return SECTIONS[section].__dataclass_fields__[name].default


def choices_of(key: str) -> tuple[str, ...]:
    """The allowed values of a run setting or of an option that sets a config
    field (from its ``Literal`` annotation)."""
    if key in CONFIG_OPTIONS:
        section, name = CONFIG_OPTIONS[key]
        return typing.get_args(typing.get_type_hints(SECTIONS[section])[name])
    return RUN_CHECKS[key]


@dataclass(frozen=True)
class Settings:
    """Everything one run needs; build it with :func:`make_settings`."""

    output: Path
    detector: str
    measure: str
    work_size: int | None
    masks: bool
    video: bool
    video_format: str
    video_size: int
    egomotion: Path | None
    jobs: int
    scheduler: str | None
    overwrite: bool
    recursive: bool
    include: tuple
    exclude: tuple
    frames_fps: float | None
    frame_skip: int | str  # "auto": from the input's frame rate (skipped_frames)
    min_event_frames: int
    merge_gap_frames: int
    pad_frames: int
    min_event: TimeSpec | None
    merge_gap: TimeSpec | None
    pad: TimeSpec | None
    start: TimeSpec | None
    end: TimeSpec | None
    thumbnails: bool
    extract_clips: bool
    clips_annotated: bool
    roi: tuple
    roi_file: Path | None
    min_area: int
    timeline: bool
    configs: dict  # section -> config instance

    @property
    def persistence(self) -> int:
        return self.configs["track"].persistence

    def event_rules(self, fps: float) -> EventRules:
        """Event rules in frames, with any time given converted at ``fps``.

        With ``frame_skip`` "auto", rules given in frames count judged
        frames (about 1/30 s apart), so that an input at 60 frames/s gets the
        events it would get at 30; with a number, they count input frames.
        """
        judged = self.skipped_frames(fps) + 1 if self.frame_skip == AUTO else 1

        def frames(spec: TimeSpec | None, fallback: int) -> int:
            return fallback * judged if spec is None else spec.frames(fps)

        return EventRules(
            max(1, frames(self.min_event, self.min_event_frames)),
            frames(self.merge_gap, self.merge_gap_frames),
            frames(self.pad, self.pad_frames),
        )

    def skipped_frames(self, fps: float | None) -> int:
        """Frames skipped after each judged one for an input at ``fps``:
        ``frame_skip``, or with "auto" one judged frame about every 1/30 s
        (:func:`~motiondetect.detection.streaming.auto_frame_skip`); known
        ego-motion, given frame to frame, judges every frame."""
        if self.frame_skip == AUTO and self.egomotion is not None:
            return 0
        return frames_to_skip(self.frame_skip, fps)

    def in_range(self, index: int, time_s: float) -> tuple[bool, bool]:
        """(before the start, past the end) for a frame."""
        before = self.start is not None and not self.start.reached(index, time_s)
        past = self.end is not None and self.end.passed(index, time_s)
        return before, past

    def detector_configs(self) -> tuple:
        """Every config the detector takes."""
        return tuple(self.configs.values())

    def result_hash(self) -> str:
        """A hash of every setting that changes an input's outputs (not where
        they go, how many jobs run, or which inputs a batch finds)."""
        batch = {"output", "jobs", "scheduler", "overwrite", "recursive", "include", "exclude"}
        doc = {k: v for k, v in self.to_json().items() if k not in batch}
        return hashlib.sha256(json.dumps(doc, sort_keys=True).encode()).hexdigest()[:16]

    def to_json(self) -> dict:
        out = {}
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            if f.name == "configs":
                value = {k: dataclasses.asdict(v) for k, v in value.items()}
            elif isinstance(value, (Path, TimeSpec)):
                value = str(value)
            elif isinstance(value, tuple):
                value = [list(v) if isinstance(v, tuple) else v for v in value]
            out[f.name] = value
        return out


def load_config_file(path: str | Path) -> dict:
    """Read a TOML config: run settings and flat options at the top (or under
    ``[motiondetect]``), config fields in sections named as in :data:`SECTIONS`."""
    try:
        with open(path, "rb") as fp:
            doc = tomllib.load(fp)
    except OSError as exc:
        raise SettingsError(f"cannot read config file {path}: {exc.strerror or exc}") from exc
    except tomllib.TOMLDecodeError as exc:
        raise SettingsError(f"config file {path} is not valid TOML: {exc}") from exc
    doc = doc.get("motiondetect", doc)
    out: dict = {}
    for key, value in doc.items():
        name = key.replace("-", "_")
        if name in SECTIONS:
            if not isinstance(value, dict):
                raise SettingsError(f"config file {path}: [{key}] must be a table")
            out[name] = {k.replace("-", "_"): v for k, v in value.items()}
        elif name in RUN_DEFAULTS or name in CONFIG_OPTIONS:
            out[name] = value
        else:
            raise SettingsError(f"config file {path}: unknown key {key!r}")
    return out


def parse_roi(value) -> tuple[int, int, int, int]:
    """``"x,y,w,h"`` (or a list of four) in input pixels, inside 0..2**31."""
    text = value if isinstance(value, str) else ",".join(str(v) for v in value)
    try:
        numbers = [float(v) for v in text.split(",")]
        if len(numbers) != 4 or not all(math.isfinite(v) and v == int(v) for v in numbers):
            raise ValueError
    except ValueError:
        raise SettingsError(f"--roi must be x,y,w,h in whole pixels, but got {text!r}") from None
    x, y, w, h = (int(v) for v in numbers)
    if w <= 0 or h <= 0 or x < 0 or y < 0 or max(x + w, y + h) > 2**31:
        raise SettingsError(f"--roi needs a positive width and height in range, but got {text!r}")
    return (x, y, w, h)


def _check_run(key: str, value):
    rule = RUN_CHECKS.get(key)
    flag = f"--{key.replace('_', '-')}"
    if key in _FLAGS and not isinstance(value, bool):
        raise SettingsError(f"{flag} must be true or false, but got {value!r}")
    if rule is None or value is None or (key == "frame_skip" and value == AUTO):
        return value
    if isinstance(rule[0], str):
        if value not in rule:
            raise SettingsError(f"{flag} must be one of {', '.join(rule)}, but got {value!r}")
        return value
    kind, lo, hi = rule
    number = value if isinstance(value, (int, float)) and not isinstance(value, bool) else None
    if number is None or (kind is int and number != int(number)) or not math.isfinite(number):
        what = "a whole" if kind is int else "a"
        what = f"{AUTO} or {what}" if key == "frame_skip" else what
        raise SettingsError(f"{flag} must be {what} number, got {value!r}")
    if number < lo or (hi is not None and number > hi):
        upper = f" and at most {hi}" if hi is not None else ""
        raise SettingsError(f"{flag} must be at least {lo}{upper}, but got {value!r}")
    return kind(number)


def _build_configs(values: dict, measure: str, work_size: int | None) -> dict:
    fields = {section: dict(values.get(section) or {}) for section in SECTIONS}
    for option, (section, name) in CONFIG_OPTIONS.items():
        if values.get(option) is not None:
            fields[section][name] = values[option]
    if work_size is not None:
        fields[_WORK_SIZE[measure]]["work_size"] = work_size
    configs = {}
    for section, cls in SECTIONS.items():
        hints = typing.get_type_hints(cls)
        for name, value in fields[section].items():
            if hints.get(name) is bool and not isinstance(value, bool):
                raise SettingsError(f"[{section}] {name} must be true or false, but got {value!r}")
        try:
            configs[section] = cls(**fields[section])
        except TypeError as exc:
            raise SettingsError(f"[{section}]: {exc}".replace("__init__() ", "")) from exc
        except ValueError as exc:
            raise SettingsError(f"{_option_naming(section, str(exc))}[{section}] {exc}") from exc
    return configs


def _option_naming(section: str, message: str) -> str:
    """``--option: `` for a config field's error when an option sets that
    field under another name (``--rolling-shutter`` sets ``[fit] line_gain``)."""
    field = message.split(" ", 1)[0]
    for option, target in CONFIG_OPTIONS.items():
        if target == (section, field) and option != field:
            return f"--{option.replace('_', '-')}: "
    return ""


def make_settings(values: dict) -> Settings:
    """Validate and build settings: defaults, overridden by ``values`` (None = unset)."""
    given = {k: v for k, v in values.items() if v is not None}
    unknown = set(given) - set(RUN_DEFAULTS) - set(CONFIG_OPTIONS) - set(SECTIONS)
    if unknown:
        raise SettingsError(f"unknown setting {sorted(unknown)[0]!r}")
    run = {**RUN_DEFAULTS, **{k: v for k, v in given.items() if k in RUN_DEFAULTS}}
    run = {k: _check_run(k, v) for k, v in run.items()}
    run["output"] = Path(run["output"])
    for key in ("egomotion", "roi_file"):
        if run[key] is not None:
            run[key] = Path(run[key])
    for key in _TIMES:
        if run[key] is not None:
            try:
                run[key] = parse_time(run[key], f"--{key.replace('_', '-')}")
            except ValueError as exc:
                raise SettingsError(str(exc)) from None
    if run["frame_skip"] not in (0, AUTO) and run["egomotion"] is not None:
        raise SettingsError(
            "--frame-skip cannot be combined with --egomotion (its motions are frame to frame)"
        )
    start, end = run["start"], run["end"]
    if start and end and start.unit == end.unit:
        # An end frame is included (10f to 10f is that frame); an end time is not.
        empty = end.value < start.value if end.unit == "f" else end.value <= start.value
        if empty:
            raise SettingsError(f"--end ({end}) must come after --start ({start})")
    for key in ("include", "exclude"):
        globs = (run[key],) if isinstance(run[key], str) else run[key]
        if not all(isinstance(g, str) and g for g in globs):
            raise SettingsError(f"--{key} takes glob patterns, but got {run[key]!r}")
        run[key] = tuple(globs)
    scheduler = run["scheduler"]
    if scheduler is not None and not (
        scheduler == "local" or (isinstance(scheduler, str) and "://" in scheduler)
    ):
        raise SettingsError(f"--scheduler must be local or tcp://HOST:PORT, but got {scheduler!r}")
    rois = run["roi"]
    run["roi"] = tuple(parse_roi(r) for r in ((rois,) if isinstance(rois, str) else rois))
    configs = _build_configs(given, run["measure"], run["work_size"])
    return Settings(**run, configs=configs)
