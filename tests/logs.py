"""What the library logs, caught in a test."""

from __future__ import annotations

import contextlib
import logging
from collections.abc import Iterator


@contextlib.contextmanager
def warnings_logged() -> Iterator[list[str]]:
    """The warning messages the ``motiondetect`` logger emits inside the block,
    at WARNING whatever level an earlier run (with ``-q``) left it at."""
    records: list[logging.LogRecord] = []
    handler = logging.Handler()
    handler.emit = records.append
    logger = logging.getLogger("motiondetect")
    level = logger.level
    logger.addHandler(handler)
    logger.setLevel(logging.WARNING)
    messages: list[str] = []
    try:
        yield messages
    finally:
        logger.removeHandler(handler)
        logger.setLevel(level)
        messages += [r.getMessage() for r in records if r.levelno == logging.WARNING]
