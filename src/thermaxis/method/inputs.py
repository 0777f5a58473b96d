"""Time-aware inputs: first-order lags and rates of change of logged signals.

A thermal error lags the temperatures that drive it, and the logs hold the whole
history between measurements.  Two derived inputs give a linear model that history at
almost no cost, and a controller can compute both cycle by cycle:

* :func:`lag_filter` / :class:`LagState` - a causal first-order lag
  ``tau * y' = u - y`` of a sampled signal, started at ``y(t0) = u(t0)``;
* :func:`rate_of_change` / :class:`RateState` - ``(u(t) - u(t - w)) / w`` per minute.

The offline functions and the online states run the same recurrences, so a model
trained on the offline inputs sees the same numbers as the controller (to rounding).
:func:`inputs_at_measurements` evaluates both on a cleaned temperature table at the
measurements, and :func:`lag_name` / :func:`rate_name` / :func:`parse_input_name` name
the results in coefficient tables (``T5@lag30min``, ``T5@rate10min``).

Times are seconds on a strictly increasing, possibly irregular time base.  Between two
samples a signal is taken to be linear (the same assumption the cleaning makes when it
puts the logs on their grid, and that ``temperatures_in_windows`` makes when it averages
over a window).  NaN is refused: a lag at a sample depends on every sample before it, so
a hole in the history has no honest value to fill it with.
"""

from __future__ import annotations

import math
import re
from collections import deque
from collections.abc import Sequence

import numpy as np

__all__ = [
    "KINDS",
    "LagState",
    "base_of",
    "RateState",
    "input_definition",
    "input_name",
    "inputs_at_measurements",
    "lag_filter",
    "lag_name",
    "parse_input_name",
    "rate_name",
    "rate_of_change",
]

KINDS = ("lag", "rate")
# The rate is reported per minute: thermal drifts are slow, and degC per second would give
# coefficients 60 times larger than the same input per minute for no gain.
_PER_MINUTE = 60.0


# ----------------------------------------------------------------------------- checks


def _positive_seconds(value, what: str) -> float:
    try:
        seconds = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{what} must be a number of seconds, got {value!r}") from None
    if not (math.isfinite(seconds) and seconds > 0):
        raise ValueError(f"{what} must be a finite number of seconds > 0, got {value!r}")
    return seconds


def _series(t, u) -> tuple[np.ndarray, np.ndarray]:
    """Time base and values as float arrays (values (n,) or (n, m)), checked."""
    t = np.asarray(t, dtype=float)
    u = np.asarray(u, dtype=float)
    if t.ndim != 1 or t.size == 0:
        raise ValueError(
            f"time base must be a non-empty 1-D sequence of seconds, got shape {t.shape}"
        )
    if u.ndim not in (1, 2) or u.shape[0] != t.size:
        raise ValueError(f"values must have one row per time ({t.size}), got shape {u.shape}")
    bad = ~np.isfinite(t)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise ValueError(f"time of sample {i} is {t[i]:g}; expected finite seconds")
    steps = np.diff(t)
    if (steps <= 0).any():
        i = int(np.flatnonzero(steps <= 0)[0]) + 1
        raise ValueError(
            f"time base must increase strictly: sample {i} at {t[i]:g} s follows sample {i - 1} at {t[i - 1]:g} s"
        )
    missing = np.isnan(u) if u.ndim == 1 else np.isnan(u).any(axis=1)
    if missing.any():
        i = int(np.flatnonzero(missing)[0])
        raise ValueError(
            f"value of sample {i} (t = {t[i]:g} s) is NaN; a lag depends on the whole history, so the signal must "
            "have a value at every sample (fill the gap or leave the signal out)"
        )
    return t, u


def _step_checks(t, u, t_prev: float | None, what: str):
    """``(t, u)`` as a float and a float, or an array of floats (several signals at once)."""
    t = float(t)
    u = float(u) if np.ndim(u) == 0 else np.asarray(u, dtype=float)
    if not math.isfinite(t):
        raise ValueError(f"{what}: time {t!r} is not finite")
    if np.isnan(u).any():
        raise ValueError(
            f"{what}: value at t = {t!r} s is NaN; the state cannot be carried over a missing sample"
        )
    if t_prev is not None and not t > t_prev:
        raise ValueError(
            f"{what}: time must increase strictly, got t = {t!r} s after t = {t_prev!r} s"
        )
    return t, u


def _lag_coefficients(dt, tau: float):
    """``a = exp(-dt/tau)`` and ``g = tau (1 - a) / dt``, both without cancellation.

    ``g`` through expm1: for dt << tau, ``1 - exp(-x)`` computed directly would lose
    every digit that the filter's slow pole relies on.
    """
    x = np.asarray(dt, dtype=float) / tau
    return np.exp(-x), -np.expm1(-x) / x


# ----------------------------------------------------------------------------- lag


def lag_filter(t, u, tau_s: float, initial=None) -> np.ndarray:
    """Causal first-order lag ``tau * dy/dt = u - y`` of a sampled signal.

    The input is taken to be linear between samples (first-order hold), and the ODE is
    solved exactly over each interval, so for a piecewise-linear signal the result does
    not depend on how finely it is sampled: adding samples on the straight segments
    changes nothing (to rounding).

    Recurrence, with ``dt_k = t_k - t_{k-1}``, ``a_k = exp(-dt_k / tau)`` and
    ``g_k = tau (1 - a_k) / dt_k``, carried in the tracking error ``e = y - u``::

        e_0 = y_0 - u_0                                     (0 unless ``initial`` is given)
        e_k = a_k e_{k-1} - g_k (u_k - u_{k-1})
        y_k = u_k + e_k

    which is the same as ``y_k = a_k y_{k-1} + (1 - a_k) u_k - (g_k - a_k)(u_k - u_{k-1})``.
    Derivation: with ``u`` of slope ``s_k = (u_k - u_{k-1}) / dt_k`` on the interval,
    ``e' = -e / tau - s_k``, whose exact solution over ``dt_k`` is
    ``e_k = a_k e_{k-1} - s_k tau (1 - a_k)``.  Carrying ``e`` rather than ``y`` keeps
    ``a`` and ``g`` the only coefficients (both computed without cancellation, see
    :func:`_lag_coefficients`), and ``e`` stays small while ``y`` tracks ``u``.

    Parameters
    ----------
    t : strictly increasing times in seconds (irregular allowed), shape (n,).
    u : the signal at those times, shape (n,) or (n, m) (m signals filtered at once).
    tau_s : time constant in seconds, finite and > 0.
    initial : the filter's value at ``t[0]``; default ``u[0]``: the signal is taken to
        have been steady before the record starts (the run's start), so the value at a
        sample depends on the whole history since then.  A scalar, or one value per
        signal.

    Returns
    -------
    np.ndarray
        ``y`` at every sample, the shape of ``u``.

    Raises
    ------
    ValueError
        ``tau_s`` not a finite positive number; times not finite or not strictly
        increasing; a NaN value (naming the first such sample).  NaN is refused rather
        than skipped: the lag after a gap depends on what happened in it.
    """
    tau = _positive_seconds(tau_s, "time constant tau_s")
    t, u = _series(t, u)
    flat = u.ndim == 1
    u2 = u.reshape(t.size, -1)
    e = np.empty_like(u2)
    e[0] = 0.0 if initial is None else np.asarray(initial, dtype=float) - u2[0]
    if not np.isfinite(e[0]).all():
        raise ValueError(f"initial value must be finite, got {initial!r}")
    a, g = _lag_coefficients(np.diff(t), tau)
    drive = g[:, None] * np.diff(u2, axis=0)
    if a.size and (a == a[0]).all():
        # Evenly sampled (a logger's usual record): one constant pole, so the recurrence
        # is an IIR filter, which scipy runs in compiled code: e_k = -drive_k + a e_{k-1},
        # the state starting at a e_0. Imported here: only a lagged input needs it.
        from scipy.signal import lfilter

        e[1:] = lfilter([1.0], [1.0, -a[0]], -drive, axis=0, zi=a[0] * e[:1])[0]
    else:
        # Time-varying coefficients have no stable closed form over a long record (the
        # products of a_k underflow): step by step, vectorised over the signals.
        for k in range(1, t.size):
            e[k] = a[k - 1] * e[k - 1] - drive[k - 1]
    y = u2 + e
    return y.reshape(t.size) if flat else y


class LagState:
    """Online first-order lag: fed sample by sample, equal to :func:`lag_filter`.

    What a controller carries from one cycle to the next: the previous time, input and
    tracking error ``e = y - u``.  The first :meth:`update` starts the filter at
    ``initial`` (default: that sample's value), as :func:`lag_filter` starts at ``u[0]``.

    Parameters
    ----------
    tau_s : time constant in seconds, finite and > 0.
    initial : the filter's value at the first sample; default the first sample's value.

    :meth:`update` takes one value, or an array of values: several signals with the same
    time constant filtered at once, each exactly as alone (elementwise the same arithmetic).
    """

    def __init__(self, tau_s: float, initial: float | None = None):
        self.tau_s = _positive_seconds(tau_s, "time constant tau_s")
        if initial is not None and not math.isfinite(float(initial)):
            raise ValueError(f"initial value must be finite, got {initial!r}")
        self.initial = None if initial is None else float(initial)
        self.t: float | None = None  # time of the last sample (None before the first)
        self.u: float | None = None  # its value
        # The tracking error y - u at it, carried as lag_filter carries it (not y, whose
        # difference with u would round differently).
        self.e: float | None = None

    @property
    def y(self) -> float | None:
        """The filter's output at the last sample (None before the first)."""
        return None if self.t is None else self.u + self.e

    def update(self, t: float, u: float) -> float:
        """Advance to sample ``(t, u)`` (seconds, strictly after the last) and return ``y(t)``."""
        t, u = _step_checks(t, u, self.t, "LagState.update")
        if self.t is None:
            e = 0.0 if self.initial is None else self.initial - u
        else:
            a, g = _lag_coefficients(t - self.t, self.tau_s)
            # The same recurrence as lag_filter, on the tracking error e = y - u.
            e = float(a) * self.e - float(g) * (u - self.u)
        self.t, self.u, self.e = t, u, e
        return u + e


# ----------------------------------------------------------------------------- rate


def rate_of_change(t, u, window_s: float) -> np.ndarray:
    """Causal rate of change over a window, in units of ``u`` per minute.

    ``r(t_k) = (u(t_k) - u(t_k - w)) / w * 60``, with ``u(t_k - w)`` interpolated linearly
    between samples.  Where ``t_k - w`` lies before the first sample (the run's start),
    the first sample's value is used, and the difference is still divided by ``w``: the
    signal is taken to have been steady before the start, the same assumption the lag
    filter makes when it starts at ``u(t0)``.  So the rate of a ramp grows from 0 at the
    start to its slope at ``t0 + w`` and equals it from then on.

    Parameters
    ----------
    t : strictly increasing times in seconds (irregular allowed), shape (n,).
    u : the signal at those times, shape (n,) or (n, m).
    window_s : the window ``w`` in seconds, finite and > 0.

    Returns
    -------
    np.ndarray
        The rate at every sample, the shape of ``u``.

    Raises
    ------
    ValueError
        As :func:`lag_filter`, for the window and the series.
    """
    w = _positive_seconds(window_s, "rate window window_s")
    t, u = _series(t, u)
    flat = u.ndim == 1
    u2 = u.reshape(t.size, -1)
    # np.interp holds the first value to the left of t[0]: the documented start policy.
    before = np.column_stack([np.interp(t - w, t, u2[:, j]) for j in range(u2.shape[1])])
    r = (u2 - before) / w * _PER_MINUTE
    return r.reshape(t.size) if flat else r


class RateState:
    """Online rate of change over a window: fed sample by sample, equal to :func:`rate_of_change`.

    Carries the samples of the last ``window_s`` seconds plus the one just before them
    (to interpolate at ``t - w``); on a regular cycle ``dt`` that is at most
    ``ceil(w / dt) + 2`` samples, a ring buffer of fixed size on a controller.

    Parameters
    ----------
    window_s : the window ``w`` in seconds, finite and > 0.

    :meth:`update` takes one value, or an array of values (several signals at once), as
    :class:`LagState`.
    """

    def __init__(self, window_s: float):
        self.window_s = _positive_seconds(window_s, "rate window window_s")
        self.history: deque[tuple[float, float]] = deque()

    def update(self, t: float, u: float) -> float:
        """Add sample ``(t, u)`` (seconds, strictly after the last) and return the rate at ``t`` per minute."""
        t_prev = self.history[-1][0] if self.history else None
        t, u = _step_checks(t, u, t_prev, "RateState.update")
        h = self.history
        h.append((t, u))
        back = t - self.window_s
        # Drop samples no longer needed: keep the last one at or before t - w.
        while len(h) >= 2 and h[1][0] <= back:
            h.popleft()
        (t0, u0) = h[0]
        if back <= t0:
            # Before the first sample kept: either it is exactly t - w, or t - w lies
            # before the run's start and the start's value is used (as rate_of_change).
            before = u0
        else:
            t1, u1 = h[1]
            before = u0 + (u1 - u0) / (t1 - t0) * (back - t0)
        return (u - before) / self.window_s * _PER_MINUTE


# ----------------------------------------------------------------------------- names

# The base is a signal's name (no '@', which separates it from the definition); the
# number is plain decimal, as input_name writes it.
_NAME = re.compile(r"(?P<base>[^@]+)@(?P<kind>lag|rate)(?P<number>\d+(?:\.\d+)?)(?P<unit>min|s)")


def _duration_text(seconds: float) -> str:
    """Whole minutes as '30min', other durations in seconds ('45s', '90s', '0.5s')."""
    if seconds % 60 == 0:
        return f"{int(seconds // 60)}min"
    if seconds.is_integer():
        return f"{int(seconds)}s"
    text = repr(seconds)  # the shortest text that reads back as the same float
    if "e" in text:
        raise ValueError(
            f"duration {seconds!r} s cannot be written in plain decimal; use whole seconds"
        )
    return f"{text}s"


def input_name(base: str, kind: str, seconds: float) -> str:
    """Name of a derived input in coefficient tables: ``<base>@<kind><duration>``.

    ``kind`` is ``"lag"`` (time constant) or ``"rate"`` (window); whole minutes are
    written in minutes (``T5@lag30min``), anything else in seconds (``T5@lag45s``).
    Each input has exactly one name, which :func:`parse_input_name` reads back.

    Raises
    ------
    ValueError
        An empty base or one holding ``@``, an unknown kind, a duration that is not a
        finite number of seconds > 0.
    """
    if not isinstance(base, str) or not base or "@" in base:
        raise ValueError(f"signal name must be a non-empty text without '@', got {base!r}")
    if kind not in KINDS:
        raise ValueError(f"kind must be one of {', '.join(KINDS)}, got {kind!r}")
    what = "time constant" if kind == "lag" else "rate window"
    return f"{base}@{kind}{_duration_text(_positive_seconds(seconds, what))}"


def lag_name(base: str, tau_s: float) -> str:
    """``lag_name("T5", 1800) == "T5@lag30min"``; see :func:`input_name`."""
    return input_name(base, "lag", tau_s)


def rate_name(base: str, window_s: float) -> str:
    """``rate_name("T5", 600) == "T5@rate10min"``; see :func:`input_name`."""
    return input_name(base, "rate", window_s)


def base_of(name: str) -> str:
    """The logged signal an input is read from: ``base_of("T5@lag30min") == "T5"``; a plain
    signal is its own base."""
    return str(name).split("@", 1)[0]


def input_definition(name: str) -> dict:
    """What a derived input is, for ``model.json``: its channel, kind, duration and formula."""
    base, kind, seconds = parse_input_name(name)
    formula = (
        f"first-order lag y of {base}: {seconds:g} s * dy/dt = {base} - y, exact for {base} linear "
        f"between samples, started steady at the first reading"
        if kind == "lag"
        else f"rate of {base} per minute over the last {seconds:g} s: ({base}(t) - {base}(t - {seconds:g} s)) "
        f"/ {seconds:g} s * 60, the first reading held before it"
    )
    return {"of": base, "kind": kind, "seconds": seconds, "formula": formula}


def parse_input_name(name: str) -> tuple[str, str, float]:
    """``parse_input_name("T5@lag30min") == ("T5", "lag", 1800.0)``: base, kind, seconds.

    Only names as :func:`input_name` writes them are accepted, so that one input cannot
    appear in a table under two names (``T5@lag1800s`` is refused, naming
    ``T5@lag30min``).

    Raises
    ------
    ValueError
        Anything else, including a plain signal name.
    """
    match = _NAME.fullmatch(name) if isinstance(name, str) else None
    if match is None:
        raise ValueError(
            f"{name!r} is not a derived input name; expected <signal>@lag<duration> or <signal>@rate<duration>, "
            "the duration in whole minutes ('30min') or seconds ('45s'), e.g. 'T5@lag30min'"
        )
    number = float(match["number"])
    seconds = number * 60.0 if match["unit"] == "min" else number
    if not seconds > 0:
        raise ValueError(f"{name!r}: the duration must be > 0")
    canonical = input_name(match["base"], match["kind"], seconds)
    if canonical != name:
        raise ValueError(f"{name!r} is not written as thermaxis writes it; expected {canonical!r}")
    return match["base"], match["kind"], seconds


# ----------------------------------------------------------------------------- at measurements


def inputs_at_measurements(
    frame,
    measurements,
    lags_s: Sequence[float] = (),
    rates_s: Sequence[float] = (),
    *,
    at: str = "end",
    columns: Sequence[str] | None = None,
):
    """The derived inputs of each signal at each measurement.

    Parameters
    ----------
    frame : a cleaned table on a common time grid: ``time`` (datetime64, strictly
        increasing) and one column per signal, e.g. ``CleanedTemperatures.frame`` or the
        operating signals on the same grid.  Its first row is the run's start: the
        filters start there, steady (see :func:`lag_filter`), and no history before it
        exists for them.  (The assembly currently starts a run's grid a margin before
        its first measurement, so whoever wires this in decides how much history the
        lags see.)
    measurements : the measurement windows, a DataFrame with ``start`` and ``end``
        (optionally ``measurement``, carried into the result), or a sequence of
        instants (datetime64), each taken as a window of no length.
    lags_s : time constants of the lag filters, seconds.
    rates_s : windows of the rates of change, seconds (rates in units per minute).
    at : the instant of a window the inputs are evaluated at.  ``"end"`` (default): the
        last instant of the measurement, so the inputs use no data logged after the
        measurement was over.  ``"start"``: strictly causal for every point of the
        measurement, including the first one measured.  ``"mid"``: the middle.
    columns : the signals to derive from; default every column but ``time``.

    Returns
    -------
    pd.DataFrame
        One row per measurement in the given order: ``measurement``, ``start``, ``end``
        (those the windows have), ``time`` (the instant evaluated at) and, per signal in
        order, its lags in the order of ``lags_s``, then its rates, named by
        :func:`lag_name` and :func:`rate_name`.

    Notes
    -----
    The plain temperatures of a measurement (``clean.temperatures_in_windows``) are, by
    default, the time average of the linearly interpolated series over the window
    (``how="start"``: the value at its start).  The derived inputs are values at one
    instant instead, of the same linearly interpolated series: a lag is already a
    weighted average of the past with weight ``exp(-(t - s)/tau) / tau``, so averaging
    it again over a window of minutes would change it little for the time constants it
    is meant for (tens of minutes) and would break the equality with what a controller
    computes at one cycle.  As ``tau`` goes to 0 a lag tends to the temperature at
    ``at``, not to the window mean.

    Raises
    ------
    ValueError
        No ``time`` column or one not strictly increasing; an unknown ``at``; a window
        with ``end`` before ``start``; a measurement outside the frame's time span; a
        NaN that a measurement's inputs depend on, naming the signal, the time and the
        measurement (every sample up to the evaluation instant: a lag depends on all of
        them); no lag or rate configured; a bad duration or signal name.
    """
    import pandas as pd  # only this function needs pandas; the filters are plain numpy

    if "time" not in frame.columns:
        raise ValueError("temperature table: missing column 'time'")
    if at not in ("end", "start", "mid"):
        raise ValueError(f"at must be 'end', 'start' or 'mid', got {at!r}")
    lags, rates = list(lags_s), list(rates_s)
    columns = [c for c in frame.columns if c != "time"] if columns is None else list(columns)
    names = _derived_names(frame, columns, lags, rates)
    start, end, labels, out = _measurement_windows(measurements)
    # Half the window in integer nanoseconds: exact, no float rounding of the instant.
    when = {"end": end, "start": start, "mid": start + (end - start) // 2}[at]
    grid_ns = _ns(frame["time"])
    _check_within(grid_ns, when, labels)

    # Seconds since the run's start; float64 resolves nanoseconds over days.
    grid = (grid_ns - grid_ns[0]) / 1e9
    te = (when - grid_ns[0]) / 1e9
    # Only the history up to the last measurement matters (up to the grid point at or
    # after it, which the interpolation there needs); a gap after it is harmless.
    last = int(np.searchsorted(grid, te.max(), side="left"))
    grid = grid[: last + 1]
    values = frame[columns].to_numpy(dtype=float)[: last + 1]
    _check_history(columns, values, grid, grid_ns, te, when, labels)

    derived = _derived_at(grid, values, te, lags, rates, [names[c] for c in columns])
    out["time"] = when.astype("datetime64[ns]")
    return pd.concat([out, pd.DataFrame(derived, index=out.index)], axis=1)


def _derived_at(grid, values, te, lags: list, rates: list, names: list[list[str]]) -> dict:
    """Each signal's lags, then rates, at the instants ``te`` (s), by name.

    ``values`` holds one column per signal on ``grid`` (s); ``names`` their derived
    input names, per signal, in the order of ``lags`` then ``rates``.
    """
    # The evaluation instants joined to the grid, the signal interpolated linearly there:
    # the filters are exact for a linear signal between samples, so the added points
    # change nothing else, and the value at an instant between grid points is exact.
    base = np.union1d(grid, te)
    u = np.column_stack([np.interp(base, grid, values[:, j]) for j in range(values.shape[1])])
    rows = np.searchsorted(base, te)
    lagged = [lag_filter(base, u, tau)[rows] for tau in lags]
    rated = [rate_of_change(base, u, w)[rows] for w in rates]
    derived = {}
    for j, signal_names in enumerate(names):
        for name, block in zip(signal_names, lagged + rated, strict=False):
            derived[name] = block[:, j]
    return derived


def _ns(values) -> np.ndarray:
    """Instants as integer nanoseconds, so that window arithmetic is exact."""
    import pandas as pd

    return np.asarray(pd.to_datetime(values), dtype="datetime64[ns]").astype(np.int64)


def _derived_names(frame, columns: list, lags: list, rates: list) -> dict:
    """The derived input names per signal, checked to be configured, distinct and present."""
    if not lags and not rates:
        raise ValueError(
            "no derived input configured: give at least one lag time constant or rate window"
        )
    names = {c: [lag_name(c, s) for s in lags] + [rate_name(c, s) for s in rates] for c in columns}
    flat = [n for c in columns for n in names[c]]
    if len(set(flat)) < len(flat):
        twice = next(n for n in flat if flat.count(n) > 1)
        raise ValueError(
            f"derived input {twice!r} configured twice; expected distinct time constants and windows"
        )
    absent = [c for c in columns if c not in frame.columns]
    if absent:
        raise ValueError(
            f"temperature table: no column {absent[0]!r}; it has {', '.join(map(str, frame.columns))}"
        )
    return names


def _measurement_windows(measurements):
    """Start and end (ns), labels and the carried columns of the measurement windows.

    A DataFrame gives windows (``start``, ``end``, optionally ``measurement``); a
    sequence of instants gives windows of no length.
    """
    import pandas as pd

    if isinstance(measurements, pd.DataFrame):
        for column in ("start", "end"):
            if column not in measurements.columns:
                raise ValueError(
                    f"measurement windows: missing column {column!r} (expected start, end)"
                )
        start, end = _ns(measurements["start"]), _ns(measurements["end"])
        labels = (
            [str(m) for m in measurements["measurement"]]
            if "measurement" in measurements.columns
            else [str(i) for i in range(len(measurements))]
        )
        out = measurements[
            [c for c in ("measurement", "start", "end") if c in measurements.columns]
        ]
        out = out.reset_index(drop=True).copy()
    else:
        start = end = _ns(list(measurements))
        labels = [str(i) for i in range(start.size)]
        out = pd.DataFrame(index=range(start.size))
    if start.size == 0:
        raise ValueError("no measurement given")
    if (end < start).any():
        i = int(np.flatnonzero(end < start)[0])
        raise ValueError(
            f"measurement {labels[i]}: its window ends before it starts; expected start <= end"
        )
    return start, end, labels, out


def _check_within(grid_ns: np.ndarray, when: np.ndarray, labels: list) -> None:
    """The grid strictly increasing and every evaluation instant within it."""
    import pandas as pd

    if grid_ns.size == 0 or (np.diff(grid_ns) <= 0).any():
        raise ValueError("temperature table: 'time' must be non-empty and strictly increasing")
    outside = (when < grid_ns[0]) | (when > grid_ns[-1])
    if outside.any():
        i = int(np.flatnonzero(outside)[0])
        raise ValueError(
            f"measurement {labels[i]} at {pd.Timestamp(when[i])} lies outside the temperature table "
            f"({pd.Timestamp(grid_ns[0])} to {pd.Timestamp(grid_ns[-1])})"
        )


def _check_history(columns, values, grid, grid_ns, te, when, labels) -> None:
    """No NaN in the history a measurement's lags and rates depend on (every sample since the start)."""
    import pandas as pd

    for j, column in enumerate(columns):
        holes = np.flatnonzero(np.isnan(values[:, j]))
        if holes.size:
            k = int(holes[0])
            # The first measurement whose history reaches grid point k.
            needs = te > grid[k - 1] if k > 0 else np.ones(te.size, dtype=bool)
            i = int(np.flatnonzero(needs)[np.argmin(te[needs])])
            raise ValueError(
                f"signal {column!r} has no value at {pd.Timestamp(grid_ns[k])} in the temperature table, and its "
                f"lags and rates at measurement {labels[i]} ({pd.Timestamp(when[i])}) depend on every sample since "
                f"the run's start ({pd.Timestamp(grid_ns[0])}); fill the gap or leave the signal out"
            )
