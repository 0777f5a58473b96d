"""StandardScaler's arithmetic in numpy: the linear core's moments and the inner searches' scalers.

scikit-learn's ``StandardScaler`` takes the mean as sum / n and the variance by the corrected
two-pass algorithm (Chan, Golub and LeVeque), and keeps scale 1 for a feature whose variance
is within the rounding of that algorithm (``_is_constant_feature``). The same numbers, bit
for bit, without the estimator's input checks, which cost more than a small fit.
"""

from __future__ import annotations

import numpy as np

__all__ = ["mean_variance", "is_constant", "scaler_moments"]

_EPS = np.finfo(np.float64).eps


def mean_variance(W):
    """Count, mean, centred rows and variance of the rows W, as StandardScaler computes them
    (sum / n, and the corrected two-pass variance of Chan, Golub and LeVeque)."""
    n = W.shape[0]
    mean = W.sum(axis=0) / n
    Wc = W - mean
    variance = ((Wc**2).sum(axis=0) - Wc.sum(axis=0) ** 2 / n) / n
    return n, mean, Wc, variance


def is_constant(variance, mean, n):
    """Whether each variance is within the two-pass algorithm's rounding (StandardScaler's
    ``_is_constant_feature`` bound): such a feature keeps scale 1."""
    return variance <= n * _EPS * variance + (n * mean * _EPS) ** 2


def scaler_moments(W) -> tuple[np.ndarray, np.ndarray]:
    """``StandardScaler().fit(W)``'s ``mean_`` and ``scale_``, bit for bit, for (n, m) rows
    without NaN, and without its input checks: an inner search's hold-outs are small, and
    the checks cost more than the fits of its grid."""
    n, mean, _, variance = mean_variance(np.asarray(W, dtype=float))
    scale = np.sqrt(variance)
    scale[is_constant(variance, mean, n)] = 1.0
    return mean, scale
