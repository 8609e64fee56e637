"""Small file helpers shared by every writer and reader: one place each.

* :func:`last_number`: the number a frame file is named by (``frame_12.png``
  -> 12), used to order frames folders, match ground truth and poses.
* :func:`temporary_path` / :func:`atomic_path`: write beside the target under
  a hidden name unique to this process and call, then rename over the
  target on success, so an output either exists complete or not at all and
  two runs never touch each other's temporaries.
"""

from __future__ import annotations

import contextlib
import os
import re
import secrets
from collections.abc import Iterator
from pathlib import Path

_DIGITS = re.compile(r"\d+")
#: Prefix of every temporary output name; a run removes stale ones of its own.
TEMPORARY_PREFIX = ".md-part-"


def last_number(name: str | Path) -> int | None:
    """The last run of digits in a file name's stem, or None."""
    found = _DIGITS.findall(Path(name).stem)
    return int(found[-1]) if found else None


def temporary_path(path: str | Path) -> Path:
    """A hidden sibling of ``path`` unique to this process and call, same suffix."""
    path = Path(path)
    token = f"{os.getpid()}-{secrets.token_hex(4)}"
    return path.with_name(f"{TEMPORARY_PREFIX}{token}-{path.stem}{path.suffix}")


@contextlib.contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """Yield a temporary path; rename it over ``path`` when the block succeeds.

    On an exception the temporary file is removed and ``path`` is untouched.
    """
    path = Path(path)
    tmp = temporary_path(path)
    try:
        yield tmp
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


def display_name(path: str | Path) -> str:
    """``path`` as valid text for messages and reports: bytes a file name may
    hold that are not UTF-8 appear as ``\\xff`` escapes."""
    return str(path).encode("utf-8", "surrogateescape").decode("utf-8", "backslashreplace")
