"""motiondetect: independently moving objects seen by a moving observer.

An implementation of R. C. Nelson, "Qualitative Detection of Motion by a
Moving Observer" (CVPR 1991 / IJCV 7(1) 1991): the Maxvideo normal-flow stage
pipeline, the constraint ray filter (section 3) and the animate-motion
detector (section 4).
"""

import logging

__version__ = "0.1.0"

logging.getLogger("motiondetect").addHandler(logging.NullHandler())
