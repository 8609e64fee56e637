"""The rolling shutter's wobble: what the plane leaves along the sensor's lines.

A CMOS sensor reads its rows one after another over most of the frame
period, so each row shows the view at its own time. While the camera moves
steadily every row is read one frame period after the same row before, and
the flow is the plane's. When the camera's motion changes within a frame
(a mount's vibration, a jolt), each row's displacement differs by the
change the camera made while that row waited: the picture wobbles (the
"jello" effect) by an offset that is a function of the row alone. The
homography absorbs the part linear in the row (a shear, a vertical scale);
the rest is left in the plane residual of every rigid point, row by row,
and the tolerance, which grows with the residual's spread, then hides
movers (docs/detectors.md, "A rolling shutter's wobble").

This models that offset: the median residual along each row of samples,
smoothed by a robust low-order polynomial over the frame. It is used only
when it explains enough of the residual all along the rows, in each strip
across them (model selection): a wobble moves whole rows, while a scene
whose parallax happens to vary with the row (a near surface on one side)
is explained only where that surface lies, and is left as it was. A mover
fills a few rows of samples at most; the polynomial's robust weights outvote them.
Video rotated after decoding (an upright phone clip) was read along its
columns, so both axes are tried and the one that explains more is kept.
Pure functions of one frame's samples and the last frame's.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from motiondetect.measurement.dense_flow import vector_length

#: Degree of the polynomial over the lines (a frame holds at most about one
#: swing of a 6-12 Hz vibration read over 30 ms).
DEGREE = 3
#: The smallest wobble worth taking out, work px/frame (its largest offset
#: over the lines sampled): a tenth of a pixel is below DIS's own error
#: on real frames and changes nothing a tolerance tests.
MIN_OFFSET_PX = 0.1
#: Strips across the lines in each of which the offsets must explain the residual.
STRIPS = 4
_IRLS_ROUNDS = 4


@dataclass(frozen=True)
class LineOffsets:
    """The residual's part that is a function of the sensor line alone.

    Attributes
    ----------
    axis : int
        0: a function of the row (y); 1: of the column (x).
    offsets : (n, 2) ndarray of float32
        The velocity each line adds to the plane's, work px/frame (``n``
        rows or columns of the work frame).
    gain : float
        The least share of the median residual length it takes off in a
        strip across the lines (:data:`STRIPS`).
    """

    axis: int
    offsets: np.ndarray
    gain: float

    def at(self, points: np.ndarray) -> np.ndarray:
        """The offsets at ``points`` (N, 2) of (x, y) work px: (N, 2) float32."""
        coordinate = 1 - self.axis
        index = np.clip(np.rint(points[:, coordinate]).astype(int), 0, len(self.offsets) - 1)
        return self.offsets[index]

    def field(self, shape: tuple[int, int]) -> np.ndarray:
        """The offsets over a (h, w) frame: (h, w, 2) float32."""
        per_line = self.offsets[:, None, :] if self.axis == 0 else self.offsets[None, :, :]
        return np.broadcast_to(per_line, (*shape, 2))


def line_offsets(
    residual: np.ndarray,
    lines: tuple[np.ndarray, np.ndarray],
    min_gain: float,
    shape: tuple[int, int],
    fit_px: float,
    scene: np.ndarray | None,
    previous: np.ndarray,
) -> LineOffsets | None:
    """The wobble the plane leaves on the sample grid, when it takes at
    least ``min_gain`` (in (0, 1)) off the median residual length in each
    strip across the lines (:data:`STRIPS`); else None.

    Parameters
    ----------
    residual : (r, c, 2) ndarray
        The plane residual on the sample grid, work px/frame.
    lines : ((r,) ndarray, (c,) ndarray)
        The grid's rows and columns, work px.
    shape : (h, w)
        The work frame's (the offsets cover every line of it).
    fit_px : float
        The plane's inlier threshold, work px/frame: with the offsets, the
        median sample must lie within it, as a fitted plane's inliers do.
        A plane that left most of the scene further off had failed (a
        frame beyond the band, motion blur), and no wobble mends it.
    scene : (r, c) ndarray of bool or None
        The samples off the known movers (the tracks' predicted boxes), the
        only ones measured: a mover the camera follows, filling the middle
        of the view, would otherwise be the median of its rows.
    previous : (r, c, 2) ndarray
        The last frame's plane residual on the same grid. A wobble is the
        change of the camera's motion during one frame, so it comes and
        goes (a vibration's changes sign every few frames); where the last
        frame's lines explain this one's residual as well, the structure
        persists: a surface's parallax that varies with the line (the
        ground under a sideways motion), not a wobble.
    """
    scene = np.ones(residual.shape[:2], bool) if scene is None else scene
    best = None
    for axis in (0, 1):
        kept, medians = _line_medians(residual, scene, axis)
        if kept.sum() < 2 * (DEGREE + 1):
            continue
        if _least_gain(residual, residual - _laid(medians, kept, axis), 1 - axis, scene) < min_gain:
            continue  # the lines' own medians take off too little: so would any smoothing
        last_kept, last = _line_medians(previous, scene, axis)
        persisting = residual - _laid(last, last_kept, axis)
        if _least_gain(residual, persisting, 1 - axis, scene) >= min_gain:
            continue
        offsets = _smoothed(lines[axis][kept], medians, shape[axis])
        left = residual - _spread(offsets[lines[axis].astype(int)], axis)
        at_scene = vector_length(left)[scene]
        if np.abs(offsets).max() < MIN_OFFSET_PX or _middle(at_scene, 0) > fit_px:
            continue
        gain = _least_gain(residual, left, 1 - axis, scene)
        if best is None or gain > best.gain:
            best = LineOffsets(axis, offsets, gain)
    return best if best is not None and best.gain >= min_gain else None


def _middle(values: np.ndarray, axis: int) -> np.ndarray:
    """The (upper) median along ``axis``, by one partial sort."""
    k = values.shape[axis] // 2
    return np.take(np.partition(values, k, axis=axis), k, axis=axis)


def _line_medians(
    residual: np.ndarray, scene: np.ndarray, axis: int
) -> tuple[np.ndarray, np.ndarray]:
    """Which grid lines along ``axis`` hold enough ``scene`` samples (n,)
    bool, and the median residual over those samples of each line kept (k, 2)."""
    if scene.all():
        return np.ones(residual.shape[axis], bool), _middle(residual, 1 - axis)
    per_line = residual if axis == 0 else residual.transpose(1, 0, 2)
    inside = scene if axis == 0 else scene.T
    kept = inside.sum(axis=1) >= inside.shape[1] // 4
    medians = [
        _middle(line[where], 0) for line, where in zip(per_line[kept], inside[kept], strict=True)
    ]
    return kept, np.asarray(medians).reshape(-1, 2)


def _laid(medians: np.ndarray, kept: np.ndarray, axis: int) -> np.ndarray:
    """The ``medians`` (k, 2) of the ``kept`` lines along ``axis``, laid
    over the (r, c, 2) grid (zero on the lines not kept)."""
    out = np.zeros((len(kept), 1, 2) if axis == 0 else (1, len(kept), 2), np.float32)
    out[(kept,) if axis == 0 else (slice(None), kept)] = _spread(medians, axis)
    return out


def _spread(per_line: np.ndarray, axis: int) -> np.ndarray:
    """``per_line`` (n, 2) offsets of the grid's lines along ``axis``,
    shaped to broadcast over the (r, c, 2) grid."""
    return per_line[:, None, :] if axis == 0 else per_line[None, :, :]


def _least_gain(before: np.ndarray, after: np.ndarray, across: int, scene: np.ndarray) -> float:
    """The smallest share of the median residual length taken off from
    ``before`` to ``after`` (r, c, 2), over the ``scene`` samples, in each of
    :data:`STRIPS` strips along grid axis ``across``: a wobble moves whole
    lines, so it explains the residual all along them, where parallax that
    happens to vary with the line explains it only where its surface lies."""
    gains = []
    for old, new, where in zip(
        np.array_split(vector_length(before), STRIPS, axis=across),
        np.array_split(vector_length(after), STRIPS, axis=across),
        np.array_split(scene, STRIPS, axis=across),
        strict=True,
    ):
        if not where.any():
            continue  # a strip wholly on the movers says nothing of the scene
        level = float(_middle(old[where], 0))
        gains.append(1.0 - float(_middle(new[where], 0)) / level if level > 0 else 0.0)
    return min(gains) if gains else 0.0


def _smoothed(centres: np.ndarray, medians: np.ndarray, length: int) -> np.ndarray:
    """The offsets (length, 2) as a robust polynomial in the line through
    each grid line's median residual, ``medians`` (n, 2) at ``centres`` (n,)."""
    u = 2.0 * centres / length - 1.0
    design = np.vander(u, DEGREE + 1)
    weight = np.ones(len(u))
    for _ in range(_IRLS_ROUNDS):  # Tukey's biweight on each line's miss
        weighted = design.T * weight
        coefficients = np.linalg.solve(
            weighted @ design + 1e-9 * np.eye(DEGREE + 1), weighted @ medians
        )
        miss = np.hypot(*(design @ coefficients - medians).T)
        scale = 4.685 * max(1.4826 * float(np.median(miss)), 0.05)
        weight = np.clip(1.0 - (miss / scale) ** 2, 0.0, None) ** 2
    sampled = np.clip(np.arange(length), centres.min(), centres.max())  # held, not extrapolated
    lines = np.vander(2.0 * sampled / length - 1.0, DEGREE + 1)
    return (lines @ coefficients).astype(np.float32)
