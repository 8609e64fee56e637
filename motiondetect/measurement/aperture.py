"""How much of a measured velocity the image determines (the aperture problem).

Brightness constancy gives one equation per pixel, ``grad I . v = -I_t``:
only the velocity component along the gradient (the normal flow of the
paper's section 3.2) is measured there. Dense flow fuses these equations over
a patch; where the patch's gradients all point one way (a long straight
edge, stripes, the mortar lines of a brick wall) the component along the
edges is not measured but filled in from the neighbours, and can be wrong by
pixels. Nelson's normal-flow filter never tests that component; the
velocity path tests it only as far as the image determines it.

The patch's structure tensor ``J`` (the mean of ``grad I grad I^T``) has
eigenvalues ``l1 >= l2`` (gradient energy along each eigenvector, grey
levels^2/px^2). A least-squares velocity with noise energy ``e`` per pixel
keeps a share ``l / (l + e)`` of each component: the *determined* residual
is ``J (J + e I)^-1 r``. Where both eigenvalues are well above ``e`` it is
the residual itself; across an edge it is the normal component; on a blank
patch it is nothing.
"""

from __future__ import annotations

import cv2
import numpy as np


def structure_tensor(grey: np.ndarray, window: int) -> tuple[np.ndarray, ...]:
    """Mean gradient products over a ``window`` x ``window`` box.

    Parameters
    ----------
    grey : (h, w) ndarray of uint8
    window : int
        Box side, px (odd; the flow's patch).

    Returns
    -------
    a, b, c : (h, w) ndarray of float32
        ``mean(Ix^2)``, ``mean(Ix Iy)``, ``mean(Iy^2)``, grey levels^2/px^2
        (Sobel gradients scaled to grey levels/px).
    """
    ix = cv2.Sobel(grey, cv2.CV_32F, 1, 0, ksize=3, scale=0.125)
    iy = cv2.Sobel(grey, cv2.CV_32F, 0, 1, ksize=3, scale=0.125)
    box = (window, window)
    return cv2.blur(ix * ix, box), cv2.blur(ix * iy, box), cv2.blur(iy * iy, box)


def determined(residual: np.ndarray, tensor: tuple[np.ndarray, ...], energy: float) -> np.ndarray:
    """The part of each residual velocity the image determines, ``J (J + e I)^-1 r``.

    Parameters
    ----------
    residual : (h, w, 2) ndarray of float32, px/frame
    tensor : (a, b, c) from :func:`structure_tensor`
    energy : float
        ``e``: the gradient energy a component needs to count half,
        grey levels^2/px^2 (> 0).

    Returns
    -------
    (h, w, 2) ndarray of float32, px/frame
    """
    a, b, c = tensor
    ae, ce = a + energy, c + energy
    inverse = 1.0 / (ae * ce - b * b)
    bb = b * b
    m11 = (a * ce - bb) * inverse
    m12 = b * energy * inverse
    m22 = (c * ae - bb) * inverse
    x, y = residual[..., 0], residual[..., 1]
    return np.stack([m11 * x + m12 * y, m12 * x + m22 * y], axis=-1).astype(np.float32)
