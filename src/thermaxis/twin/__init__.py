"""Calibrated thermal twin of the paper's X axis (the embedded default dataset)."""
