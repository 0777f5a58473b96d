"""Tests of thermaxis.cleaning: one per fault class, on small series whose truth is known."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from helpers import DEFAULTS
from helpers.builders import write_dataset
from thermaxis.cleaning.clock import estimate_clock_offset
from thermaxis.cleaning.passes import combine_passes, run_targets, without_strays
from thermaxis.cleaning.run import clean_run, cleaning_events
from thermaxis.cleaning.temperatures import CleanedTemperatures, clean_temperatures
from thermaxis.cleaning.windows import gap_overlaps, temperatures_in_windows
from thermaxis.config import Settings

T0 = pd.Timestamp("2022-05-10T09:00:00")  # a whole multiple of 10 s since the epoch
SETTINGS = DEFAULTS.cleaning.temperatures


def at(seconds) -> pd.DatetimeIndex:
    return T0 + pd.to_timedelta(np.asarray(seconds, dtype=float), unit="s")


def ramp(seconds):
    """20 C rising 0.6 C per minute: linear, so linear interpolation reproduces it exactly."""
    return 20.0 + 0.01 * np.asarray(seconds, dtype=float)


def source(seconds, **columns) -> pd.DataFrame:
    frame = pd.DataFrame({"time": at(seconds).astype("datetime64[ns]")})
    for name, values in columns.items():
        frame[name] = np.asarray(values, dtype=float)
    return frame


def grid_seconds(frame: pd.DataFrame) -> np.ndarray:
    return ((frame["time"] - T0) / pd.Timedelta(seconds=1)).to_numpy()


def qc_of(result: CleanedTemperatures, sensor: str) -> pd.Series:
    return result.qc.set_index("sensor").loc[sensor]


def clean(sources, offsets=None, **settings):
    return clean_temperatures(
        sources, offsets or {}, replace(DEFAULTS.cleaning.temperatures, **settings)
    )


# ----------------------------------------------------------------------------- grid and ramps


def test_grid_is_aligned_to_whole_intervals_and_ramp_is_exact():
    s = np.arange(3, 600, 10.0)  # samples 3 s off the grid
    result = clean({"box": source(s, T1=ramp(s))})
    t = grid_seconds(result.frame)
    assert t[0] == 10 and t[-1] == 590  # ceil(3) and floor(593) to multiples of 10 s
    assert np.all(np.diff(t) == 10)
    assert result.frame["time"].dtype == "datetime64[ns]"
    np.testing.assert_allclose(result.frame["T1"], ramp(t), atol=1e-9)
    assert list(result.qc.columns[:2]) == ["sensor", "source"]


def test_explicit_start_and_end_span_the_grid():
    s = np.arange(0, 1000, 10.0)
    result = clean_temperatures(
        {"box": source(s, T1=ramp(s))}, {}, SETTINGS, start=at([95])[0], end=at([305])[0]
    )
    np.testing.assert_array_equal(grid_seconds(result.frame), np.arange(100, 301, 10))


def test_irregular_sampling_with_lost_packets_is_resampled_exactly():
    rng = np.random.default_rng(11)
    s = np.cumsum(rng.uniform(20, 40, 200))  # wireless: ~30 s, irregular
    lost = np.zeros(s.size, bool)
    lost[[20, 21, 60, 130]] = True  # lost packets: 60-100 s holes, well below max_gap_s
    result = clean({"nut": source(s[~lost], T11=ramp(s[~lost]))})
    t = grid_seconds(result.frame)
    np.testing.assert_allclose(result.frame["T11"], ramp(t), atol=1e-9)
    qc = qc_of(result, "T11")
    assert qc["n_raw"] == 196 and qc["n_long_gap"] == 0
    # grid points inside the three holes (each longer than 1.5 x the median spacing)
    kept = s[~lost]
    holes = [
        (kept[i], kept[i + 1])
        for i in np.flatnonzero(np.diff(kept) > 1.5 * np.median(np.diff(kept)))
    ]
    expected = sum(((t > a) & (t < b)).sum() for a, b in holes)
    assert qc["n_interpolated"] == expected > 0


def test_sources_at_different_rates_share_one_grid():
    box_s = np.arange(0, 1200, 10.0)
    hmi_s = np.arange(5, 1200, 60.0)
    result = clean(
        {"box": source(box_s, T1=ramp(box_s)), "hmi": source(hmi_s, T12=2 * ramp(hmi_s))}
    )
    t = grid_seconds(result.frame)
    assert list(result.frame.columns) == ["time", "T1", "T12"]
    inside = (t >= hmi_s[0]) & (t <= hmi_s[-1])
    np.testing.assert_allclose(result.frame["T12"][inside], 2 * ramp(t[inside]), atol=1e-9)
    assert result.qc.set_index("sensor")["source"].to_dict() == {"T1": "box", "T12": "hmi"}


# ----------------------------------------------------------------------------- duplicates


def test_exact_duplicate_rows_are_dropped_and_counted():
    s = np.arange(0, 300, 10.0)
    frame = source(s, T1=ramp(s), T2=ramp(s) + 1)
    frame = pd.concat([frame, frame.iloc[[4, 9, 9]]]).sort_values(
        "time", kind="stable", ignore_index=True
    )
    result = clean({"box": frame})
    t = grid_seconds(result.frame)
    np.testing.assert_allclose(result.frame["T1"], ramp(t), atol=1e-9)
    assert qc_of(result, "T1")["n_duplicates"] == 3
    assert qc_of(result, "T1")["n_raw"] == s.size + 3
    assert qc_of(result, "T1")["n_spikes"] == 0


def test_repeated_timestamp_with_different_values_is_averaged():
    s = np.array([0, 10, 20, 20, 30, 40.0])
    values = np.array([20.0, 20.1, 20.1, 20.3, 20.4, 20.5])
    result = clean({"box": source(s, T1=values)})
    assert result.frame["T1"].iloc[2] == pytest.approx(20.2)
    assert qc_of(result, "T1")["n_duplicates"] == 1


def test_repeated_timestamps_with_different_values_are_named_exact_repeats_are_not():
    # T1 is read twice at 20 s (20.1 and 20.3) and at 40 s (20.5 and 20.45); T2 repeats its
    # 20 s reading exactly; the whole 60 s row is repeated. The box's clock is 5 s off.
    s = np.array([0, 10, 20, 20, 30, 40, 40, 50, 60, 60.0])
    t1 = [20.0, 20.1, 20.1, 20.3, 20.4, 20.5, 20.45, 20.6, 20.7, 20.7]
    t2 = [21.0, 21.1, 21.2, 21.2, 21.3, 21.4, 21.4, 21.5, 21.6, 21.6]
    result = clean({"box": source(s, T1=t1, T2=t2)}, offsets={"box": 5.0})
    merged = result.merged.set_index("sensor")
    assert list(merged.index) == ["T1"]
    assert merged.loc["T1", "source"] == "box"
    assert merged.loc["T1", "n_timestamps"] == 2
    assert merged.loc["T1", "first"] == at([25])[0]  # on the corrected clock, as excursions
    assert merged.loc["T1", "spread_c"] == pytest.approx(0.2)


def test_a_merged_timestamp_is_a_warning_naming_the_file_and_a_cleaning_event(tmp_path):
    dataset = write_dataset(tmp_path / "tiny")
    log = dataset / "R1" / "temperatures" / "box.csv"
    lines = log.read_text().splitlines()
    cells = lines[10].split(",")
    repeated = [cells[0], f"{float(cells[2]) + 0.25:.6f}"]  # S2 read again, 0.25 C higher
    lines.insert(11, ",".join([repeated[0], cells[1], repeated[1], *cells[3:]]))
    log.write_text("\n".join(lines) + "\n")
    cleaned = clean_run(dataset, "R1", DEFAULTS.cleaning, [])
    assert cleaned.error is None
    (warning,) = [w for w in cleaned.warnings if "repeated timestamp" in w]
    assert str(log) in warning and "sensor S2 has 1 repeated" in warning
    (event,) = cleaning_events(cleaned.tables.qc).itertuples()
    assert (event.run, event.sensor, event.finding) == ("R1", "S2", "repeated_timestamps")
    assert event.start == event.end == pd.Timestamp(cells[0])  # the log has no clock offset
    assert event.size_c == pytest.approx(0.25)


def test_open_circuit_value_at_a_repeated_timestamp_never_enters_the_mean():
    s = np.array([0, 10, 20, 20, 30, 40.0])
    values = np.array([20.0, 20.1, 850.0, 20.25, 20.3, 20.4])
    result = clean({"box": source(s, T1=values)})
    assert result.frame["T1"].iloc[2] == pytest.approx(
        20.25
    )  # the valid reading, not an interpolation
    assert qc_of(result, "T1")["n_out_of_range"] == 1
    assert qc_of(result, "T1")["n_duplicates"] == 0  # only one valid reading at 20 s


# ----------------------------------------------------------------------------- clock offsets


def test_given_clock_offset_is_added_to_the_timestamps():
    true_s = np.arange(0, 1200, 60.0)
    stamped = true_s - 7.0  # this clock runs 7 s behind: add +7 s
    result = clean({"hmi": source(stamped, T12=ramp(true_s))}, {"hmi": 7.0})
    t = grid_seconds(result.frame)
    np.testing.assert_allclose(result.frame["T12"], ramp(t), atol=1e-9)
    assert t[0] == 0
    assert qc_of(result, "T12")["clock_offset_s"] == 7.0
    assert not qc_of(result, "T12")["offset_estimated"]


def warm_up(seconds):
    """A machine start at 1000 s (10 C exponential rise) and a cooling at 5000 s."""
    s = np.asarray(seconds, dtype=float)
    rise = np.where(s > 1000, 10 * (1 - np.exp(-(s - 1000) / 600)), 0.0)
    fall = np.where(s > 5000, -4 * (1 - np.exp(-(s - 5000) / 400)), 0.0)
    return 25.0 + rise + fall


@pytest.mark.parametrize("true_offset", [-23.0, 6.4, 41.0])
def test_clock_offset_is_estimated_on_a_shared_transient(true_offset):
    rng = np.random.default_rng(3)
    ref_s = np.arange(0, 9600, 10.0)
    reference = pd.Series(warm_up(ref_s) + rng.normal(0, 0.02, ref_s.size), index=at(ref_s))
    true_s = np.arange(0, 9600, 10.0)
    series = pd.Series(
        warm_up(true_s) + rng.normal(0, 0.02, true_s.size), index=at(true_s - true_offset)
    )
    assert estimate_clock_offset(series, reference, 120, 1.0) == pytest.approx(true_offset, abs=0.5)
    # The same with the roles reversed (dense series, sparse reference): the sign flips.
    sparse = reference.iloc[::6]
    assert estimate_clock_offset(sparse, series, 120, 1.0) == pytest.approx(-true_offset, abs=1.0)


def test_clock_offset_of_quantised_sparse_hmi_is_found_within_a_few_seconds():
    rng = np.random.default_rng(5)
    ref_s = np.arange(0, 9600, 10.0)
    box = pd.DataFrame(
        {
            "T7": warm_up(ref_s) + rng.normal(0, 0.02, ref_s.size),
            "T10": 30 + rng.normal(0, 0.02, ref_s.size),
        },
        index=at(ref_s),
    )
    true_s = np.arange(13, 9600, 60.0)
    hmi = pd.Series(np.round(warm_up(true_s), 1), index=at(true_s - 8.0))
    assert estimate_clock_offset(hmi, box, 120, 1.0) == pytest.approx(8.0, abs=4.0)


def test_clean_temperatures_estimates_offsets_against_the_reference_source():
    rng = np.random.default_rng(7)
    box_s = np.arange(0, 9600, 10.0)
    box = source(box_s, T7=warm_up(box_s) + rng.normal(0, 0.02, box_s.size), T10=30 + 0 * box_s)
    true_s = np.arange(0, 9600, 10.0)
    hmi = source(true_s - 12.0, T12=warm_up(true_s) + rng.normal(0, 0.02, true_s.size))
    # dataset.yaml gave +5 s; the residual +7 s is estimated on top.
    result = clean({"box": box, "hmi": hmi}, {"hmi": 5.0}, estimate_clock_offsets=True)
    qc = result.qc.set_index("sensor")
    assert qc.loc["T12", "clock_offset_s"] == pytest.approx(12.0, abs=0.5)
    assert qc.loc["T12", "offset_estimated"] and not qc.loc["T7", "offset_estimated"]
    assert qc.loc["T7", "clock_offset_s"] == 0.0


def test_a_clock_offset_that_cannot_be_estimated_stays_as_declared():
    # hmi logs a sensor that stays at 30 C: no transient to align, so its declared +5 s
    # stands, and the run goes on (one logger's clock must not cost the run).
    box_s = np.arange(0, 9600, 10.0)
    box = source(box_s, T7=warm_up(box_s), T10=30 + 0 * box_s)
    hmi = source(box_s, T12=30 + 0 * box_s)
    result = clean({"box": box, "hmi": hmi}, {"hmi": 5.0}, estimate_clock_offsets=True)
    ((which, why),) = result.unestimated
    assert (which, why) == (
        "hmi",
        "the series overlap too little for a search of +/-120 s or do not vary",
    )
    qc = result.qc.set_index("sensor")
    assert qc.loc["T12", "clock_offset_s"] == 5.0 and not qc.loc["T12", "offset_estimated"]


def test_clock_offset_estimation_refuses_without_overlap_or_shared_transient():
    s = np.arange(0, 200, 10.0)
    series = pd.Series(warm_up(s), index=at(s))
    with pytest.raises(ValueError, match="overlap"):
        estimate_clock_offset(series, series, 120, 1.0)
    rng = np.random.default_rng(9)
    s = np.arange(0, 7200, 10.0)
    a = pd.Series(ramp(s) + rng.normal(0, 0.02, s.size), index=at(s))
    b = pd.Series(ramp(s) + rng.normal(0, 0.02, s.size), index=at(s + 30))
    with pytest.raises(ValueError, match="no shared transient"):
        estimate_clock_offset(a, b, 120, 1.0)


# ----------------------------------------------------------------------------- spikes and limits


def test_single_sample_spike_is_removed_and_replaced_by_interpolation():
    s = np.arange(0, 600, 10.0)
    values = ramp(s)
    values[[17, 40]] += [3.0, -2.5]
    values[0] += 4.0  # a spike on the very first sample is caught too
    result = clean_temperatures({"box": source(s, T1=values)}, {}, SETTINGS, start=T0)
    t = grid_seconds(result.frame)
    assert t[0] == 0
    np.testing.assert_allclose(result.frame["T1"].iloc[1:], ramp(t[1:]), atol=1e-9)
    assert result.frame["T1"].iloc[0] == ramp(10)  # held from the first valid sample
    qc = qc_of(result, "T1")
    assert (qc["n_spikes"], qc["n_interpolated"], qc["n_edge_held"]) == (3, 2, 1)


def test_open_circuit_values_are_removed():
    s = np.arange(0, 600, 10.0)
    values = ramp(s)
    values[12], values[30] = 850.0, -200.0
    result = clean({"box": source(s, T1=values)})
    t = grid_seconds(result.frame)
    np.testing.assert_allclose(result.frame["T1"], ramp(t), atol=1e-9)
    qc = qc_of(result, "T1")
    assert (qc["n_out_of_range"], qc["n_spikes"], qc["n_interpolated"]) == (2, 0, 2)


def test_hmi_quantisation_is_not_mistaken_for_spikes():
    s = np.arange(0, 7200, 60.0)
    truth = warm_up(s + 800)  # flat, then a fast rise and its bend
    result = clean({"hmi": source(s, T12=np.round(truth, 1))})
    assert qc_of(result, "T12")["n_spikes"] == 0
    # ... while a real spike in the same series is still caught.
    spiky = np.round(truth, 1)
    spiky[50] += 1.5
    assert qc_of(clean({"hmi": source(s, T12=spiky)}), "T12")["n_spikes"] == 1


def test_noisy_warm_up_has_no_false_spikes():
    rng = np.random.default_rng(2)
    s = np.arange(0, 9600, 10.0)
    result = clean({"box": source(s, T1=warm_up(s) + rng.normal(0, 0.02, s.size))})
    assert qc_of(result, "T1")["n_spikes"] == 0


# ----------------------------------------------------------------------------- gaps


def test_short_gap_is_interpolated_within_tolerance():
    s = np.arange(0, 3600, 10.0)
    truth = 25 + 2 * np.sin(2 * np.pi * s / 3600)  # a slow real oscillation
    hole = (s > 1000) & (s < 1500)  # 500 s < max_gap_s = 600 s
    result = clean({"box": source(s[~hole], T1=truth[~hole])})
    t = grid_seconds(result.frame)
    err = np.abs(result.frame["T1"].to_numpy() - (25 + 2 * np.sin(2 * np.pi * t / 3600)))
    # chord error of a sine: amplitude * (2 pi / P)^2 * gap^2 / 8
    bound = 2 * (2 * np.pi / 3600) ** 2 * 500**2 / 8
    assert err.max() <= bound + 1e-12 and bound < 0.2
    assert qc_of(result, "T1")["n_interpolated"] == 49  # 1010 ... 1490 s
    assert result.gaps.empty
    assert qc_of(result, "T1")["longest_gap_s"] == 500


def test_long_gap_is_left_nan_and_reported():
    s = np.arange(0, 3600, 10.0)
    hole = (s > 1000) & (s < 1900)  # samples at 1000 and 1900 s: 900 s apart
    result = clean({"box": source(s[~hole], T1=ramp(s[~hole]))})
    t = grid_seconds(result.frame)
    inside = (t > 1000) & (t < 1900)
    assert result.frame["T1"][inside].isna().all()
    np.testing.assert_allclose(result.frame["T1"][~inside], ramp(t[~inside]), atol=1e-9)
    assert qc_of(result, "T1")["n_long_gap"] == inside.sum() == 89
    assert qc_of(result, "T1")["n_interpolated"] == 0
    gap = result.gaps.iloc[0]
    assert len(result.gaps) == 1 and gap["sensor"] == "T1"
    assert (gap["start"], gap["end"], gap["duration_s"]) == (at([1000])[0], at([1900])[0], 900.0)


def test_sensor_starting_late_is_held_briefly_then_reported():
    box_s = np.arange(0, 2000, 10.0)
    nut_s = np.arange(25, 2000, 30.0)
    result = clean({"box": source(box_s, T1=ramp(box_s)), "nut": source(nut_s, T11=ramp(nut_s))})
    assert result.frame["T11"].iloc[:3].tolist() == [ramp(25)] * 3  # held for 25 s <= 300 s
    assert result.frame["T11"].iloc[-2:].tolist() == [ramp(1975)] * 2  # and after its last sample
    assert qc_of(result, "T11")["n_edge_held"] == 5
    late = source(nut_s + 700, T11=ramp(nut_s + 700))  # first sample at 725 s > max_gap_s / 2
    result = clean({"box": source(box_s, T1=ramp(box_s)), "nut": late})
    t = grid_seconds(result.frame)
    assert (
        result.frame["T11"][t < 425].isna().all()
        and result.frame["T11"][(t >= 425) & (t < 725)].notna().all()
    )
    gap = result.gaps.iloc[0]
    assert (gap["sensor"], gap["start"], gap["end"]) == ("T11", at([0])[0], at([725])[0])


def windows_frame(*spans):
    return pd.DataFrame(
        {
            "measurement": np.arange(1, len(spans) + 1),
            "name": [f"m{i:02d}" for i in range(1, len(spans) + 1)],
            "start": at([a for a, _ in spans]),
            "end": at([b for _, b in spans]),
        }
    )


def test_a_long_gap_overlapping_measurements_is_one_summary_per_sensor():
    gaps = pd.DataFrame(
        {"sensor": ["T11"], "start": at([1000]), "end": at([2600]), "duration_s": [1600.0]}
    )
    windows = windows_frame((0, 600), (1800, 2400), (2500, 2550), (3000, 3600))
    (overlap,) = gap_overlaps(gaps, windows, max_gap_s=600.0)
    assert overlap.sensor == "T11" and overlap.start == at([1000])[0]
    assert "measurement 2 (m02)" in overlap.text and overlap.text.endswith("(and 1 more)")
    # A gap that ends exactly when a measurement starts has a real sample there.
    assert (
        gap_overlaps(
            gaps.assign(end=at([1900])), windows_frame((0, 600), (1900, 2400)), max_gap_s=600.0
        )
        == []
    )


def test_gaps_of_clean_temperatures_feed_gap_overlaps():
    s = np.arange(0, 3600, 10.0)
    hole = (s > 1000) & (s < 1900)
    result = clean({"box": source(s[~hole], T1=ramp(s[~hole]))})
    assert [
        o.sensor for o in gap_overlaps(result.gaps, windows_frame((1500, 1600)), max_gap_s=600.0)
    ] == ["T1"]
    assert gap_overlaps(result.gaps, windows_frame((2000, 2600)), max_gap_s=600.0) == []


# ----------------------------------------------------------------------------- windows


def test_window_mean_and_start_of_a_ramp_are_exact():
    s = np.arange(0, 3600, 10.0)
    frame = clean({"box": source(s, T1=ramp(s), T2=2 * ramp(s))}).frame
    windows = windows_frame(
        (103, 887), (1000, 1000), (2004, 2006)
    )  # off-grid, empty, shorter than a step
    mean = temperatures_in_windows(frame, windows, how="mean")
    start = temperatures_in_windows(frame, windows, how="start")
    mid = np.array([495.0, 1000.0, 2005.0])
    np.testing.assert_allclose(mean["T1"], ramp(mid), atol=1e-9)
    np.testing.assert_allclose(mean["T2"], 2 * ramp(mid), atol=1e-9)
    np.testing.assert_allclose(start["T1"], ramp([103, 1000, 2004]), atol=1e-9)
    assert list(mean.columns) == ["measurement", "start", "end", "T1", "T2"]
    assert mean["measurement"].tolist() == [1, 2, 3]


def test_window_mean_of_a_step_weights_by_time():
    frame = pd.DataFrame({"time": at([0, 10, 20, 30, 40]), "T1": [0.0, 0.0, 10.0, 10.0, 10.0]})
    # piecewise linear: 0 until 10 s, ramps to 10 at 20 s; mean over [0, 40] = (5*10 + 10*20) / 40
    mean = temperatures_in_windows(frame, windows_frame((0, 40)), how="mean")
    assert mean["T1"].iloc[0] == pytest.approx(6.25)


def test_window_mean_skips_a_nan_stretch_and_window_outside_raises():
    frame = pd.DataFrame({"time": at([0, 10, 20, 30]), "T1": [1.0, 1.0, np.nan, 3.0]})
    assert temperatures_in_windows(frame, windows_frame((0, 30)), how="mean")["T1"].iloc[
        0
    ] == pytest.approx(1.0)
    with pytest.raises(ValueError, match="outside the temperature record"):
        temperatures_in_windows(frame, windows_frame((20, 40)), how="mean")
    with pytest.raises(ValueError, match="how"):
        temperatures_in_windows(frame, windows_frame((0, 10)), how="median")


# ----------------------------------------------------------------------------- bad input


def test_sensor_in_two_sources_raises():
    s = np.arange(0, 100, 10.0)
    with pytest.raises(ValueError, match="T1"):
        clean({"box": source(s, T1=ramp(s)), "nut": source(s, T1=ramp(s))})


@pytest.mark.parametrize(
    "section, key, value",
    [
        ("temperatures", "spike_max_rate_c_per_min", 0.0),
        ("temperatures", "max_offset_s", 0.0),
        ("errors", "steps", "ignore"),
        ("errors", "direction", "both"),
    ],
)
def test_settings_are_validated_by_the_schema(section, key, value):
    with pytest.raises(ValueError, match=f"config {section}/{key}: "):
        Settings.from_config({section: {key: value}})


def test_limits_are_ordered():
    # The one check the schema cannot express: two items of one array compared.
    with pytest.raises(ValueError, match="limits_c"):
        replace(DEFAULTS.cleaning.temperatures, limits_c=(120.0, -20.0))


# ----------------------------------------------------------------------------- everything at once


def test_all_faults_together_meet_the_acceptance_criterion():
    """Within 0.1 C of the truth at >= 99 % of grid points inside the measurement windows."""
    rng = np.random.default_rng(42)
    duration = 3 * 3600.0
    truth = {
        "T1": lambda x: 25 + 3 * (1 - np.exp(-x / 2400)),
        "T11": lambda x: 26 + 5 * (1 - np.exp(-x / 1800)),
        "T12": lambda x: 30 + 12 * (1 - np.exp(-x / 1200)),
    }
    box_s = np.arange(0, duration, 10.0)
    box = source(box_s, T1=truth["T1"](box_s) + rng.normal(0, 0.02, box_s.size))
    box.loc[[100, 900], "T1"] += [4.0, -3.0]  # spikes
    box.loc[1500, "T1"] = 850.0  # open circuit
    box = pd.concat([box, box.iloc[[200, 201]]]).sort_values(
        "time", kind="stable", ignore_index=True
    )
    nut_s = np.cumsum(rng.uniform(22, 38, 400))
    nut_s = nut_s[(nut_s < duration) & rng.uniform(size=nut_s.size).__ge__(0.05)]  # lost packets
    nut_s = nut_s[(nut_s < 5000) | (nut_s > 5400)]  # a 400 s outage
    nut = source(nut_s, T11=truth["T11"](nut_s) + rng.normal(0, 0.02, nut_s.size))
    hmi_s = np.arange(0, duration, 60.0)
    hmi = source(hmi_s - 6.0, T12=np.round(truth["T12"](hmi_s), 1))  # clock 6 s behind
    result = clean({"box": box, "nut": nut, "hmi": hmi}, {"hmi": 6.0})

    t = grid_seconds(result.frame)
    in_window = np.zeros(t.size, bool)
    for a in np.arange(0, duration - 600, 1200.0):
        in_window |= (t >= a) & (t <= a + 600)
    for sensor, f in truth.items():
        err = np.abs(result.frame[sensor].to_numpy()[in_window] - f(t[in_window]))
        assert np.mean(err <= 0.1) >= 0.99, sensor
    qc = result.qc.set_index("sensor")
    assert (
        qc.loc["T1", "n_spikes"],
        qc.loc["T1", "n_out_of_range"],
        qc.loc["T1", "n_duplicates"],
    ) == (2, 1, 2)
    assert qc.loc["T12", "n_spikes"] == 0 and result.gaps.empty


# ----------------------------------------------------------------------------- errors


def measurement(rows, direction=True):
    frame = pd.DataFrame(rows, columns=["position_mm", "error_um", "direction"])
    frame.insert(0, "time", at(np.arange(len(frame)) * 20.0))
    return frame if direction else frame.drop(columns="direction")


TARGETS = [185.0, 205.0, 225.0, 245.0, 265.0]


def two_passes(forward, backward):
    rows = [(p, e, "+") for p, e in zip(TARGETS, forward, strict=True) if e is not None]
    rows += [
        (p, e, "-")
        for p, e in zip(reversed(TARGETS), reversed(backward), strict=True)
        if e is not None
    ]
    return measurement(rows)


def test_mean_of_both_passes():
    m = two_passes([0.0, -1.0, -2.0, -3.0, -4.0], [1.0, 0.0, -1.0, -2.0, -2.0])
    curve, warnings = combine_passes(m, TARGETS, DEFAULTS.cleaning.errors, name="m01")
    np.testing.assert_allclose(curve.to_numpy(), [0.5, -0.5, -1.5, -2.5, -3.0])
    assert curve.index.tolist() == TARGETS and curve.index.name == "position_mm"
    assert warnings == []


@pytest.mark.parametrize(
    "direction, expected",
    [("+", [0.0, -1.0, -2.0, -3.0, -4.0]), ("-", [1.0, 0.0, -1.0, -2.0, -2.0])],
)
def test_one_direction(direction, expected):
    m = two_passes([0.0, -1.0, -2.0, -3.0, -4.0], [1.0, 0.0, -1.0, -2.0, -2.0])
    curve, _ = combine_passes(m, TARGETS, replace(DEFAULTS.cleaning.errors, direction=direction))
    np.testing.assert_allclose(curve.to_numpy(), expected)


def test_single_unlabelled_pass_is_used_as_is():
    m = measurement([(p, -float(i), None) for i, p in enumerate(TARGETS)], direction=False)
    curve, warnings = combine_passes(
        m, TARGETS, replace(DEFAULTS.cleaning.errors, direction="mean")
    )
    np.testing.assert_allclose(curve.to_numpy(), [0.0, -1.0, -2.0, -3.0, -4.0])
    assert warnings == []


def test_target_read_in_one_pass_only_keeps_that_reading_with_a_warning():
    m = two_passes([0.0, -1.0, None, -3.0, -4.0], [1.0, 0.0, -1.0, -2.0, -2.0])
    curve, warnings = combine_passes(m, TARGETS, DEFAULTS.cleaning.errors, name="m03")
    assert curve[225.0] == -1.0
    assert len(warnings) == 1 and "m03" in warnings[0] and "225" in warnings[0]


def test_a_position_few_measurements_read_is_a_stray_reading_not_a_target():
    line = [0.0, -1.0, -2.0, -3.0, -4.0]
    run = {f"M{i}": two_passes(line, line) for i in range(1, 6)}
    extra = pd.DataFrame([[run["M3"]["time"].iloc[2], 215.0, -9.0, "+"]], columns=run["M3"].columns)
    run["M3"] = pd.concat([run["M3"], extra], ignore_index=True)
    # By hand: 215 mm is read by 1 of 5 measurements, no majority, so not a target.
    targets = run_targets(run)
    assert targets.tolist() == TARGETS
    kept, why = without_strays(run, targets)
    assert list(why) == ["M3"] and "215 mm read by 1 of the run's 5 measurements" in why["M3"]
    assert len(kept["M3"]) == 10 and 215.0 not in kept["M3"]["position_mm"].tolist()
    curve, _ = combine_passes(kept["M3"], targets, DEFAULTS.cleaning.errors)
    np.testing.assert_allclose(curve.to_numpy(), line)
    # Read by three of five it is a target, missing in two.
    for name in ("M1", "M2"):
        run[name] = pd.concat([run[name], extra], ignore_index=True)
    assert 215.0 in run_targets(run).tolist()


def test_missing_target_reading_is_dropped_with_a_warning():
    m = two_passes([0.0, -1.0, None, -3.0, -4.0], [1.0, 0.0, None, -2.0, -2.0])
    curve, warnings = combine_passes(
        m, TARGETS, replace(DEFAULTS.cleaning.errors, max_missing_fraction=0.2), name="m03"
    )
    assert np.isnan(curve[225.0]) and curve.notna().sum() == 4
    assert len(warnings) == 1 and "225" in warnings[0] and "no reading" in warnings[0]
    # a NaN reading is as missing as an absent row
    m.loc[m["position_mm"] == 245.0, "error_um"] = np.nan
    with pytest.raises(ValueError, match="2 of 5"):
        combine_passes(m, TARGETS, replace(DEFAULTS.cleaning.errors, max_missing_fraction=0.2))


def test_too_many_missing_targets_raise():
    m = two_passes([0.0, None, None, -3.0, -4.0], [1.0, None, None, -2.0, -2.0])
    with pytest.raises(ValueError, match=r"measurement m05: 2 of 5 targets"):
        combine_passes(
            m, TARGETS, replace(DEFAULTS.cleaning.errors, max_missing_fraction=0.2), name="m05"
        )
    curve, _ = combine_passes(
        m, TARGETS, replace(DEFAULTS.cleaning.errors, max_missing_fraction=0.4), name="m05"
    )
    assert curve.isna().sum() == 2


def test_measurement_with_one_direction_only():
    # what thermaxis.dataset.reader makes of a file without a direction column: every row "+"
    forward_only = two_passes([0.0, -1.0, -2.0, -3.0, -4.0], [None] * 5)
    curve, warnings = combine_passes(
        forward_only, TARGETS, replace(DEFAULTS.cleaning.errors, direction="mean")
    )
    np.testing.assert_allclose(curve.to_numpy(), [0.0, -1.0, -2.0, -3.0, -4.0])
    assert warnings == []
    with pytest.raises(ValueError, match=r"m02: no - pass"):
        combine_passes(
            forward_only, TARGETS, replace(DEFAULTS.cleaning.errors, direction="-"), name="m02"
        )


def test_conflicting_duplicate_position_raises():
    m = two_passes([0.0, -1.0, -2.0, -3.0, -4.0], [1.0, 0.0, -1.0, -2.0, -2.0])
    m = pd.concat([m, measurement([(205.0, -1.3, "+")])], ignore_index=True)
    with pytest.raises(ValueError, match=r"m07.*205 mm.*\+ pass"):
        combine_passes(m, TARGETS, DEFAULTS.cleaning.errors, name="m07")


def test_exact_duplicate_rows_are_dropped_silently_and_counted():
    m = two_passes([0.0, -1.0, -2.0, -3.0, -4.0], [1.0, 0.0, -1.0, -2.0, -2.0])
    m = pd.concat([m, m.iloc[[1, 7]]], ignore_index=True)
    curve, warnings = combine_passes(m, TARGETS, DEFAULTS.cleaning.errors)
    np.testing.assert_allclose(curve.to_numpy(), [0.5, -0.5, -1.5, -2.5, -3.0])
    assert warnings == [] and curve.attrs["n_duplicate_rows"] == 2


def test_position_that_is_no_target_raises():
    m = measurement([(185.0, 0.0, "+"), (500.0, 1.0, "+")])
    with pytest.raises(ValueError, match="500 mm is not one of the targets"):
        combine_passes(m, TARGETS, replace(DEFAULTS.cleaning.errors, max_missing_fraction=1.0))


def test_a_sensor_flat_through_a_run_while_others_change_is_kept_with_a_warning(tiny_dataset):
    # S2 stuck at 23.4 C through R1 while S1 and S3 rise: a warning and a QC row naming
    # it, and its readings kept (a place far from the heat can stay put too). Where no
    # sensor changes, none stands out.
    from thermaxis.cleaning.run import clean_and_assemble_run
    from thermaxis.dataset.reader import load_dataset, read_run

    for run, stuck in (("R1", ["S2"]), ("R2", ["S1", "S2", "S3"])):
        log = tiny_dataset / run / "temperatures" / "box.csv"
        frame = pd.read_csv(log)
        frame[stuck] = 23.4
        frame.to_csv(log, index=False)
    dataset = load_dataset(tiny_dataset)
    tables = clean_and_assemble_run(dataset, read_run(dataset, "R1"), DEFAULTS.cleaning)
    flat = tables.qc[tables.qc["finding"] == "flat"]
    assert flat["sensor"].tolist() == ["S2"] and flat["action"].tolist() == ["kept"]
    assert [n for n in tables.notes if "throughout the run" in n] == [
        f"{tiny_dataset}/R1/temperatures/box.csv: sensor S2 of run R1 reads 23.4 C throughout "
        "the run while other sensors change: a stuck sensor? (kept)"
    ]
    assert (tables.temperatures.query("sensor == 'S2'")["absolute_c"] == 23.4).all()
    quiet = clean_and_assemble_run(dataset, read_run(dataset, "R2"), DEFAULTS.cleaning)
    assert "flat" not in quiet.qc["finding"].tolist()
