"""Helpers every command shares: logging, one-line failures, the error guard."""

from __future__ import annotations

import logging
import sys

import click

log = logging.getLogger("motiondetect")


def _setup_logging(verbose: bool, quiet: bool) -> None:
    level = logging.DEBUG if verbose else (logging.ERROR if quiet else logging.WARNING)
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(logging.Formatter("%(levelname)s: %(message)s"))
    log.handlers[:] = [handler]
    log.setLevel(level)
    log.propagate = False


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
            if verbose:
                return False
            click.echo(f"error: {exc}", err=True)
            sys.exit(1)

    return Guard()
