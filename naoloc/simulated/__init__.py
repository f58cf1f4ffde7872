"""Simulation parts shared by the simulated backends (numpy and OpenCV only)."""
