"""Perception: what one picture says, with no map and no robot.

- :mod:`~naoloc.perception.floorline`: the floor-wall line from a bottom-camera image;
- :mod:`~naoloc.perception.features`: local features (A-KAZE, ORB, SIFT).
"""
