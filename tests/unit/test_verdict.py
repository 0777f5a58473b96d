"""The deployment verdict: counts, tests and intervals worked out by hand, and the three
outcomes on synthetic records built like logger records."""

import math

import numpy as np
import pandas as pd
import pytest
from scipy.stats import binom

from helpers.builders import held_out_summary as summary
from thermaxis.compensation.held_out import held_out_tables
from thermaxis.compensation.runtime import ControllerParameters, Step
from thermaxis.compensation.verdict import (
    clopper_pearson,
    deployment_verdict,
    median_interval,
    run_changes,
    runs_needed,
    sign_test_p,
    tolerance_um,
    verdict_sentence,
)

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


def test_the_tolerance_is_the_accuracy_over_the_stroke_and_never_below_the_floor():
    # 0.5 ppm of 260 mm = 0.5e-6 * 260e3 um = 0.13 um; of 100 mm 0.05 um, under the 0.1 um floor.
    assert tolerance_um(260.0, 0.5, 0.1) == pytest.approx(0.13)
    assert tolerance_um(100.0, 0.5, 0.1) == 0.1
    assert tolerance_um(0.0, 0.5, 0.1) == 0.1  # a single-point record


def test_the_sign_test_by_hand():
    # 3 of 4 improve: P(X >= 3) = (C(4,3) + C(4,4)) / 16 = 5/16; 7 of 8: (8 + 1) / 256.
    assert sign_test_p(4, 3) == 5 / 16
    assert sign_test_p(8, 7) == 9 / 256
    assert sign_test_p(5, 0) == 1.0
    assert sign_test_p(1000, 600) == pytest.approx(binom.sf(599, 1000, 0.5), rel=1e-9)


def test_runs_needed_is_the_fewest_improving_runs_that_pass():
    # 3 of 4 plus m improving: p = (n + 1) / 2^n with n = 4 + m, one run not improved:
    # 6/32, 7/64, 8/128 = 0.0625 > 0.05, 9/256 = 0.035 <= 0.05 at m = 4.
    assert runs_needed(4, 3, 0.05) == 4
    assert runs_needed(8, 7, 0.05) == 0


def test_the_clopper_pearson_ends_are_one_sided_bounds():
    low, high = clopper_pearson(4, 3, 0.05)
    # The lower end L solves P(X >= 3 | n=4, L) = 0.05; the upper end U P(X <= 3 | U) = 0.05.
    tail = lambda p: sum(math.comb(4, i) * p**i * (1 - p) ** (4 - i) for i in (3, 4))  # noqa: E731
    assert tail(low) == pytest.approx(0.05, abs=1e-9)
    assert 1 - high**4 == pytest.approx(0.05, abs=1e-9)
    assert clopper_pearson(3, 0, 0.05)[0] == 0.0 and clopper_pearson(3, 3, 0.05)[1] == 1.0
    # Lower end above 1/2 exactly when the sign test passes: 7 of 8 (p = 9/256) does.
    assert clopper_pearson(8, 7, 0.05)[0] > 0.5 > clopper_pearson(4, 3, 0.05)[0]


def test_the_median_interval_is_two_order_statistics():
    # n = 8: P(X <= 1) = 9/256 <= 0.05 < P(X <= 2) = 37/256, so j = 2: (x_(2), x_(7)),
    # coverage 1 - 2 * 9/256.
    assert median_interval([8, 1, 7, 2, 6, 3, 5, 4], 0.05) == (2.0, 7.0, 1 - 18 / 256)
    # n = 3: even the extremes miss with P(X = 0) = 1/8 > 0.05: the full range, 1 - 2/8.
    assert median_interval([3, 1, 2], 0.05) == (1.0, 3.0, 0.75)


def test_a_change_within_the_tolerance_is_unchanged():
    # Changes exact in binary: R2 +0.125, R3 -0.125, at a tolerance of 0.125: neither beyond.
    rows = [("R1", 1, 2.0, 1.0, 1.0, 0.5), ("R2", 1, 2.0, 2.125, 1.0, 1.0),
            ("R3", 1, 2.0, 1.875, 1.0, 1.0)]  # fmt: skip
    verdict = deployment_verdict(summary(rows), tolerance=0.125, significance=0.05)
    assert [r["effect"] for r in verdict["runs"]] == ["improved", "unchanged", "unchanged"]
    assert (verdict["improved_runs"], verdict["unchanged_runs"]) == (1, 2)
    # 1 improved, none worsened, median -0.125: it leans to improvement, too few to tell.
    assert verdict["outcome"] == "not_established"
    verdict = deployment_verdict(summary(rows), tolerance=0.1, significance=0.05)
    assert [r["effect"] for r in verdict["runs"]] == ["improved", "worsened", "improved"]


def test_a_run_worse_in_e_alone_is_worsened():
    rows = [("R1", 1, 8.0, 3.0, 1.0, 1.5)]  # largest |deviation| -5, E +0.5
    verdict = deployment_verdict(summary(rows), tolerance=0.1, significance=0.05)
    assert verdict["runs"][0]["effect"] == "worsened" and verdict["worsened"] == ["R1"]


def test_the_hand_made_rows():
    verdict = deployment_verdict(summary(ROWS), tolerance=0.1, significance=0.05)
    # R1 improves, R2 worsens (+7.7 and E +2), R10 improves (-0.5 and E -0.1: E within).
    assert [r["effect"] for r in verdict["runs"]] == ["improved", "worsened", "improved"]
    assert verdict["sign_test_p"] == 4 / 8  # P(X >= 2 | n = 3) = (3 + 1) / 8
    largest = verdict["largest_abs"]
    assert largest["median_change_um"] == pytest.approx(-0.5)  # of -5.0, 7.7, -0.5
    assert (largest["worst_run"], largest["worst_change_um"]) == ("R2", pytest.approx(7.7))
    assert largest["worst_share_of_uncompensated"] == pytest.approx(7.7 / 8.3)
    assert verdict["E"]["worst_change_um"] == pytest.approx(2.0)
    assert verdict["outcome"] == "not_established"
    assert verdict["recommended_for_deployment"] is False
    # 2 of 3 plus m: 1 - (C(n,0) + C(n,1)) ... by hand (n+1)/2^n <= 0.05 first at n = 8: m = 5.
    assert verdict["runs_needed"] == 5


def test_the_sentence_is_ascii_for_exports_and_in_micrometres_for_pages():
    verdict = deployment_verdict(summary(ROWS), tolerance=0.1, significance=0.05)
    # 2 of 3: the share's ends solve 3L^2 - 2L^3 = 0.05 (L = 0.135) and 1 - U^3 = 0.05
    # (U = 0.983); the median's interval is the full range, 1 - 2/8 = 75 %.
    head = (
        "Not established: of 3 held-out run(s) compensating improves 2 beyond the +/-0.10 {u} "
        "the measurement resolves (67%, 90% interval 14% to 98%; sign test p = 0.5 > 0.05), "
        "leaves 0 unchanged and worsens 1; median change of the largest |deviation| -0.50 {u} "
        "(75% interval -5.00 to +7.70 {u}). It worsens R2 (worst R2: largest |deviation| +7.70 {u}, "
        "93% of its "
        "uncompensated error). Too few runs to tell: 5 more held-out run(s) that it improves "
        "would establish it, at the conditions of R2 or outside those tested."
    )
    assert verdict_sentence(verdict) == head.format(u="um")
    assert verdict_sentence(verdict).isascii()
    assert verdict_sentence(verdict, unit="µm") == head.format(u="µm")


def test_no_held_out_rows_is_refused():
    with pytest.raises(ValueError, match="needs at least one held-out run"):
        deployment_verdict(summary([]), tolerance=0.1, significance=0.05)


def test_a_single_point_record_is_judged_on_its_largest_deviation_alone():
    # One target read in one direction: no span, so no E (NaN) in any measurement.
    nan = float("nan")
    rows = [
        ("R1", 1, 4.0, 1.0, nan, nan),
        ("R1", 2, 6.0, 2.0, nan, nan),
        ("R2", 1, 3.0, 2.5, nan, nan),
    ]
    verdict = deployment_verdict(summary(rows), tolerance=0.1, significance=0.05)
    assert "E" not in verdict
    assert verdict["largest_abs"]["median_change_um"] == pytest.approx(-2.25)  # (-4, -0.5)
    assert sorted(verdict["runs"][0]) == [
        "effect", "largest_abs_after_um", "largest_abs_before_um", "largest_abs_change_um", "run",
    ]  # fmt: skip
    assert verdict["improved_runs"] == 2


def test_the_verdict_reads_the_paired_changes_and_the_config_only():
    """No number of a held-out run reaches the tolerance, and the rule sees only the
    paired changes: replacing every run's values by others with the same changes leaves
    the verdict's evidence and outcome as they were; replacing them by anything leaves the
    tolerance and the level as the config set them."""
    verdict = deployment_verdict(summary(ROWS), tolerance=0.1, significance=0.05)
    shifted = summary(ROWS)
    for column in shifted.columns[2:]:
        shifted[column] += 50.0  # before and after alike: the same changes
    same = deployment_verdict(shifted, tolerance=0.1, significance=0.05)
    keys = ["outcome", "improved_runs", "unchanged_runs", "worsened_runs", "worsened",
            "sign_test_p", "share_interval", "runs_needed"]  # fmt: skip
    assert {k: same[k] for k in keys} == {k: verdict[k] for k in keys}
    for name in ("median_change_um", "median_interval_um", "worst_run"):
        assert same["largest_abs"][name] == pytest.approx(verdict["largest_abs"][name])
    other = summary(ROWS)
    other.iloc[:, 2:] = np.random.default_rng(0).uniform(0, 100, size=(len(ROWS), 4))
    replaced = deployment_verdict(other, tolerance=0.1, significance=0.05)
    assert (replaced["tolerance_um"], replaced["significance"]) == (0.1, 0.05)


# -------------------------------------------------- synthetic records built like logger records

TARGETS = np.arange(185.0, 446.0, 20.0)  # the paper's 14 targets, a 260 mm stroke
TOLERANCE = tolerance_um(TARGETS[-1] - TARGETS[0], 0.5, 0.1)  # 0.13 um


def _run_summary(run: str, speed_rpm: float, ambient_c: float, gain: float) -> pd.DataFrame:
    """One held-out run as compensation.held_out tabulates it: six measurements 20 min apart
    while the axis warms at a rate set by its condition (spindle speed, ambient), read in
    both directions with 2 um of reversal, and a controller that applies ``gain`` times
    the true drift's opposite (0.9: a model that tracks the run; above 2: a run unlike
    those it was trained on, over-compensated)."""
    minutes = np.arange(6) * 20.0
    warm = 1.0 - np.exp(-minutes / 60.0)
    # Slope (um/m) and intercept (um) of the deviation line grow with speed and ambient.
    k = (speed_rpm / 1000.0) * 12.0 * warm + 0.8 * (ambient_c - 20.0)
    b = (speed_rpm / 1000.0) * 6.0 * warm - 0.5 * (ambient_c - 20.0)
    deviations = {
        m + 1: {
            "+": b[m] + k[m] * TARGETS / 1000.0 + 1.0,
            "-": b[m] + k[m] * TARGETS / 1000.0 - 1.0,
        }
        for m in range(6)
    }
    steps = []
    for m in range(6):
        dk, db = k[m] - k[0], b[m] - b[0]  # the drift since the pitch table (measurement 1)
        p = ControllerParameters(-gain * db / 1000.0, -gain * dk * 1e-6, 0.0, (), 0.0, False)
        steps.append(Step(minutes[m] * 60.0, p, "ok"))
    tables = held_out_tables(
        run, steps, minutes, deviations, TARGETS, [s.parameters for s in steps]
    )
    return tables["summary"]


def _record(conditions) -> pd.DataFrame:
    return pd.concat(
        [_run_summary(f"E{i}", *c) for i, c in enumerate(conditions, start=1)], ignore_index=True
    )


def test_forty_four_runs_most_improved_is_recommended_and_names_the_edge():
    # 44 conditions: 4 speeds x 11 ambients; the 4 hottest high-speed runs are unlike the rest.
    conditions = [(s, a, 0.9) for s in (1000, 2000, 3000, 4000) for a in np.linspace(18, 26, 11)]
    unlike = {40, 41, 42, 43}  # 0-based: E41-E44, 4000 rpm at the warmest ambients
    conditions = [(s, a, 2.6 if i in unlike else g) for i, (s, a, g) in enumerate(conditions)]
    verdict = deployment_verdict(_record(conditions), TOLERANCE, 0.05)
    assert (verdict["improved_runs"], verdict["worsened_runs"]) == (40, 4)
    assert verdict["worsened"] == ["E41", "E42", "E43", "E44"]
    assert verdict["sign_test_p"] == pytest.approx(binom.sf(39, 44, 0.5), rel=1e-9)
    assert verdict["outcome"] == "recommended" and verdict["recommended_for_deployment"]
    assert verdict["largest_abs"]["median_change_um"] < 0
    text = verdict_sentence(verdict)
    assert text.startswith("Recommended for deployment: of 44 held-out run(s)")
    assert "It worsens E41, E42, E43 and E44" in text and "the edge of the conditions" in text


def test_six_runs_half_worsened_by_several_micrometres_is_not_recommended():
    conditions = [(1000, 20, 0.9), (2000, 22, 3.0), (3000, 20, 0.9), (3000, 24, 3.0),
                  (2000, 19, 0.9), (4000, 23, 3.0)]  # fmt: skip
    verdict = deployment_verdict(_record(conditions), TOLERANCE, 0.05)
    assert verdict["worsened"] == ["E2", "E4", "E6"]
    changes = [r["largest_abs_change_um"] for r in verdict["runs"] if r["effect"] == "worsened"]
    assert min(changes) > 3.0  # several um
    assert verdict["outcome"] == "not_recommended" and verdict["runs_needed"] is None
    assert verdict_sentence(verdict).startswith("NOT recommended for deployment: of 6 held-out")


def test_four_runs_three_improved_is_not_established_and_says_what_is_needed():
    conditions = [(1000, 20, 0.9), (2000, 22, 0.9), (3000, 24, 2.6), (4000, 20, 0.9)]
    verdict = deployment_verdict(_record(conditions), TOLERANCE, 0.05)
    assert verdict["improved_runs"] == 3 and verdict["worsened"] == ["E3"]
    assert verdict["sign_test_p"] == 5 / 16
    assert verdict["outcome"] == "not_established" and verdict["runs_needed"] == 4
    assert verdict_sentence(verdict).endswith(
        "Too few runs to tell: 4 more held-out run(s) that it improves would establish it, "
        "at the conditions of E3 or outside those tested."
    )


def test_a_quantity_some_runs_do_not_give_is_summed_up_over_those_that_do():
    nan = float("nan")
    rows = [("R1", 1, 4.0, 1.0, nan, nan), ("R2", 1, 3.0, 2.5, 2.0, 3.0)]
    verdict = deployment_verdict(summary(rows), tolerance=0.1, significance=0.05)
    assert verdict["E"]["median_change_um"] == 1.0 and verdict["E"]["worst_run"] == "R2"
    assert [r["effect"] for r in verdict["runs"]] == ["improved", "worsened"]


def test_a_run_worsened_only_in_e_is_named_with_that_quantity():
    # R1: largest |deviation| 8 -> 3 (better) but E 1.0 -> 2.5 (+1.5, 150 % of 1.0): worsened.
    # R2 improves in both; the largest |deviation|'s own worst run (-4.0) is R2, not R1.
    rows = [("R1", 1, 8.0, 3.0, 1.0, 2.5), ("R2", 1, 8.0, 4.0, 1.0, 0.8)]
    verdict = deployment_verdict(summary(rows), tolerance=0.1, significance=0.05)
    assert verdict["worsened"] == ["R1"] and verdict["largest_abs"]["worst_run"] == "R2"
    assert "It worsens R1 (worst R1: E of ISO 230-2 +1.50 um, 150% of its uncompensated error)" in (
        verdict_sentence(verdict)
    )


def test_harm_is_judged_on_the_runs_that_changed():
    # 6 runs: 3 improved, 3 worsened -> not recommended; with one of the worsened made
    # unchanged instead (3 improved, 2 worsened, 1 unchanged) it leans to improvement:
    # not established, and p = P(X >= 3 | 6, 1/2) = 42/64.
    def rows(last_after):
        improved = [(f"R{i}", 1, 8.0, 4.0, 1.0, 0.5) for i in (1, 2, 3)]
        worsened = [("R4", 1, 4.0, 9.0, 1.0, 2.0), ("R5", 1, 4.0, 9.0, 1.0, 2.0)]
        return improved + worsened + [("R6", 1, 4.0, last_after, 1.0, 1.0)]

    harm = deployment_verdict(summary(rows(9.0)), tolerance=0.1, significance=0.05)
    assert (harm["improved_runs"], harm["worsened_runs"], harm["outcome"]) == (
        3, 3, "not_recommended",
    )  # fmt: skip
    lean = deployment_verdict(summary(rows(4.0)), tolerance=0.1, significance=0.05)
    assert (lean["improved_runs"], lean["worsened_runs"], lean["unchanged_runs"]) == (3, 2, 1)
    assert lean["outcome"] == "not_established"
    assert lean["sign_test_p"] == pytest.approx(42 / 64)


def _with_status(rows, statuses):
    table = summary(rows)
    table["status"] = statuses
    return table


def test_runs_the_fallback_withheld_throughout_do_not_test_it():
    # Two runs, each outside its fold's training range: held at every measurement from the
    # first, so nothing is applied (after == before). No run tested the model: not
    # established, not "not recommended". The sign test still counts them as not improved
    # (the controller applies nothing there either): m more improving runs pass when
    # P(X >= m | 2 + m, 1/2) <= 0.05; m = 8: (45 + 10 + 1) / 1024 = 0.055, m = 9:
    # (55 + 11 + 1) / 2048 = 0.033, so 9.
    rows = [("R1", 1, 3.0, 3.0, 1.0, 1.0), ("R1", 2, 5.0, 5.0, 2.0, 2.0),
            ("R2", 1, 4.0, 4.0, 1.5, 1.5)]  # fmt: skip
    held = deployment_verdict(_with_status(rows, ["hold"] * 3), tolerance=0.1, significance=0.05)
    assert (held["untested_runs"], held["untested"], held["unchanged_runs"]) == (2, ["R1", "R2"], 0)
    assert [r["effect"] for r in held["runs"]] == ["untested", "untested"]
    assert held["outcome"] == "not_established" and held["runs_needed"] == 9
    sentence = verdict_sentence(held)
    assert sentence.startswith("Not established: ")
    assert "the fallback withheld it throughout R1 and R2, which do not test it" in sentence
    assert "No held-out run tests it" in sentence and "nothing here shows" not in sentence
    # The same numbers with the model applied (status ok) are two runs it leaves unchanged:
    # it helps none, which is the documented "not recommended".
    applied = deployment_verdict(_with_status(rows, ["ok"] * 3), tolerance=0.1, significance=0.05)
    assert (applied["unchanged_runs"], applied["untested_runs"]) == (2, 0)
    assert applied["outcome"] == "not_recommended"


def test_a_run_holding_an_earlier_good_value_is_judged_on_its_changes():
    # R1 is held at its second measurement but applies the value of its first (8 -> 3):
    # it is improved, not untested. R2 is held throughout; R3 improves. 2 improved of 3
    # with R2 untested: p = P(X >= 2 | 3) = 4/8, not established, R2 named.
    rows = [("R1", 1, 2.0, 1.0, 1.0, 0.5), ("R1", 2, 8.0, 3.0, 2.0, 1.0),
            ("R2", 1, 4.0, 4.0, 1.0, 1.0),
            ("R3", 1, 6.0, 2.0, 1.0, 0.5)]  # fmt: skip
    verdict = deployment_verdict(
        _with_status(rows, ["ok", "hold", "hold", "ok"]), tolerance=0.1, significance=0.05
    )
    assert [r["effect"] for r in verdict["runs"]] == ["improved", "untested", "improved"]
    assert verdict["sign_test_p"] == 4 / 8 and verdict["outcome"] == "not_established"
    sentence = verdict_sentence(verdict)
    assert "the fallback withheld it throughout R2, which does not test it" in sentence
    assert "Too few runs to tell" in sentence


def test_a_refusal_says_which_measure_fell_where_one_did():
    # R1: largest |deviation| 8 -> 3 (-5) but E 1.0 -> 2.5 (+1.5): lower and higher at once.
    # R2 worse in both, R3 within 0.1 in both. None improved, 2 worsened: not recommended.
    # The temperatures did predict part of R1's drift, so the refusal says that, not
    # "nothing shows"; with R1 worse in both measures too, it says "nothing shows".
    rows = [("R1", 1, 8.0, 3.0, 1.0, 2.5), ("R2", 1, 4.0, 9.0, 1.0, 2.0),
            ("R3", 1, 5.0, 5.05, 1.0, 1.05)]  # fmt: skip
    verdict = deployment_verdict(summary(rows), tolerance=0.1, significance=0.05)
    assert (verdict["improved_runs"], verdict["worsened"]) == (0, ["R1", "R2"])
    assert verdict["outcome"] == "not_recommended"
    assert verdict_sentence(verdict).endswith(
        "It helps no held-out run beyond the tolerance in both measures: it lowers the "
        "largest |deviation| of R1 beyond the tolerance but raises E of ISO 230-2 there."
    )
    rows[0] = ("R1", 1, 8.0, 8.5, 1.0, 2.5)
    nothing = verdict_sentence(deployment_verdict(summary(rows), 0.1, 0.05))
    assert nothing.endswith("nothing here shows that the temperatures predict this axis's drift.")
