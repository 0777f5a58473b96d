"""The deployment verdict: counts, medians and refusals worked out by hand."""

import pandas as pd
import pytest

from thermaxis.compensation.verdict import deployment_verdict, run_changes, verdict_sentence


def summary(rows):
    columns = ["run", "measurement", "largest_abs_uncompensated_um", "largest_abs_compensated_um",
               "E_uncompensated_um", "E_compensated_um"]  # fmt: skip
    return pd.DataFrame(rows, columns=columns)


# R1 improves (8 -> 3), R2 worsens (8.3 -> 16.0 at its worst measurement), R10 improves a little.
ROWS = [
    ("R1", 1, 1.0, 1.0, 0.5, 0.5),
    ("R1", 2, 8.0, 3.0, 2.0, 1.0),
    ("R2", 1, 8.3, 16.0, 1.0, 3.0),
    ("R2", 2, 4.0, 2.0, 1.0, 0.5),
    ("R10", 1, 5.0, 4.5, 1.0, 0.9),
]


def test_worst_values_per_run_in_natural_order():
    changes = run_changes(summary(ROWS))
    assert list(changes["run"]) == ["R1", "R2", "R10"]
    assert list(changes["largest_abs_before_um"]) == [8.0, 8.3, 5.0]
    assert list(changes["largest_abs_after_um"]) == [3.0, 16.0, 4.5]
    assert changes["largest_abs_change_um"].tolist() == pytest.approx([-5.0, 7.7, -0.5])
    assert changes["E_change_um"].tolist() == pytest.approx([-1.0, 2.0, -0.1])


def test_a_run_made_worse_withdraws_the_recommendation_and_says_why():
    verdict = deployment_verdict(summary(ROWS), max_worsening_um=0.1)
    largest = verdict["largest_abs"]
    assert (largest["improved_runs"], largest["worsened_runs"]) == (2, 1)
    assert largest["median_reduction_um"] == pytest.approx(0.5)  # median of 5.0, -7.7, 0.5
    assert largest["worst_increase_um"] == pytest.approx(7.7)
    assert verdict["E"]["worst_increase_um"] == pytest.approx(2.0)
    assert verdict["recommended_for_deployment"] is False
    assert verdict["reasons"] == [
        "held-out run R2: largest |deviation| over the stroke 8.30 -> 16.00 um "
        "(+7.70 um, more than compensation.max_worsening_um = 0.1 um)",
        "held-out run R2: E of ISO 230-2 1.00 -> 3.00 um "
        "(+2.00 um, more than compensation.max_worsening_um = 0.1 um)",
    ]
    assert "NOT recommended for deployment" in verdict_sentence(verdict)


def test_the_sentence_is_ascii_for_exports_and_in_micrometres_for_pages():
    verdict = deployment_verdict(summary(ROWS), max_worsening_um=0.1)
    head = (
        "On 3 held-out run(s) compensating improves 2 and worsens 1 (largest |deviation| over "
        "the stroke; median reduction 0.50 {u}, worst increase 7.70 {u}). NOT recommended for "
        "deployment: held-out run R2: largest |deviation| over the stroke 8.30 -> 16.00 {u} "
        "(+7.70 {u}, more than compensation.max_worsening_um = 0.1 {u}); held-out run R2: E of "
        "ISO 230-2 1.00 -> 3.00 {u} (+2.00 {u}, more than compensation.max_worsening_um = 0.1 {u})."
    )
    assert verdict_sentence(verdict) == head.format(u="um")
    assert verdict_sentence(verdict).isascii()
    assert verdict_sentence(verdict, unit="µm") == head.format(u="µm")


def test_worsening_within_the_tolerance_is_still_recommended():
    rows = [("R1", 1, 2.0, 1.0, 1.0, 0.5), ("R2", 1, 2.0, 2.05, 1.0, 1.0)]
    verdict = deployment_verdict(summary(rows), max_worsening_um=0.1)
    assert verdict["recommended_for_deployment"] is True
    assert verdict["largest_abs"]["worsened_runs"] == 1
    assert verdict_sentence(verdict).endswith("Recommended for deployment.")


def test_no_held_out_rows_is_refused():
    with pytest.raises(ValueError, match="needs at least one held-out run"):
        deployment_verdict(summary([]), max_worsening_um=0.1)


def test_a_single_point_record_is_judged_on_its_largest_deviation_alone():
    # One target read in one direction: no span, so no E (NaN) in any measurement.
    nan = float("nan")
    rows = [
        ("R1", 1, 4.0, 1.0, nan, nan),
        ("R1", 2, 6.0, 2.0, nan, nan),
        ("R2", 1, 3.0, 2.5, nan, nan),
    ]
    verdict = deployment_verdict(summary(rows), max_worsening_um=0.1)
    assert "E" not in verdict
    assert verdict["largest_abs"]["median_reduction_um"] == pytest.approx(2.25)  # (6-2, 3-2.5)
    assert sorted(verdict["runs"][0]) == [
        "largest_abs_after_um", "largest_abs_before_um", "largest_abs_change_um", "run",
    ]  # fmt: skip
    assert verdict["recommended_for_deployment"] is True
