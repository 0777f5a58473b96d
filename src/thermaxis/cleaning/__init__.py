"""Cleaning one run (the ``clean`` rule, run by run): temperatures onto a common grid, clock offsets, interferometer passes, and the run's tidy tables."""
