"""Models shared by the simulated backends (fake and mujoco): odometry error, walk sway,
the camera model and pictures.

Pure numpy and OpenCV; no simulator imports. Both backends use the same models so that
unit tests on the fake backend and runs in MuJoCo agree on what a NAO's walk and camera do.
"""
