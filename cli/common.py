"""Helpers every command shares: logging, one-line failures, the error guard."""

from __future__ import annotations

import contextlib
import logging
import sys

import av
import click
from tqdm import tqdm

log = logging.getLogger("motiondetect")


class _BarSafeHandler(logging.Handler):
    """To stderr through ``tqdm.write``, so log lines never break a progress bar."""

    def emit(self, record: logging.LogRecord) -> None:
        try:
            tqdm.write(self.format(record), file=sys.stderr)
        except Exception:  # noqa: BLE001 - logging must never raise
            self.handleError(record)


def _setup_logging(verbose: bool, quiet: bool, logfile=None) -> None:
    """stderr at WARNING (ERROR with -q, DEBUG with -v); ``logfile`` gets
    everything, DEBUG included, with timestamps."""
    level = logging.DEBUG if verbose else (logging.ERROR if quiet else logging.WARNING)
    for stream in (sys.stdout, sys.stderr):  # file names need not be valid UTF-8
        with contextlib.suppress(AttributeError, ValueError):
            stream.reconfigure(errors="backslashreplace")
    handler = _BarSafeHandler()
    handler.setFormatter(logging.Formatter("%(levelname)s: %(message)s"))
    handler.setLevel(level)
    handlers: list[logging.Handler] = [handler]
    if logfile is not None:
        try:
            to_file = logging.FileHandler(logfile, encoding="utf-8")
        except OSError as exc:
            message = f"cannot open --logfile {logfile}: {exc.strerror or exc}"
            raise click.UsageError(message) from None
        to_file.setFormatter(logging.Formatter("%(asctime)s %(levelname)s: %(message)s"))
        handlers.append(to_file)
    close_log_files()
    log.handlers[:] = handlers
    log.setLevel(logging.DEBUG if logfile is not None else level)
    log.propagate = False
    libav = logging.getLogger("libav")  # FFmpeg's own lines, through PyAV: only with -v
    libav.handlers[:] = handlers if verbose else []
    libav.propagate = False
    av.logging.set_level(av.logging.WARNING if verbose else None)


def close_log_files() -> None:
    """Close and drop the handlers that write to files (--logfile)."""
    for handler in list(log.handlers):
        if isinstance(handler, logging.FileHandler):
            handler.close()
            log.removeHandler(handler)


def _fail(message: str, code: int = 1) -> None:
    click.echo(f"error: {message}", err=True)
    sys.exit(code)


def _guard(verbose: bool):
    """Turn unexpected exceptions into one line (traceback with -v)."""

    class Guard:
        def __enter__(self):
            return self

        def __exit__(self, exc_type, exc, tb):
            if exc_type is None or issubclass(
                exc_type, (SystemExit, click.exceptions.Exit, click.ClickException)
            ):
                return False
            if issubclass(exc_type, KeyboardInterrupt):
                click.echo("interrupted", err=True)
                sys.exit(130)
            code = getattr(exc, "code", None)
            if type(exc).__name__ == "Interrupted" and code in (130, 143):
                click.echo(f"{exc}; unfinished inputs are redone on the next run", err=True)
                sys.exit(code)
            if verbose:
                return False
            click.echo(f"error: {exc}", err=True)
            sys.exit(1)

    return Guard()
