"""The public API (issue 16): exports, and the docs/api.md doctest."""

from __future__ import annotations

import doctest
import os
from pathlib import Path

import motiondetect

ROOT = Path(__file__).resolve().parents[1]


def test_public_names_are_exported():
    for name in motiondetect.__all__:
        assert hasattr(motiondetect, name), name
    assert (ROOT / "motiondetect" / "py.typed").exists()


def test_api_doc_examples_run(monkeypatch):
    monkeypatch.chdir(ROOT)
    failures, tried = doctest.testfile(
        os.fspath(ROOT / "docs" / "api.md"), module_relative=False, optionflags=doctest.ELLIPSIS
    )
    assert tried > 5 and failures == 0
