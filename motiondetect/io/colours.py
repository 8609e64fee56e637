"""Colours (BGR) shared by the annotated video and the timeline: one table each."""

from __future__ import annotations

#: Observer-motion class (-1: none or unreliable; 6: known ego-motion).
CLASS_COLOURS = {
    -1: (160, 160, 160),
    0: (90, 90, 90),
    1: (200, 120, 40),
    2: (60, 170, 60),
    3: (40, 200, 200),
    4: (200, 80, 200),
    5: (40, 110, 230),
    6: (230, 200, 60),
}

RAY, ANIMATE, BOTH = (0, 140, 255), (255, 80, 200), (0, 0, 255)

#: Box colour by the detectors that found a region.
DETECTOR_COLOURS = {
    ("constraint-ray",): RAY,
    ("animate",): ANIMATE,
    ("constraint-ray", "animate"): BOTH,
    ("velocity-ray",): RAY,
    ("velocity-animate",): ANIMATE,
    ("velocity-ray", "velocity-animate"): BOTH,
}

LEGEND = (("ray", RAY), ("animate", ANIMATE), ("both", BOTH))

#: A detection's own motion, drawn as an arrow from its box's centre (cyan:
#: apart from the detectors' colours and the normal path's white coarse field).
OWN_MOTION = (255, 255, 0)
