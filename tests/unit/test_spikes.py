"""Spike detection that keeps trends: generated series whose spikes are known, and the twin's."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from helpers import DEFAULTS, REPO
from thermaxis.cleaning.spikes import (
    excursions,
    noise_sigma,
    resolution,
    spike_limit,
    spike_mask,
)
from thermaxis.cleaning.temperatures import clean_temperatures
from thermaxis.dataset.reader import load_dataset, read_run
from thermaxis.twin import faults

SETTINGS = DEFAULTS.cleaning.temperatures
LIMITS = dict(
    threshold=SETTINGS.spike_threshold,
    min_deviation=SETTINGS.spike_min_deviation_c,
    max_rate_c_per_min=SETTINGS.spike_max_rate_c_per_min,
    window_s=SETTINGS.spike_window_s,
)
DURATION_MIN = 240.0
RISE_C = 8.0


def _steepening(u):
    return np.expm1(3.0 * u) / np.expm1(3.0)


def _flattening(u):
    return -np.expm1(-4.0 * u) / -np.expm1(-4.0)


def _flat_then_steep(u):
    # Flat for 80 % of the run, then a parabola: the steepest at the very last sample.
    return np.clip(u - 0.8, 0.0, None) ** 2 / 0.04


def _steep_then_flat(u):
    return 1.0 - _flat_then_steep(1.0 - u)


SHAPES = {
    "steepening": _steepening,
    "flattening": _flattening,
    "flat_then_steep": _flat_then_steep,
    "steep_then_flat": _steep_then_flat,
}


def quantised_ramp(shape, step_c, interval_s, noise_c=0.0, seed=0):
    """Seconds and readings of a heating ramp as a quantised logger reports it."""
    t = np.arange(0.0, DURATION_MIN * 60.0 + interval_s / 2, interval_s)
    rng = np.random.default_rng(seed)
    truth = 20.0 + RISE_C * SHAPES[shape](t / t[-1]) + rng.normal(0.0, noise_c, t.size)
    return t, np.round(truth / step_c) * step_c


def test_the_ramps_stay_below_the_rate_limit():
    # The generated heating is physical (the steepest is 0.33 C/min, at the end of
    # flat_then_steep: 8 C * 2 * 0.2 / 0.04 / 240 min): no sample is a spike by its rate.
    for shape in SHAPES:
        t, x = quantised_ramp(shape, 1e-6, 10.0)
        assert np.max(np.abs(np.diff(x)) / (np.diff(t) / 60.0)) < 0.34


@pytest.mark.parametrize("interval_s", [10.0, 60.0, 300.0])
@pytest.mark.parametrize("step_c", [0.1, 0.01])
@pytest.mark.parametrize("shape", sorted(SHAPES))
def test_no_sample_of_a_quantised_ramp_is_a_spike(shape, step_c, interval_s):
    t, x = quantised_ramp(shape, step_c, interval_s)
    assert not spike_mask(t, x, **LIMITS).any()
    # And on noisy readings: 0.03 C of noise, quantised (7 noise sigmas stay below 0.2 C).
    t, x = quantised_ramp(shape, step_c, interval_s, noise_c=0.03, seed=int(interval_s))
    assert not spike_mask(t, x, **LIMITS).any()


def test_the_reported_record_end_is_kept():
    # The report's sensor T10: the last seven 5-minute readings; the old filter flagged 8.3.
    x = np.array([8.0, 8.0, 8.0, 8.0, 8.1, 8.2, 8.3])
    assert not spike_mask(np.arange(7) * 300.0, x, **LIMITS).any()


def with_spikes(t, x, interval_s):
    """Single and double spikes in the middle and at both ends, and the truth of where."""
    x = x.copy()
    n = x.size
    # At the ends only the rate tells: the second of a double end spike must depart
    # faster than 1 C/min over two intervals (10 min at 5-minute logging).
    end = 20.0 if interval_s >= 300 else 4.0
    spikes = {
        0: +end,  # single, first sample
        n // 4: +3.0,  # single
        n // 2: -2.5,  # double ...
        n // 2 + 1: -2.0,
        3 * n // 4: +1.0,  # a small single
        n - 2: -end,  # double, last two samples
        n - 1: -end - 0.5,
    }
    for i, delta in spikes.items():
        x[i] += delta
    truth = np.zeros(n, dtype=bool)
    truth[list(spikes)] = True
    return x, truth


@pytest.mark.parametrize("interval_s", [10.0, 60.0, 300.0])
@pytest.mark.parametrize("shape", ["steepening", "flat_then_steep"])
def test_single_and_double_spikes_in_the_middle_and_at_the_ends_are_found(shape, interval_s):
    t, clean = quantised_ramp(shape, 0.1, interval_s, noise_c=0.03, seed=3)
    x, truth = with_spikes(t, clean, interval_s)
    np.testing.assert_array_equal(spike_mask(t, x, **LIMITS), truth)


def test_an_end_spike_within_the_rate_limit_is_kept():
    # 0.5 C within 5 minutes is 0.1 C/min: a real end of a record may do that.
    t, x = quantised_ramp("steepening", 0.1, 300.0)
    x[-1] += 0.5
    assert not spike_mask(t, x, **LIMITS).any()
    # The same jump within 10 s is 3 C/min: a spike.
    t, x = quantised_ramp("steepening", 0.1, 10.0)
    x[-1] += 0.5
    assert np.flatnonzero(spike_mask(t, x, **LIMITS)).tolist() == [t.size - 1]


def test_the_limit_never_falls_below_two_resolution_steps():
    # A 0.5 C logger that flickers to the next level now and then, with no minimum
    # deviation configured: its noise sigma is 0 (most samples lie on their neighbours' line).
    x = np.full(60, 20.0)
    x[5::10] = 20.5
    t = np.arange(x.size) * 60.0
    assert (resolution(x), noise_sigma(t, x)) == (0.5, 0.0)
    strict = dict(LIMITS, min_deviation=0.0)
    assert not spike_mask(t, x, **strict).any()
    x[30] = 21.5  # 1.5 C beyond both neighbours: more than two steps of 0.5 C
    assert np.flatnonzero(spike_mask(t, x, **strict)).tolist() == [30]


def test_noise_sigma_of_white_noise_on_a_ramp():
    rng = np.random.default_rng(11)
    t = np.arange(20000) * 10.0
    x = 20.0 + 0.001 * t + rng.normal(0.0, 0.05, t.size)
    assert noise_sigma(t, x) == pytest.approx(0.05, rel=0.05)


def test_a_tie_with_the_limit_is_not_a_spike():
    # 20.6 is exactly 0.2 beyond both neighbours in 0.1 C steps: 0.20000000000000284.
    x = np.array([20.4, 20.4, 20.4, 20.6, 20.4, 20.4, 20.4])
    assert float(x[3] - x[2]) > 0.2
    assert not spike_mask(np.arange(7) * 60.0, x, **LIMITS).any()


def test_the_cleaning_counts_the_spikes_it_removes():
    t, clean = quantised_ramp("flat_then_steep", 0.1, 300.0)
    x, truth = with_spikes(t, clean, 300.0)
    frame = pd.DataFrame(
        {"time": pd.Timestamp("2024-01-01") + pd.to_timedelta(t, unit="s"), "T10": x}
    )
    result = clean_temperatures({"box": frame}, {}, replace(SETTINGS, interval_s=300.0))
    assert int(result.qc.loc[0, "n_spikes"]) == int(truth.sum())
    # The last two readings are spikes: the grid ends at the last reading kept.
    assert result.frame["T10"].iloc[-1] == pytest.approx(clean[-3])
    assert result.frame["time"].iloc[-1] == frame["time"].iloc[-3]


@pytest.mark.skipif(not (REPO / "data/raw/twin/dataset.yaml").is_file(), reason="no twin")
@pytest.mark.parametrize("run", ["E1", "E2", "E3", "E4"])
def test_every_spike_injected_into_the_twin_is_found_and_nothing_else(run):
    dataset = load_dataset(REPO / "data" / "raw" / "twin")
    raw = read_run(dataset, run)
    box = raw.sources["box"].drop_duplicates()
    first = raw.windows()["start"].iloc[0]
    minutes = ((box["time"] - first) / pd.Timedelta(minutes=1)).to_numpy()
    seconds = minutes * 60.0
    for sensor in (c for c in box.columns if c != "time"):
        values = box[sensor].to_numpy(dtype=float)
        ok = np.isfinite(values) & (values < faults.OPEN_CIRCUIT_C)
        found = minutes[ok][spike_mask(seconds[ok], values[ok], **LIMITS)]
        injected = [s.minute for s in faults.SPIKES if (s.run, s.sensor) == (run, sensor)]
        np.testing.assert_allclose(np.sort(found), injected, atol=0.1)


def _limit(t, x):
    return spike_limit(t, x, LIMITS["threshold"], LIMITS["min_deviation"])


@pytest.mark.parametrize("interval_s", [10.0, 60.0, 300.0])
@pytest.mark.parametrize("shape", sorted(SHAPES))
def test_a_quantised_ramp_has_no_excursion(shape, interval_s):
    t, x = quantised_ramp(shape, 0.1, interval_s, noise_c=0.03, seed=5)
    assert excursions(t, x, _limit(t, x)) == []


@pytest.mark.parametrize("interval_s", [10.0, 60.0, 300.0])
def test_a_20_minute_excursion_is_kept_and_found_where_it_is(interval_s):
    # +1.5 C for 20 minutes from minute 100 on a quantised, noisy ramp: no sample of it is
    # a spike (the old rule ate such a departure a sample at a time), and it is one
    # excursion spanning exactly its readings, of about its size.
    t, x = quantised_ramp("flattening", 0.1, interval_s, noise_c=0.03, seed=7)
    inside = (t >= 6000.0) & (t < 7200.0)
    x = np.where(inside, x + 1.5, x)
    assert not spike_mask(t, x, **LIMITS).any()
    ((first, last, size),) = excursions(t, x, _limit(t, x))
    assert (first, last) == (np.flatnonzero(inside)[0], np.flatnonzero(inside)[-1])
    assert size == pytest.approx(1.5, abs=0.2)


def test_an_isolated_5_c_spike_is_still_replaced_and_is_no_excursion():
    t, x = quantised_ramp("steepening", 0.1, 60.0, noise_c=0.03, seed=9)
    x[120] += 5.0
    assert np.flatnonzero(spike_mask(t, x, **LIMITS)).tolist() == [120]
    kept = np.arange(t.size) != 120
    assert excursions(t[kept], x[kept], _limit(t[kept], x[kept])) == []


@pytest.mark.parametrize("interval_s", [1.0, 10.0, 60.0])
def test_an_up_and_down_glitch_is_one_spike_and_no_excursion(interval_s):
    # +3 C then -3 C off a noisy quantised ramp (interference that overshoots and
    # undershoots): each half lies beside the other, so neither alone returns to the trend.
    # Both go, and the record has no excursion left; before, the pair was kept and a
    # later pair made a false 'excursion' of every sample between them.
    t, x = quantised_ramp("steepening", 0.1, interval_s, noise_c=0.03, seed=5)
    for i in (t.size // 3, 2 * t.size // 3):
        x[i] += 3.0
        x[i + 1] -= 3.0
    spikes = spike_mask(t, x, **LIMITS)
    assert np.flatnonzero(spikes).tolist() == [
        t.size // 3,
        t.size // 3 + 1,
        2 * t.size // 3,
        2 * t.size // 3 + 1,
    ]
    kept = ~spikes
    assert excursions(t[kept], x[kept], _limit(t[kept], x[kept])) == []


def test_heavy_tailed_noise_on_a_flat_sensor_makes_no_excursion():
    # A noisy sensor whose readings scatter with heavy tails (Student t, 3 degrees of
    # freedom) on a slow random wander, every 15 s, as fl_thermal's T16: nothing departs.
    # Two noise extremes must not tilt the trend a departure is measured from (before,
    # 9 'excursions' in these 20 records, up to 5.5 h long); a lone reading that the
    # spike filter leaves may still be named.
    longest = 0
    for seed in range(20):
        rng = np.random.default_rng(seed)
        wander = np.zeros(2000)
        for k in range(1, wander.size):
            wander[k] = 0.9 * wander[k - 1] + rng.normal(0.0, 0.03)
        t, x = np.arange(wander.size) * 15.0, 25.0 + wander + 0.07 * rng.standard_t(3, wander.size)
        kept = ~spike_mask(t, x, **LIMITS)
        found = excursions(t[kept], x[kept], _limit(t[kept], x[kept]))
        longest = max([longest, *(last - first + 1 for first, last, _ in found)])
    assert longest == 1


def test_a_departure_that_does_not_return_is_no_spike():
    # The sensor: off its rise by 2.8 C, then 1.6, 1.8, 1.5, 1.4 on 5-minute logging.
    t = np.arange(40) * 300.0
    x = np.round(20.0 + 0.004 * t / 60.0, 1)
    x[20:25] += np.array([2.8, 1.6, 1.8, 1.5, 1.4])
    assert spike_mask(t, x, **LIMITS)[20:25].sum() <= 1  # a 0.2 C wiggle on it may be one
    ((first, last, size),) = excursions(t, x, _limit(t, x))
    assert (first, last) == (20, 24) and size == pytest.approx(1.6, abs=0.15)  # the median


@pytest.mark.parametrize("policy", ["keep", "fault"])
def test_an_excursion_is_kept_or_dropped_as_a_fault_and_said_so(policy):
    t, x = quantised_ramp("flattening", 0.1, 60.0, noise_c=0.03, seed=7)
    inside = (t >= 6000.0) & (t < 7200.0)
    frame = pd.DataFrame(
        {
            "time": pd.Timestamp("2024-01-01") + pd.to_timedelta(t, unit="s"),
            "T3": np.where(inside, x + 1.5, x),
        }
    )
    settings = replace(SETTINGS, interval_s=60.0, excursions=policy)
    result = clean_temperatures({"box": frame}, {}, settings)
    (event,) = result.excursions.itertuples()
    assert (event.sensor, event.start, event.end) == (
        "T3",
        frame["time"][inside].iloc[0],
        frame["time"][inside].iloc[-1],
    )
    grid = result.frame.set_index("time")["T3"]
    middle = frame["time"][inside].iloc[10]
    if policy == "keep":
        assert event.action == "kept as data" and grid[middle] == pytest.approx(x[inside][10] + 1.5)
    else:
        # Dropped: a 20-minute hole, longer than max_gap_s (600 s), left NaN on the grid.
        assert event.action == "dropped as a sensor fault" and np.isnan(grid[middle])
