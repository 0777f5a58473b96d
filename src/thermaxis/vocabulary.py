"""The paper's vocabulary, defined once: the two modelling approaches and the algorithms.

Code, the config schema (``$defs``), the wildcard constraints of the workflow and the
figure table all take these from here; a test checks the schema against them. This
module imports nothing, so the workflow can read it while Snakemake parses.
"""

__all__ = ["APPROACHES", "ALGORITHMS", "SEARCHABLE"]

# Decoupled: the slope k and the intercept b of each measurement's error line (Eq. 6),
# each modelled from temperatures (Eq. 9). Point by point: one model of the error at
# every target position (Eq. 8).
APPROACHES = ("decoupled", "pointwise")

# Multiple linear regression and support-vector regression (the paper's two), ridge,
# lasso (a sparse model: it also selects sensors), partial least squares and
# Gaussian-process regression, and the evidence ridge ("bayesridge": a ridge whose strength
# maximises the evidence of the training rows, scikit-learn's BayesianRidge, so it needs no
# inner search).
ALGORITHMS = ("mlr", "svr", "ridge", "lasso", "pls", "gpr", "bayesridge")

# The algorithms whose strength (ridge and lasso alpha, PLS components) an inner search
# on the training runs may choose; the SVR always searches its grid.
SEARCHABLE = ("ridge", "lasso", "pls")
