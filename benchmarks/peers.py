"""The peer baselines of ``compare.py``, each a 0/255 mask per frame at input resolution.

* frame differencing: |I_t - I_{t-1}| > 25 after a 5x5 blur, then a 3x3 opening;
* OpenCV MOG2 (``detectShadows=False``), as DVR-Scan uses it;
* homography-compensated differencing: ORB features, brute-force Hamming
  matching, RANSAC homography, warp the previous frame, difference > 25,
  3x3 opening;
* the dense residual of issue 13: DIS flow less a RANSAC homography's.
"""

from __future__ import annotations

import cv2
import numpy as np


class FrameDiff:
    name = "frame differencing"

    def __init__(self):
        self.prev = None

    def __call__(self, frame, time_s=0.0):
        g = cv2.GaussianBlur(cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY), (5, 5), 0)
        prev, self.prev = self.prev, g
        if prev is None:
            return np.zeros_like(g)
        mask = (cv2.absdiff(g, prev) > 25).astype(np.uint8) * 255
        return cv2.morphologyEx(mask, cv2.MORPH_OPEN, np.ones((3, 3), np.uint8))


class Mog2:
    name = "OpenCV MOG2"

    def __init__(self):
        self.sub = cv2.createBackgroundSubtractorMOG2(detectShadows=False)

    def __call__(self, frame, time_s=0.0):
        return np.where(self.sub.apply(frame) > 127, 255, 0).astype(np.uint8)


class HomographyDiff:
    name = "homography-compensated diff"

    def __init__(self):
        self.orb = cv2.ORB_create(1000)
        self.matcher = cv2.BFMatcher(cv2.NORM_HAMMING, crossCheck=True)
        self.prev = None

    def __call__(self, frame, time_s=0.0):
        g = cv2.GaussianBlur(cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY), (5, 5), 0)
        kp, des = self.orb.detectAndCompute(g, None)
        prev, self.prev = self.prev, (g, kp, des)
        if prev is None or des is None or prev[2] is None:
            return np.zeros_like(g)
        matches = self.matcher.match(prev[2], des)
        if len(matches) < 8:
            return np.zeros_like(g)
        src = np.float32([prev[1][m.queryIdx].pt for m in matches])
        dst = np.float32([kp[m.trainIdx].pt for m in matches])
        hom, _ = cv2.findHomography(src, dst, cv2.RANSAC, 3.0)
        if hom is None:
            return np.zeros_like(g)
        h, w = g.shape
        warped = cv2.warpPerspective(prev[0], hom, (w, h))
        valid = cv2.warpPerspective(np.ones_like(g), hom, (w, h)) > 0
        mask = ((cv2.absdiff(g, warped) > 25) & valid).astype(np.uint8) * 255
        return cv2.morphologyEx(mask, cv2.MORPH_OPEN, np.ones((3, 3), np.uint8))


class DenseResidual:
    """DIS flow at 320 px, RANSAC homography on a 4-px grid, |flow - H flow| > 1.5 px,
    3x3 opening, kept only within 4 px of the previous frame's flags (issue 13)."""

    name = "dense residual"

    def __init__(self):
        self.dis = cv2.DISOpticalFlow_create(cv2.DISOPTICAL_FLOW_PRESET_FAST)
        self.prev = None
        self.prev_mask = None

    def __call__(self, frame, time_s=0.0):
        h0, w0 = frame.shape[:2]
        s = 320 / max(h0, w0)
        small = cv2.resize(frame, (round(w0 * s), round(h0 * s)), interpolation=cv2.INTER_AREA)
        g = cv2.cvtColor(small, cv2.COLOR_BGR2GRAY)
        prev, self.prev = self.prev, g
        if prev is None:
            return np.zeros((h0, w0), np.uint8)
        flow = self.dis.calc(prev, g, None)
        h, w = g.shape
        ys, xs = np.mgrid[0:h:4, 0:w:4].astype(np.float32)
        src = np.stack([xs.ravel(), ys.ravel()], 1)
        hom, _ = cv2.findHomography(src, src + flow[0:h:4, 0:w:4].reshape(-1, 2), cv2.RANSAC, 1.0)
        if hom is None:
            return np.zeros((h0, w0), np.uint8)
        yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
        grid = np.stack([xx, yy], -1)
        plane = cv2.perspectiveTransform(grid.reshape(-1, 1, 2), hom).reshape(h, w, 2) - grid
        mask = (np.linalg.norm(flow - plane, axis=2) > 1.5).astype(np.uint8)
        mask = cv2.morphologyEx(mask, cv2.MORPH_OPEN, np.ones((3, 3), np.uint8))
        prev_mask, self.prev_mask = self.prev_mask, mask
        near = cv2.dilate(prev_mask, np.ones((9, 9), np.uint8)) if prev_mask is not None else 0
        mask = mask & near
        return cv2.resize(mask * 255, (w0, h0), interpolation=cv2.INTER_NEAREST)
