"""Grey relational analysis, step 4 of the sensitive-point selection (Eq. 4).

In each class of the fuzzy clustering (:mod:`thermaxis.method.selection`) the sensor whose
sequence relates most closely to the target's is the sensitive point: Deng's grey
relational grade (Eq. 4) or, as the text also names, Liu Sifeng's absolute degree of grey
incidence. The checks of a table of sensor readings and of a target sequence live here,
with the functions that take them first, and the selection shares them.
"""

from __future__ import annotations

import warnings

import numpy as np
import pandas as pd

from thermaxis.errors import SelectionWarning

__all__ = [
    "NORMALISATIONS",
    "as_samples_by_sensors",
    "as_sequence",
    "grey_relational_grade",
    "absolute_grey_incidence",
]

NORMALISATIONS = ("initial", "mean", "minmax")


def as_samples_by_sensors(X, name: str = "X") -> np.ndarray:
    """Readings as a finite float array (n_samples >= 2, n_sensors >= 1); ``name`` in errors."""
    arr = np.asarray(X.to_numpy() if isinstance(X, pd.DataFrame) else X, dtype=float)
    if arr.ndim != 2:
        raise ValueError(f"{name} must be 2-D (n_samples, n_sensors), got shape {arr.shape}")
    if arr.shape[0] < 2 or arr.shape[1] < 1:
        raise ValueError(f"{name} needs at least 2 samples and 1 sensor, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} contains NaN or infinite values; drop or fill them first")
    return arr


def as_sequence(y, n_samples: int, name: str = "y") -> np.ndarray:
    """A target as a finite 1-D float array of ``n_samples`` (a single column is flattened)."""
    arr = np.asarray(y.to_numpy() if isinstance(y, (pd.Series, pd.DataFrame)) else y, dtype=float)
    arr = arr.reshape(-1) if arr.ndim == 2 and 1 in arr.shape else arr
    if arr.ndim != 1 or arr.size != n_samples:
        raise ValueError(
            f"{name} must be a 1-D sequence of {n_samples} samples, got shape {arr.shape}"
        )
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} contains NaN or infinite values; drop or fill them first")
    return arr


# --------------------------------------------------------------------------- #
# step 4: grey relational analysis (Eq. 4)
# --------------------------------------------------------------------------- #
def _normalise(seqs: np.ndarray, normalisation: str) -> np.ndarray:
    """Dimensionless sequences; ``seqs`` is (n_samples, n_sequences), column 0 = x0."""
    if normalisation == "initial":
        first = seqs[0]
        if np.any(first == 0):
            bad = np.flatnonzero(first == 0).tolist()
            raise ValueError(
                "initial-value normalisation needs a non-zero first value; sequence(s) "
                f"{bad} (0 = the target, i = sensor column i-1) start at 0 - use 'mean' or 'minmax'"
            )
        return seqs / first
    if normalisation == "mean":
        mean = seqs.mean(axis=0)
        if np.any(mean == 0):
            bad = np.flatnonzero(mean == 0).tolist()
            raise ValueError(
                f"mean normalisation needs a non-zero mean; sequence(s) {bad} "
                "(0 = the target, i = sensor column i-1) average to 0 - use 'minmax'"
            )
        return seqs / mean
    span = seqs.max(axis=0) - seqs.min(axis=0)
    flat = span == 0
    if flat.any():
        warnings.warn(
            f"constant sequence(s) {np.flatnonzero(flat).tolist()} (0 = the target, "
            "i = sensor column i-1): min-max normalised to all zeros",
            SelectionWarning,
            stacklevel=3,
        )
    return np.where(flat, 0.0, (seqs - seqs.min(axis=0)) / np.where(flat, 1.0, span))


def grey_relational_grade(x0, X, rho: float, normalisation: str) -> np.ndarray:
    """Deng's grey relational grade of each sensor sequence to the target x0 (Eq. 4).

    After making every sequence dimensionless,

    ``xi_i(k) = (min_j min_k D_j(k) + rho max_j max_k D_j(k)) / (D_i(k) + rho max_j max_k D_j(k))``

    with ``D_i(k) = |x0(k) - x_i(k)|``; the two-level minimum and maximum run
    over **all** candidate sensors j and all samples k, so grades of different
    sensors are on one scale.  The grade is the mean of ``xi_i(k)`` over k.

    Parameters
    ----------
    x0 : array-like, shape (n_samples,)
        Target (reference) sequence: k, b or the error at one position.
    X : array-like or DataFrame, shape (n_samples, n_sensors)
        Comparison sequences, one column per sensor.
    rho : float
        Distinguishing coefficient, ``0 < rho <= 1`` (0.5 as in the paper).
    normalisation : {"minmax", "initial", "mean"}
        ``"minmax"``: ``(x - min) / (max - min)`` per sequence (a constant
        sequence becomes zeros, with a warning); ``"initial"``: ``x / x(1)``;
        ``"mean"``: ``x / mean(x)``.  Applied to x0 and to every sensor.

    Returns
    -------
    numpy.ndarray, shape (n_sensors,)
        Grades in (0, 1]; all ones if every sequence equals x0 after
        normalisation.

    Raises
    ------
    ValueError
        Initial-value normalisation meeting a zero first value (e.g. the
        relative temperatures used for the intercept b, which start at 0), mean
        normalisation meeting a zero mean, or bad shapes / parameters.

    Notes
    -----
    The grade measures closeness of the curves, not of the trends' sign: a
    sensor that falls while x0 rises gets a low grade after min-max scaling.
    """
    arr = as_samples_by_sensors(X)
    target = as_sequence(x0, arr.shape[0], name="x0")
    if not (0.0 < float(rho) <= 1.0):
        raise ValueError(f"rho must lie in (0, 1], got {rho}")
    if normalisation not in NORMALISATIONS:
        raise ValueError(f"normalisation must be one of {NORMALISATIONS}, got {normalisation!r}")
    seqs = _normalise(np.column_stack([target, arr]), normalisation)
    delta = np.abs(seqs[:, 1:] - seqs[:, [0]])
    d_min, d_max = float(delta.min()), float(delta.max())
    if d_max == 0.0:
        return np.ones(arr.shape[1])
    coefficient = (d_min + rho * d_max) / (delta + rho * d_max)
    return coefficient.mean(axis=0)


def absolute_grey_incidence(x0, X) -> np.ndarray:
    """Liu Sifeng's absolute degree of grey incidence of each sensor to x0.

    With zero-starting-point images ``x^0(k) = x(k) - x(1)`` of equal-interval
    sequences of length n,

    ``s = sum_{k=2}^{n-1} x^0(k) + x^0(n) / 2``  and
    ``eps_0i = (1 + |s_0| + |s_i|) / (1 + |s_0| + |s_i| + |s_i - s_0|)``.

    Parameters
    ----------
    x0 : array-like, shape (n_samples,)
        Target sequence.
    X : array-like or DataFrame, shape (n_samples, n_sensors)
        Sensor sequences (raw, not normalised: the degree compares the areas
        the zero-started curves sweep, in the data's own units).

    Returns
    -------
    numpy.ndarray, shape (n_sensors,)
        Degrees in (0, 1]; 1 when the two zero-started areas are equal.
    """
    arr = as_samples_by_sensors(X)
    target = as_sequence(x0, arr.shape[0], name="x0")

    def area(seq: np.ndarray) -> np.ndarray:
        zero_started = seq - seq[:1]
        return zero_started[1:-1].sum(axis=0) + 0.5 * zero_started[-1]

    s0 = area(target[:, None])
    si = area(arr)
    both = 1.0 + np.abs(s0) + np.abs(si)
    return both / (both + np.abs(si - s0))
