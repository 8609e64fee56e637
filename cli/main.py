"""The ``motiondetect`` command. Click parses and validates; the library runs.

Exit codes: 0 every input done, 1 some inputs failed (the others finished),
2 usage error. Each failure is one line; ``-v`` adds tracebacks.
"""

from __future__ import annotations

import logging

import click
from motiondetect_cli.detect import detect
from motiondetect_cli.tools import evaluate, info, synth

from motiondetect import __version__

log = logging.getLogger("motiondetect")


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="motiondetect")
def main() -> None:
    """Find independently moving objects in video shot by a moving camera."""


for _command in (detect, info, synth, evaluate):
    main.add_command(_command)


if __name__ == "__main__":  # pragma: no cover
    main()
