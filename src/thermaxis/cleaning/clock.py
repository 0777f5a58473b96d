"""Clock offsets between temperature devices, estimated by lagged correlation against a reference source."""

from __future__ import annotations

import numpy as np
import pandas as pd

from thermaxis.cleaning._timebase import _NS, MAD_TO_SIGMA, _as_ns

__all__ = [
    "estimate_clock_offset",
]
# Clock-offset estimation: at most this many samples per correlation (a slow thermal
# signal needs no more), and only this many sensor pairs searched over all lags.
_MAX_LAG_SAMPLES = 2000
_SEARCHED_PAIRS = 32
# Below this peak correlation the series share no transient and the lag is noise.
_MIN_PEAK_CORRELATION = 0.5


# ----------------------------------------------------------------------------- clock offsets


class OffsetNotFound(ValueError):
    """No clock offset could be estimated. ``reason`` says why in a phrase, without the
    message's advice: the cleaning quotes it when it keeps the declared offset instead."""

    def __init__(self, message: str, reason: str):
        super().__init__(message)
        self.reason = reason


def _detrend(t: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Residuals of a straight line in time, fitted per row of ``values``."""
    tc = t - t.mean()
    centred = values - values.mean(axis=-1, keepdims=True)
    slope = (centred @ tc) / (tc @ tc)
    return centred - np.multiply.outer(slope, tc)


def _noise_variance(t: np.ndarray, v: np.ndarray) -> float:
    """Robust white-noise variance of a smooth signal's samples.

    Each inner sample is compared with the straight line through its two neighbours;
    for white noise of variance s2 that residual has variance s2 * (1 + (h1^2 + h2^2) / (h1 + h2)^2).
    """
    if v.size < 3:
        return 0.0
    h1, h2 = np.diff(t[:-1]), np.diff(t[1:])
    residual = v[1:-1] - (h2 * v[:-2] + h1 * v[2:]) / (h1 + h2)
    scaled = residual / np.sqrt(1 + (h1**2 + h2**2) / (h1 + h2) ** 2)
    return float((MAD_TO_SIGMA * np.median(np.abs(scaled))) ** 2)


def _lag_correlation(
    sparse_t, sparse_v, dense_t, dense_v, lags_s: np.ndarray, sign: int
) -> np.ndarray:
    """Correlation of the detrended sparse samples with the dense series, per lag.

    The dense series is interpolated at the sparse series' own sample times (moved by
    ``sign * lag``), never the other way round: interpolating a sparse, quantised
    series would blur the transient that carries the timing.  Interpolating between
    two noisy samples averages their noise, which would favour lags that fall between
    the dense samples; the expected noise lost that way is added back to the norm.
    """
    span = np.abs(lags_s).max()
    t = (sparse_t - dense_t[0]) / _NS
    td = (dense_t - dense_t[0]) / _NS
    keep = (t >= span) & (t <= td[-1] - span)  # the same samples at every lag
    t, v = t[keep], sparse_v[keep]
    stride = max(1, -(-t.size // _MAX_LAG_SAMPLES))
    t, v = t[::stride], v[::stride]
    if t.size < 4:
        return np.full(lags_s.size, np.nan)
    a = _detrend(t, v)
    noise = _noise_variance(td, dense_v)
    out = np.full(lags_s.size, np.nan)
    chunk = max(1, 2_000_000 // t.size)  # bounds the memory of the (lags x samples) arrays
    for first in range(0, lags_s.size, chunk):
        q = t[None, :] + sign * lags_s[first : first + chunk, None]
        j = np.clip(np.searchsorted(td, q, side="right") - 1, 0, td.size - 2)
        w = np.clip((q - td[j]) / (td[j + 1] - td[j]), 0.0, 1.0)
        b = _detrend(t, dense_v[j] * (1 - w) + dense_v[j + 1] * w)
        norm2 = (b * b).sum(axis=1) + noise * (2 * w * (1 - w)).sum(axis=1)
        norm = np.sqrt(norm2 * (a @ a))
        out[first : first + chunk] = np.divide(
            b @ a, norm, out=np.full(norm.size, np.nan), where=norm > 0
        )
    return out


def _pair_correlation(series, reference, lags_s: np.ndarray) -> np.ndarray:
    (s_t, s_v), (r_t, r_v) = series, reference
    if s_t.size < 4 or r_t.size < 4:
        return np.full(lags_s.size, np.nan)
    if np.median(np.diff(s_t)) >= np.median(np.diff(r_t)):
        return _lag_correlation(s_t, s_v, r_t, r_v, lags_s, +1)
    return _lag_correlation(r_t, r_v, s_t, s_v, lags_s, -1)


def _best_offset(series, reference, max_offset_s: float, step_s: float):
    """(offset_s, peak correlation) of the best-matching (series, reference) pair.

    ``series`` and ``reference`` are lists of (t_ns, v) pairs of valid samples; all
    series share one clock.  The offset L moves the series' times to ``t + L``.  Pairs
    are ranked by their correlation at lag 0 and only the best few are searched over
    all lags, which keeps 64 x 64 sensors affordable.
    """
    max_lag = int(np.ceil(max_offset_s / step_s))
    lags = np.arange(-max_lag, max_lag + 1) * step_s
    pairs = [(s, r) for s in series for r in reference]
    if len(pairs) > _SEARCHED_PAIRS:
        at_zero = np.array([_pair_correlation(s, r, np.zeros(1))[0] for s, r in pairs])
        order = np.argsort(-np.nan_to_num(at_zero, nan=-np.inf), kind="stable")
        pairs = [pairs[i] for i in order[:_SEARCHED_PAIRS]]
    best_peak, best_corr = -np.inf, None
    for s, r in pairs:
        corr = _pair_correlation(s, r, lags)
        if np.isfinite(corr).any() and np.nanmax(corr) > best_peak:
            best_peak, best_corr = float(np.nanmax(corr)), corr
    if best_corr is None:
        reason = (
            f"the series overlap too little for a search of +/-{max_offset_s:g} s or do not vary"
        )
        raise OffsetNotFound(f"cannot estimate a clock offset: {reason}", reason)
    if best_peak < _MIN_PEAK_CORRELATION:
        reason = f"best correlation {best_peak:.2f} < {_MIN_PEAK_CORRELATION}"
        raise OffsetNotFound(
            f"cannot estimate a clock offset: {reason} "
            "(no shared transient; give the offset in dataset.yaml instead)",
            reason,
        )
    j = int(np.nanargmax(best_corr))
    if j in (0, best_corr.size - 1):
        reason = f"estimated clock offset reaches the search limit +/-{max_offset_s:g} s"
        raise OffsetNotFound(
            f"{reason} (no shared transient? give the offset in dataset.yaml instead)", reason
        )
    # A parabola through the peak and its neighbours refines the lag below one step.
    c0, c1, c2 = best_corr[j - 1], best_corr[j], best_corr[j + 1]
    curvature = c0 - 2 * c1 + c2
    shift = 0.5 * (c0 - c2) / curvature if np.isfinite(curvature) and curvature < 0 else 0.0
    return float(lags[j] + np.clip(shift, -0.5, 0.5) * step_s), best_peak


def _valid_samples(obj) -> list[tuple[np.ndarray, np.ndarray]]:
    frame = obj.to_frame() if isinstance(obj, pd.Series) else obj
    if not isinstance(frame.index, pd.DatetimeIndex):
        raise ValueError("estimate_clock_offset expects series indexed by time (a DatetimeIndex)")
    t = _as_ns(frame.index)
    out = []
    for column in frame.columns:
        v = frame[column].to_numpy(dtype=float)
        ok = np.isfinite(v)
        out.append((t[ok], v[ok]))
    return out


def estimate_clock_offset(series, reference, max_offset_s: float, step_s: float) -> float:
    """Seconds to ADD to ``series``' timestamps to put it on ``reference``'s clock.

    For every candidate lag L (a multiple of ``step_s`` within ``+/- max_offset_s``)
    the denser of the two series is interpolated at the sparser one's own sample
    times (shifted by L); both are detrended by a straight line in time and
    correlated.  The best lag is refined by a parabola through the correlation peak.

    Parameters
    ----------
    series : pd.Series indexed by time (DatetimeIndex), NaN = missing.
    reference : pd.Series or pd.DataFrame indexed by time; with several columns the
        column whose correlation peak is highest decides.
    max_offset_s, step_s : search range and resolution, seconds (the cleaning uses
        :class:`thermaxis.config.TemperatureCleaning`'s ``max_offset_s`` and ``offset_step_s``).

    Returns
    -------
    float

    Raises
    ------
    ValueError
        When the series overlap too little, or the peak lies at the search limit.

    Notes
    -----
    Limits: this only works when both sensors see the *same* temperature transient
    (a machine start, a door opening) within the search range.  It measures the
    total delay, so a sensor whose thermal response genuinely lags the reference
    (another location, a thicker housing) is "corrected" by its physical lag too;
    compare sensors at the same spot (e.g. motor shell vs. motor internal).  Sparse
    and quantised data limit the precision: a 60 s, 0.1 C-quantised series against
    a 10 s reference sharing a 10 C warm-up came out within about +/-3 s of the true
    offset, depending on where its samples fall.  A monotone drift alone carries no
    timing information (the detrending removes it).
    """
    if not isinstance(series, pd.Series):
        raise ValueError("estimate_clock_offset expects series as a pd.Series indexed by time")
    offset, _ = _best_offset(
        _valid_samples(series), _valid_samples(reference), max_offset_s, step_s
    )
    return offset
