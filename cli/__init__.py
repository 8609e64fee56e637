"""The motiondetect command line (installed as ``motiondetect_cli``)."""
