"""Results measured on the picture inside black bars, placed in the whole frame.

The velocity path measures only the picture of a letterboxed or pillarboxed
video (:mod:`motiondetect.measurement.picture`), so its masks are in the
picture's working pixels and its boxes in the picture's input pixels.
:class:`Framing` puts them where they lie in the frame the user gave: masks
in the whole frame at the same working scale, boxes and grid cells in the
frame's input pixels.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from motiondetect.detection.base import cells_from_mask
from motiondetect.detection.regions import Region
from motiondetect.measurement.normal_flow import GridGeometry
from motiondetect.measurement.picture import Picture


class Framing:
    """The whole frame around a picture measured at ``geometry``.

    Parameters
    ----------
    picture : Picture
        Where the picture lies, input pixels.
    geometry : GridGeometry
        The picture's input and working sizes.
    """

    def __init__(self, picture: Picture, geometry: GridGeometry) -> None:
        (iw, ih), (ww, wh) = geometry.input_size, geometry.work_size
        sx, sy = ww / iw, wh / ih
        fw, fh = picture.frame_size
        x, y = picture.box[:2]
        self.picture = picture
        self.work_size = (max(ww, round(fw * sx)), max(wh, round(fh * sy)))
        self.offset = (
            min(round(x * sx), self.work_size[0] - ww),
            min(round(y * sy), self.work_size[1] - wh),
        )

    def mask(self, mask: np.ndarray) -> np.ndarray:
        """A picture mask (h, w) in the whole frame, at the same working scale."""
        out = np.zeros(self.work_size[::-1], mask.dtype)
        x, y = self.offset
        out[y : y + mask.shape[0], x : x + mask.shape[1]] = mask
        return out

    def region(self, region: Region, own: np.ndarray) -> Region:
        """``region`` (of the picture; ``own`` its object's picture mask) in the whole frame."""
        x, y, w, h = region.bbox
        px, py = self.picture.box[:2]
        cells = np.argwhere(cells_from_mask(self.mask(own), share=1e-6))
        return dataclasses.replace(region, bbox=[x + px, y + py, w, h], cells=cells)

    def placed(
        self, regions: list[Region], masks: list[np.ndarray], mask: np.ndarray, overlay
    ) -> tuple[list[Region], np.ndarray, np.ndarray | None]:
        """The frame's regions (with their objects' masks), its mask and its
        overlay (or None), each in the whole frame."""
        regions = [self.region(r, own) for r, own in zip(regions, masks, strict=True)]
        return regions, self.mask(mask), None if overlay is None else self.mask(overlay)
