"""The one range check every frozen config runs in ``__post_init__``."""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping


def check_fields(
    config: object,
    *,
    positive: Iterable[str] = (),
    non_negative: Iterable[str] = (),
    shares: Iterable[str] = (),
    choices: Mapping[str, tuple] | None = None,
) -> None:
    """Raise ``ValueError`` naming the first field out of its range:
    ``positive`` above 0, ``non_negative`` at least 0, ``shares`` in [0, 1]
    (a share, an overlap, a rate).

    NaN fails every numeric check (``nan > 0`` is false), and so does a
    value that is not a number at all.
    """
    for name in positive:
        _number(config, name, lambda v: v > 0, "be positive")
    for name in non_negative:
        _number(config, name, lambda v: v >= 0, "not be negative")
    for name in shares:
        _number(config, name, lambda v: 0 <= v <= 1, "be in [0, 1]")
    for name, allowed in (choices or {}).items():
        value = getattr(config, name)
        if value not in allowed:
            raise ValueError(f"{name} must be one of {list(allowed)}, but got {value!r}")


def _number(config: object, name: str, ok, wording: str) -> None:
    value = getattr(config, name)
    good = isinstance(value, (int, float)) and not isinstance(value, bool)
    if not (good and not math.isnan(value) and ok(value)):
        raise ValueError(f"{name} must {wording}, but got {value!r}")
