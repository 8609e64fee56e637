"""The house rules (issue 17): sizes, layers, and one source for settings."""

from __future__ import annotations

import ast
import dataclasses
import importlib
import re
from pathlib import Path

import click
import pytest
from click.testing import CliRunner
from motiondetect_cli.detect import detect
from motiondetect_cli.main import main

from motiondetect.app.settings import (
    CONFIG_OPTIONS,
    RUN_DEFAULTS,
    SECTIONS,
    SettingsError,
    load_config_file,
    make_settings,
)

ROOT = Path(__file__).resolve().parents[1]
SOURCES = sorted([*(ROOT / "motiondetect").rglob("*.py"), *(ROOT / "cli").rglob("*.py")])
#: Every Python file the project keeps: the size rule holds for tests and tools too.
EVERY_MODULE = sorted(
    [*SOURCES, *(p for d in ("tests", "benchmarks", "docs") for p in (ROOT / d).glob("*.py"))]
)

#: Layers, lowest first; a module may import its own layer and those below.
LAYERS = {
    "config_checks": 0, "io.files": 0, "measurement": 0,
    "detection.base": 1, "detection.regions": 1,
    "constraint_ray": 2, "animate": 2, "detection": 3, "io": 4, "app": 5, "tools": 5,
}  # fmt: skip


def _layer(module: str) -> int | None:
    parts = module.split(".")[1:]
    for n in (2, 1):
        key = ".".join(parts[:n])
        if key in LAYERS:
            return LAYERS[key]
    return None


@pytest.mark.parametrize("path", EVERY_MODULE, ids=lambda p: str(p.relative_to(ROOT)))
def test_modules_and_functions_stay_small(path):
    source = path.read_text()
    assert len(source.splitlines()) <= 400
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            assert node.end_lineno - node.lineno + 1 <= 60, f"{node.name} is too long"


@pytest.mark.parametrize(
    "path", [p for p in SOURCES if "motiondetect" in p.parts], ids=lambda p: p.name
)
def test_imports_run_down_the_layers(path):
    module = ".".join(path.relative_to(ROOT).with_suffix("").parts)
    own = _layer(module)
    if own is None:
        return
    tree = ast.parse(path.read_text())
    for node in tree.body:  # module-level imports only: registries import lazily
        if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("motiondetect."):
            other = _layer(node.module)
            assert other is None or other <= own, f"{module} imports {node.module}"


def test_every_option_is_a_setting_and_every_setting_an_option():
    presentation = {"inputs", "config_file", "quiet", "verbose", "logfile", "print_events"}
    params = {p.name for p in detect.params} - presentation
    settable = set(RUN_DEFAULTS) | set(CONFIG_OPTIONS)
    assert params == settable


def test_every_option_is_in_the_cli_docs():
    """docs/cli.md's table names every option of ``detect`` (it had drifted:
    ten options missing, a wrong working-size default)."""
    text = (ROOT / "docs" / "cli.md").read_text(encoding="utf-8")
    table = text[text.index("## Options") : text.index("## Outputs")]
    missing = [
        p.opts[-1]
        for p in detect.params
        if isinstance(p, click.Option)
        and not any(
            re.search(rf"(?<![\w-]){re.escape(o)}(?![\w-])", table)
            for o in p.opts + p.secondary_opts
        )
    ]
    assert missing == []


#: What the docs are: the README and every page under docs/.
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


def _in_docs(pattern: str) -> set:
    """Every match of ``pattern`` (``re.findall``'s items) in the docs."""
    return {m for doc in DOCS for m in re.findall(pattern, doc.read_text(encoding="utf-8"))}


def test_every_path_the_docs_name_exists():
    """A newcomer finds the paper's sections by the files the docs name
    (docs/stages.md and docs/detectors.md had named six modules that the
    restructure of issue 14 had moved into packages)."""
    named = _in_docs(r"(?<![\w./-])((?:motiondetect|cli|benchmarks|tests)/[\w/]*\w(?:\.py)?)")
    assert len(named) > 50  # the pattern still finds what the docs name
    assert sorted(path for path in named if not (ROOT / path).exists()) == []


def _resolves(dotted: str) -> bool:
    """Whether ``motiondetect.a.b...`` names a module, or an attribute of one."""
    parts = dotted.split(".")
    for n in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:n]))
        except ImportError:
            continue
        for name in parts[n:]:
            if not hasattr(obj, name):
                return False
            obj = getattr(obj, name)
        return True
    return False


def test_every_dotted_name_the_docs_give_resolves():
    """``motiondetect.x.y`` in the docs names a module or an object of one
    (docs/cli.md had sent readers to ``motiondetect.runner.run``)."""
    named = _in_docs(r"(?<![\w./-])motiondetect(?:\.[a-z_]\w*)+")
    assert len(named) > 5
    assert sorted(n for n in named if not _resolves(n)) == []


def test_every_test_the_docs_cite_exists():
    """``test_x.py::test_y`` in the docs names a test of that file (a name
    ending in ``_`` names the tests it begins)."""
    cited = _in_docs(r"(test_\w+\.py)::(\w+)")
    assert len(cited) > 20
    defined: dict[str, set[str]] = {}
    for path in (ROOT / "tests").glob("test_*.py"):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        defined[path.name] = {
            node.name
            for node in ast.walk(tree)
            if isinstance(node, (ast.FunctionDef, ast.ClassDef))
        }
    stale = [
        f"{file}::{name}"
        for file, name in sorted(cited)
        if not any(
            d == name or (name.endswith("_") and d.startswith(name)) for d in defined.get(file, ())
        )
    ]
    assert stale == []


def test_every_config_field_is_reachable_from_toml(tmp_path):
    lines = []
    for section, cls in SECTIONS.items():
        lines.append(f"[{section}]")
        for f in dataclasses.fields(cls):
            value = f.default
            if isinstance(value, bool):
                lines.append(f"{f.name} = {str(value).lower()}")
            elif isinstance(value, (int, float)) and value == value and abs(value) != float("inf"):
                lines.append(f"{f.name} = {value!r}")
            elif isinstance(value, str):
                lines.append(f'{f.name} = "{value}"')
    (tmp_path / "all.toml").write_text("\n".join(lines) + "\n")
    settings = make_settings(load_config_file(tmp_path / "all.toml"))
    for section, cls in SECTIONS.items():
        assert settings.configs[section] == cls()
    (tmp_path / "one.toml").write_text("measure = 'normal'\n[velocity_ray]\nfloor_px = 1.7\n")
    changed = make_settings(load_config_file(tmp_path / "one.toml"))
    assert changed.configs["velocity_ray"].floor_px == 1.7 and changed.measure == "normal"


@pytest.mark.parametrize(
    ("toml", "option", "message"),
    [
        ("frames_fps = nan", ["--frames-fps", "nan"], "--frames-fps must be a number"),
        ("jobs = 0", ["--jobs", "0"], "--jobs must be at least 1"),
        ("persistence = 0", ["--persistence", "0"], "persistence must be positive"),
        ("focal_share = -1", ["--focal-share", "-1"], "focal_share must not be negative"),
        (
            "rolling_shutter = 1.5",
            ["--rolling-shutter", "1.5"],
            "--rolling-shutter: [fit] line_gain must be in [0, 1]",
        ),
        ("roi = ['0,0,-5,5']", ["--roi", "0,0,-5,5"], "--roi needs a positive width"),
        ("roi = ['0,0,99999999999,10']", ["--roi", "0,0,99999999999,10"], "in range"),
    ],
)
def test_command_line_and_config_file_refuse_alike(tmp_path, toml, option, message):
    (tmp_path / "c.toml").write_text(toml + "\n")
    with pytest.raises(SettingsError, match=re.escape(message)):
        make_settings(load_config_file(tmp_path / "c.toml"))
    runner = CliRunner()
    clip = ROOT / "sample_videos" / "uniform_rigid" / "video.mp4"
    for args in (option, ["--config", str(tmp_path / "c.toml")]):
        result = runner.invoke(main, ["detect", str(clip), "-o", str(tmp_path / "o"), *args])
        assert result.exit_code == 2 and message in result.output, result.output


@pytest.mark.parametrize(
    ("section", "line"),
    [("track", "min_iou = 2"), ("track", "trim_share = 1.5"), ("fit", "blur_ratio = 3")],
)
def test_a_share_beyond_one_is_refused(tmp_path, section, line):
    """An overlap or a share above 1 can never be met: refused with one line,
    not run to an empty result (``min_iou = 2`` once gave 0 detections)."""
    (tmp_path / "c.toml").write_text(f"[{section}]\n{line}\n")
    name = line.split(" =")[0]
    with pytest.raises(SettingsError, match=rf"{name} must be in \[0, 1\]"):
        make_settings(load_config_file(tmp_path / "c.toml"))
    clip = ROOT / "sample_videos" / "uniform_rigid" / "video.mp4"
    args = ["detect", str(clip), "-o", str(tmp_path / "o"), "--config", str(tmp_path / "c.toml")]
    result = CliRunner().invoke(main, args)
    assert result.exit_code == 2 and f"{name} must be in [0, 1]" in result.output


def test_wrong_types_in_the_config_file_get_one_line(tmp_path):
    (tmp_path / "c.toml").write_text('work_size = "big"\n[track]\ngap_px = "wide"\n')
    with pytest.raises(SettingsError, match="--work-size must be a whole number"):
        make_settings(load_config_file(tmp_path / "c.toml"))
    (tmp_path / "d.toml").write_text('[track]\ngap_px = "wide"\n[nonsense]\nx = 1\n')
    with pytest.raises(SettingsError, match="unknown key 'nonsense'"):
        load_config_file(tmp_path / "d.toml")


@pytest.mark.parametrize(("section", "name"), [("track", "prior"), ("fit", "parallax")])
def test_switches_in_the_config_file_must_be_true_or_false(tmp_path, section, name):
    (tmp_path / "c.toml").write_text(f"[{section}]\n{name} = 3\n")
    with pytest.raises(SettingsError, match=f"\\[{section}\\] {name} must be true or false"):
        make_settings(load_config_file(tmp_path / "c.toml"))
    (tmp_path / "d.toml").write_text(f"[{section}]\n{name} = true\n")
    assert getattr(make_settings(load_config_file(tmp_path / "d.toml")).configs[section], name)
