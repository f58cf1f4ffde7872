"""Data on disk: survey datasets (MCAP), their checks, and outputs written whole."""
