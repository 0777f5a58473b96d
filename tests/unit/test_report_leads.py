"""The sentences the reports open with, from small tables whose answers are worked out by hand."""

from __future__ import annotations

import pandas as pd

from thermaxis.reports.leads import (
    condition_lead,
    conditions_lead,
    dataset_lead,
    how_much_more,
    lead_html,
    model_lead,
    paper_lead,
)


def _metrics() -> pd.DataFrame:
    rows = [
        ("E2", "decoupled", "mlr", "error", 8.11, 15.448),
        ("E2", "pointwise", "mlr", "error", 2.76, 5.572),
        ("E2", "decoupled", "mlr", "k", 1.0, 99.0),  # another target: ignored
        ("E1", "pointwise", "mlr", "error", 0.1, 0.2),  # another fold: ignored
    ]
    return pd.DataFrame(
        rows, columns=["fold", "approach", "algorithm", "target", "rmse", "max_abs"]
    )


def _compensation(after) -> pd.DataFrame:
    return pd.DataFrame(
        {
            "largest_abs_uncompensated_um": [0.1, 4.0, 8.3],
            "largest_abs_compensated_um": after,
            "status": ["ok", "ok", "hold"],
        }
    )


def test_the_model_lead_compares_the_largest_errors_and_says_what_compensating_did():
    text = model_lead(
        _metrics(),
        "E2",
        [["decoupled", "mlr"], ["pointwise", "mlr"]],
        _compensation([0.1, 9.0, 17.2]),
        ("decoupled", "mlr"),
    )
    # 15.448 / 5.572 = 2.77; the compensated largest |deviation| 17.2 > 8.3: worse.
    assert text == (
        "On held-out run E2 the decoupled MLR's largest error is 15.4 µm, 2.8 times the point-by-point "
        "MLR's 5.6 µm (RMSE 2.76 µm). Compensating with the decoupled MLR takes the largest "
        "|deviation| of E2 from 8.3 µm to 17.2 µm: it makes E2 worse. The fallback policy acted at 1 of "
        "3 measurements."
    )


def test_a_compensation_that_lowers_the_deviation_makes_the_run_better():
    text = model_lead(
        _metrics(),
        "E2",
        [["pointwise", "mlr"]],
        _compensation([0.1, 1.0, 2.5]),
        ("pointwise", "mlr"),
    )
    assert (
        "largest error is 5.6 µm (RMSE 2.76 µm)" in text
        and "from 8.3 µm to 2.5 µm: it makes E2 better" in text
    )


def test_ratios_in_words():
    assert how_much_more(4.1, 2.0) == "twice"
    assert how_much_more(1.05, 1.0) == "about as large as"
    assert how_much_more(3.0, 1.0) == "3.0 times"


def test_the_condition_lead_names_the_span_the_drift_and_the_warmest_sensor():
    errors = pd.DataFrame(
        {
            "measurement": [1, 1, 2, 2, 3, 3],
            "time_min": [0, 0, 30, 30, 75, 75],
            "position_mm": [0, 100] * 3,
            "error_um": [-1.0, 0.5, 2.0, -3.0, 6.0, 1.0],
        }
    )
    temperatures = pd.DataFrame(
        {
            "measurement": [1, 2, 3] * 2,
            "sensor": ["T10"] * 3 + ["T2"] * 3,
            "relative_c": [0, 1.0, 2.5, 0, 3.0, 2.0],
        }  # fmt: skip
    )
    assert condition_lead("E1", "feed 500", errors, temperatures) == (
        "Run E1 (feed 500): 3 measurements over 75 min. The unzeroed error's largest magnitude goes from "
        "1.0 µm at the first measurement to 6.0 µm at the last (at most 6.0 µm). Sensor T2 warms most, "
        "3.0 °C above the first measurement."
    )


def test_the_dataset_lead_counts_runs_repairs_and_finds_the_largest_error():
    summary = pd.DataFrame(
        {"condition": ["a", "a", "b"], "n_measurements": [5, 6, 7], "n_sensors": [12] * 3}
    )
    repairs = pd.DataFrame({"repaired": [3, 4]})
    errors = pd.DataFrame(
        {"run": ["R1", "R2"], "position_mm": [10.0, 250.0], "error_um": [3.0, -7.25]}
    )
    assert dataset_lead(summary, repairs, errors) == (
        "3 runs under 2 condition(s), 18 measurements, 12 temperature sensors. Cleaning repaired 7 readings of "
        "2 sensor log(s); the table below says which. The largest unzeroed error is 7.2 µm, in run R2 at 250 mm."
    )
    assert "Cleaning repaired nothing." in dataset_lead(summary, repairs.iloc[:0], errors)


def test_the_paper_lead_counts_reproduced_numbers_and_names_the_largest_difference():
    comparison = pd.DataFrame(
        {
            "table": ["table4", "table4", "eq9"],
            "item": ["RMSE MLR", "RMSE SVR", "c1"],
            "unit": ["um", "um", None],
            "published": [2.0, 3.0, 0.5],
            "reproduced": [2.5, None, 0.25],
            "difference": [0.5, None, -0.25],
        }
    )
    assert paper_lead(comparison) == (
        "2 of the paper's 3 published numbers are reproduced below. The largest difference is in table4 "
        "(RMSE MLR): 2.5 against 2 um."
    )


def test_the_lead_is_escaped():
    assert lead_html("run <E1>") == '<p class="tx-lead">run &lt;E1&gt;</p>'


def test_the_conditions_lead_names_the_runs_that_drift_most_and_least():
    largest = pd.DataFrame(
        {
            "run": ["E1", "E1", "E2", "E2", "E2", "E10"],
            "measurement": [1, 2, 1, 2, 3, 1],
            "largest_abs_um": [1.0, 4.0, 0.5, 9.25, 2.0, 0.75],
        }  # fmt: skip
    )
    assert conditions_lead(largest) == (
        "3 runs of 1 to 3 measurements. The largest unzeroed error is 9.2 µm, in run E2; the run that "
        "drifts least, E10, stays within 0.8 µm."
    )


def test_the_small_multiples_have_one_panel_per_run_on_shared_axes():
    from thermaxis.figures.overview import fig_runs_overview, largest_error_by_measurement

    errors = pd.DataFrame(
        {
            "run": ["E10", "E10", "E2", "E2", "E2"],
            "measurement": [1, 1, 1, 2, 2],
            "time_min": [0, 0, 0, 30, 30],
            "error_um": [1.0, -3.0, 0.5, 2.0, -2.5],
        }  # fmt: skip
    )
    table = largest_error_by_measurement(errors)
    assert table["largest_abs_um"].tolist() == [3.0, 0.5, 2.5]
    fig = fig_runs_overview(errors)
    axes = fig.get_axes()
    # E2 before E10 (natural order); the other two panels of the row are removed.
    assert [ax.get_title(loc="left") for ax in axes] == ["E2", "E10"]
    assert axes[0].get_shared_y_axes().joined(axes[0], axes[1])
    x, y = axes[0].get_lines()[0].get_data()
    assert list(x) == [0, 30] and list(y) == [0.5, 2.5]
