"""Times on the command line: a start, an end, or a duration.

One grammar for every option that takes a time (``--start``, ``--end``,
``--min-event``, ``--merge-gap``, ``--pad``):

* ``12.5`` or ``12.5s``: seconds;
* ``00:01:02.500`` or ``01:02.5``: a timecode (hours optional);
* ``45f``: a frame count (a frame number for ``--start`` and ``--end``).

Seconds are taken from the source's timestamps; frames are frames.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

_TIMECODE = re.compile(r"^(?:(\d+):)?(\d+):(\d+(?:\.\d*)?)$")


@dataclass(frozen=True)
class TimeSpec:
    """A time or duration: ``value`` seconds, or ``value`` frames."""

    value: float
    unit: str  # "s" or "f"

    def frames(self, fps: float) -> int:
        """As a whole number of frames at ``fps``."""
        return int(self.value) if self.unit == "f" else int(round(self.value * fps))

    def reached(self, index: int, time_s: float) -> bool:
        """Has a frame at ``index`` / ``time_s`` reached this point in time?"""
        return index >= self.value if self.unit == "f" else time_s >= self.value - 1e-9

    def passed(self, index: int, time_s: float) -> bool:
        """Is a frame past this end? A time ends before it, a frame number includes it."""
        return index > self.value if self.unit == "f" else time_s >= self.value - 1e-9

    def __str__(self) -> str:
        return f"{int(self.value)}f" if self.unit == "f" else f"{self.value:g}s"


def parse_time(text: str | int | float, option: str = "time") -> TimeSpec:
    """Parse one time; raise ``ValueError`` with a one-line message."""
    raw = str(text).strip()
    try:
        if raw.endswith("f") and raw[:-1].isdigit():
            return TimeSpec(float(int(raw[:-1])), "f")
        match = _TIMECODE.match(raw)
        if match:
            h, m, s = match.groups()
            if int(m) >= 60 or float(s) >= 60:
                raise ValueError
            return TimeSpec(int(h or 0) * 3600 + int(m) * 60 + float(s), "s")
        seconds = float(raw[:-1] if raw.endswith("s") else raw)
        if not math.isfinite(seconds) or seconds < 0:
            raise ValueError
        return TimeSpec(seconds, "s")
    except ValueError:
        raise ValueError(
            f"{option} must be seconds (12.5), a timecode (00:01:02.5) or frames (45f), "
            f"but got {raw!r}"
        ) from None
