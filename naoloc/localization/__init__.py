"""Localization: where the robot is in a map, from observations (robot-free).

- :mod:`~naoloc.localization.fusion`: the particle filter over odometry and fixes;
- :mod:`~naoloc.localization.floorfix`: floor-wall lines against the map's walls.
"""
