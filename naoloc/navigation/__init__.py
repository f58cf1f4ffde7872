"""Navigation: the free-floor grid learned from the survey, paths, homing routes."""
