"""Cleaning one run (the ``clean_run`` rule): temperatures onto a common grid, clock offsets, interferometer passes, and the run's tidy tables."""
