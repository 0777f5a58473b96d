"""thermaxis.statistics against independent computations: textbook examples, scipy called
directly, exact enumerations and coverage simulations."""

from __future__ import annotations

import itertools
import math
import warnings

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from helpers.builders import synthetic_temperatures
from helpers.truth import POSITIONS, eq9_errors, eq9_truth
from thermaxis.config import SelectionSettings, StatisticsSettings
from thermaxis.statistics import (
    CLAIM_COLUMNS,
    claim_results,
    claims_table,
    holm,
    measurement_sums,
    metric_intervals,
    paired_comparison,
    selection_stability,
    verdict,
    with_intervals,
    with_uncertainty,
)
from thermaxis.statistics.paired import rmse_difference, share_above_half, wilcoxon_p
from thermaxis.statistics.ranking import mean_ranks, rank_standard_error, versus_control
from thermaxis.statistics.resampling import (
    block_indices,
    block_length_for,
    fold_mean_interval,
    percentile_interval,
    stratified_indices,
)

SETTINGS = StatisticsSettings(
    level=0.95, n_resamples=1999, seed=0, block_length=0, stability_subsets=(12, 5)
)


def selection(**changes) -> SelectionSettings:
    section = dict(
        method="fuzzy_grey", scope="training", n_clusters=3, similarity="pearson",
        grade="deng", rho=0.5, normalisation="minmax", pointwise_common=3, fixed={},
    )  # fmt: skip
    section.update(changes)
    return SelectionSettings.from_section(section)


# --------------------------------------------------------------------------- textbook tests


def test_wilcoxon_on_darwins_zea_mays_matches_the_textbook_and_an_exact_enumeration():
    # Fisher's (1935) differences of Darwin's cross- and self-fertilised plants (eighths
    # of an inch): the negative ranks sum to W = 24 (|-48| is rank 10, |-67| rank 14),
    # two-sided exact p = 0.0413 in every textbook that uses them.
    d = np.array([6, 8, 14, 16, 23, 24, 28, 29, 41, -48, 49, 56, 60, -67, 75], dtype=float)
    ranks = stats.rankdata(np.abs(d))
    assert ranks[d < 0].sum() == 24
    signs = np.array(list(itertools.product((0, 1), repeat=d.size)), dtype=float)
    w_minus = signs @ ranks
    exact = 2 * np.mean(w_minus <= 24)
    assert exact == pytest.approx(0.0413, abs=5e-5)
    assert wilcoxon_p(d) == pytest.approx(exact, rel=1e-9)


def test_wilcoxon_says_nothing_where_nothing_can_be_ranked():
    assert math.isnan(wilcoxon_p([0.0, 0.0, 0.0]))
    assert math.isnan(wilcoxon_p([1.5]))
    # Four folds all of one sign: the smallest two-sided p there is, 2 / 2^4.
    assert wilcoxon_p([1.0, 2.0, 3.0, 4.0]) == pytest.approx(0.125)


def test_friedman_ranks_and_post_hoc_against_the_best_by_hand():
    # 3 configurations x 4 folds: A lowest everywhere; B second in three folds.
    scores = np.array(
        [[1.0, 1.0, 1.0, 1.0], [2.0, 2.0, 3.0, 2.0], [3.0, 3.0, 2.0, 3.0]]
    )  # rows A, B, C; columns folds
    ranks = mean_ranks(scores)
    np.testing.assert_allclose(ranks, [1.0, 2.25, 2.75])
    # chi2_F = 12 / (N k (k+1)) sum R_j^2 - 3 N (k+1) with rank sums 4, 9, 11: 6.5;
    # with 2 degrees of freedom its tail is exp(-6.5 / 2).
    assert stats.friedmanchisquare(*scores).pvalue == pytest.approx(math.exp(-3.25))
    se = math.sqrt(3 * 4 / (6 * 4))
    assert rank_standard_error(3, 4) == pytest.approx(se)
    z_b, z_c = 1.25 / se, 1.75 / se
    p_b, p_c = math.erfc(z_b / math.sqrt(2)), math.erfc(z_c / math.sqrt(2))
    # Holm: the smaller p times 2, the larger times 1, kept monotone.
    expected = [np.nan, max(p_b, 2 * p_c), 2 * p_c]
    np.testing.assert_allclose(versus_control(ranks, 0, 4), expected)


def test_ranking_gains_intervals_ranks_and_whether_each_is_distinguishable():
    scores = {"A": [1.0, 1.0, 1.0, 1.0], "B": [2.0, 2.0, 3.0, 2.0], "C": [3.0, 3.0, 2.0, 3.0]}
    summary = pd.DataFrame(
        [
            {"config_id": c, "fold": f"F{i}", "target": "error", "max_abs": v}
            for c, values in scores.items()
            for i, v in enumerate(values)
        ]
    )
    ranking = pd.DataFrame({"rank": [1, 2, 3], "config_id": ["A", "B", "C"]})
    out = with_uncertainty(summary, ranking, SETTINGS).set_index("config_id")
    assert out["friedman_p"].iloc[0] == pytest.approx(math.exp(-3.25))
    np.testing.assert_allclose(out["mean_rank"], [1.0, 2.25, 2.75])
    # B's Holm p (0.077) stays above 0.05, C's (0.027) does not.
    assert out["distinguishable"].tolist() == [False, False, True]
    assert out.loc["A", "mean_max_abs_lo"] == out.loc["A", "mean_max_abs_hi"] == 1.0
    assert out.loc["B", "mean_max_abs_lo"] <= 2.25 <= out.loc["B", "mean_max_abs_hi"]
    cd = stats.norm.ppf(1 - 0.05 / 4) * rank_standard_error(3, 4)
    assert out["critical_difference"].iloc[0] == pytest.approx(cd)


def test_holm_by_hand_and_with_gaps():
    # Sorted 0.005, 0.01, 0.03, 0.04 times 4, 3, 2, 1: 0.02, 0.03, 0.06, 0.04 -> 0.06 (monotone).
    np.testing.assert_allclose(holm([0.01, 0.04, 0.03, 0.005]), [0.03, 0.06, 0.06, 0.02])
    out = holm([0.2, np.nan, 0.9])
    np.testing.assert_allclose(out, [0.4, np.nan, 0.9])
    assert np.isnan(holm([np.nan])).all()


def test_verdicts():
    assert verdict(1.0, 0.5, 1.5, 0.01, 0.05) == "holds"
    assert verdict(-1.0, -1.5, -0.5, 0.01, 0.05) == "reversed"
    assert verdict(1.0, -0.1, 1.5, 0.01, 0.05) == "not resolved"
    assert verdict(1.0, 0.5, 1.5, 0.2, 0.05) == "not resolved"
    assert verdict(math.nan, math.nan, math.nan, math.nan, 0.05) == "not resolved"


# --------------------------------------------------------------------------- resampling


def test_blocks_are_consecutive_measurements_and_stay_in_their_fold():
    rng = np.random.default_rng(1)
    rows = block_indices(10, 3, 50, rng)
    assert rows.shape == (50, 10) and rows.min() >= 0 and rows.max() <= 9
    # Each block of 3 starts anywhere in 0..7 and runs on by one.
    for r in rows:
        for start in range(0, 9, 3):
            block = r[start : start + 3]
            assert np.all(np.diff(block) == 1)
    groups = np.array(["a"] * 8 + ["b"] * 5)
    strat = stratified_indices(groups, 2, 100, np.random.default_rng(2))
    assert np.all(strat[:, :8] < 8) and np.all(strat[:, 8:] >= 8)
    assert block_length_for(8, 0) == 2 and block_length_for(48, 0) == 4
    assert block_length_for(5, 9) == 5 and block_length_for(8, 3) == 3


def test_percentile_interval_of_the_mean_covers_at_close_to_its_level():
    # 300 samples of 40 draws of N(1, 1): the 95 % interval must cover 1 about 95 % of the time.
    rng = np.random.default_rng(7)
    covered = 0
    for _ in range(300):
        x = rng.normal(1.0, 1.0, 40)
        rows = block_indices(40, 1, 999, rng)
        lo, hi = percentile_interval(x[rows].mean(axis=1), 0.95)
        covered += lo <= 1.0 <= hi
    assert 0.90 <= covered / 300 <= 0.98


def test_blocks_keep_the_coverage_that_single_measurements_lose_on_drifting_errors():
    # AR(1) with phi = 0.6: the mean's variance is (1 + phi) / (1 - phi) = 4 times what
    # independent draws give, so resampling single measurements covers only about
    # P(|Z| < 1.96 / 2) = 0.67; blocks of 4 recover most of it (the moving-block bootstrap
    # still underestimates a little at n = 60, about 0.85 in theory).
    rng = np.random.default_rng(11)
    hits = {1: 0, 4: 0}
    for _ in range(300):
        e = np.zeros(80)
        for t in range(1, 80):
            e[t] = 0.6 * e[t - 1] + rng.normal()
        e = e[20:]  # past the start-up
        for length in hits:
            rows = block_indices(60, length, 999, rng)
            lo, hi = percentile_interval(e[rows].mean(axis=1), 0.95)
            hits[length] += lo <= 0.0 <= hi
    assert 0.58 < hits[1] / 300 < 0.74
    assert 0.76 < hits[4] / 300 < 0.92


def test_fold_mean_interval_is_scipys_percentile_bootstrap():
    values = np.array([3.1, 2.4, 5.0, 1.2])
    expected = stats.bootstrap(
        (values,), np.mean, n_resamples=999, method="percentile",
        rng=np.random.default_rng(3),
    ).confidence_interval  # fmt: skip
    assert fold_mean_interval(values, 0.95, 999, 3) == (expected.low, expected.high)
    assert all(math.isnan(v) for v in fold_mean_interval([2.0], 0.95, 999, 3))
    assert fold_mean_interval([2.0, 2.0], 0.95, 999, 3) == (2.0, 2.0)


def _predictions(residuals: np.ndarray) -> tuple[pd.DataFrame, pd.DataFrame]:
    """error_predictions with measured = residual, predicted = 0 (one fold), and no k/b rows."""
    n, p = residuals.shape
    rows = [
        {"fold": "F", "approach": "pointwise", "algorithm": "mlr", "run": "F",
         "measurement": m + 1, "position_mm": float(j), "measured": residuals[m, j],
         "predicted": 0.0}
        for m in range(n)
        for j in range(p)
    ]  # fmt: skip
    kb = pd.DataFrame(columns=["fold", "approach", "algorithm", "target", "run", "measurement",
                               "measured", "predicted"])  # fmt: skip
    return kb, pd.DataFrame(rows)


def test_metric_intervals_agree_with_scipys_bootstrap_of_whole_measurements():
    rng = np.random.default_rng(5)
    residuals = rng.normal(0.0, 2.0, (40, 3))
    kb, errors = _predictions(residuals)
    sums = measurement_sums(kb, errors)
    settings = StatisticsSettings(
        level=0.95, n_resamples=4999, seed=0, block_length=1, stability_subsets=(12, 5)
    )
    got = metric_intervals(sums, settings).iloc[0]

    # scipy resampling the measurements (rows) one by one, on the same numbers.
    def rmse(idx, axis=-1):
        return np.sqrt((residuals[idx.astype(int)] ** 2).mean(axis=(-1, -2)))

    ci = stats.bootstrap(
        (np.arange(40.0),), rmse, vectorized=True, n_resamples=4999, method="percentile",
        rng=np.random.default_rng(9),
    ).confidence_interval  # fmt: skip
    assert got["rmse_lo"] == pytest.approx(ci.low, rel=0.03)
    assert got["rmse_hi"] == pytest.approx(ci.high, rel=0.03)
    point = np.sqrt(np.mean(residuals**2))
    assert got["rmse_lo"] < point < got["rmse_hi"]
    assert got["max_abs_hi"] == pytest.approx(np.abs(residuals).max())
    metrics = pd.DataFrame(
        [{"fold": "F", "approach": "pointwise", "algorithm": "mlr", "target": "error",
          "rmse": point, "max_abs": 1.0, "mae": 1.0, "residual_min": -1.0, "residual_max": 1.0}]
    )  # fmt: skip
    table = with_intervals(metrics, metric_intervals(sums, settings))
    assert list(table.columns[4:13]) == [
        "rmse", "rmse_lo", "rmse_hi", "max_abs", "max_abs_lo", "max_abs_hi",
        "mae", "mae_lo", "mae_hi",
    ]  # fmt: skip


# --------------------------------------------------------------------------- paired tests


def test_sign_flip_test_equals_an_exact_enumeration_of_swaps():
    # 10 measurements in 2 folds: 2^10 swaps, fewer than n_resamples, so scipy is exact.
    rng = np.random.default_rng(4)
    a = rng.gamma(2.0, 1.0, 10)
    b = a * rng.uniform(0.3, 1.2, 10)
    folds = np.array(["F1"] * 5 + ["F2"] * 5, dtype=object)
    result = paired_comparison(a, b, folds, rmse_difference, SETTINGS)

    def effect(x, y):
        return np.mean(
            [np.sqrt(x[f].mean()) - np.sqrt(y[f].mean()) for f in (slice(0, 5), slice(5, 10))]
        )

    observed = effect(a, b)
    assert result.effect == pytest.approx(observed)
    null = []
    for swap in itertools.product((False, True), repeat=10):
        s = np.array(swap)
        null.append(effect(np.where(s, b, a), np.where(s, a, b)))
    null = np.array(null)
    tol = 1e-14 * abs(observed)
    exact = min(1.0, 2 * min(np.mean(null >= observed - tol), np.mean(null <= observed + tol)))
    assert result.p_permutation == pytest.approx(exact)
    assert result.p_wilcoxon == pytest.approx(stats.wilcoxon(np.array(result.fold_effects)).pvalue)
    assert result.lo <= result.effect <= result.hi


# --------------------------------------------------------------------------- the claims


def _eq9_dataset(runs=("E1", "E2", "E3", "E4")):
    """X, Y, the tidy errors and the model sums of data made exactly by Eq. 9."""
    X = synthetic_temperatures(runs=runs).assign(time_min=0.0)
    Y = eq9_errors(X)
    long = [
        {"run": run, "measurement": m, "position_mm": float(x), "error_um": e,
         "rezeroed_um": e - row.iloc[0]}
        for (run, m), (_, row) in zip(zip(X["run"], X["measurement"], strict=True), Y.iterrows(),
                                      strict=True)
        for x, e in row.items()
    ]  # fmt: skip
    return X, Y, pd.DataFrame(long)


def test_claims_on_data_made_by_eq9_hold_where_eq9_says_so():
    X, Y, errors = _eq9_dataset()
    folds = ["E1", "E2", "E3", "E4"]
    results = claim_results({}, X, Y, errors, folds, selection(), SETTINGS)
    # The drift shares by hand from Eq. 9's own k and b.
    k, b = eq9_truth(X)
    first = X["measurement"].to_numpy() == 1
    runs = X["run"].to_numpy()
    k0 = pd.Series(k[first], index=runs[first]).loc[runs].to_numpy()
    b0 = pd.Series(b[first], index=runs[first]).loc[runs].to_numpy()
    x = (POSITIONS - POSITIONS[0]) / 1000.0
    shares = []
    for run in folds:
        r = runs == run
        sb = len(x) * ((b[r] - b0[r]) ** 2).sum()
        sk = (((k[r] - k0[r])[:, None] * x) ** 2).sum()
        shares.append(sb / (sb + sk) - 0.5)
    assert results["intercept_drift"].effect == pytest.approx(np.mean(shares), rel=1e-6)
    # Re-zeroing at the first position removes b exactly; what is left is k times the stroke.
    removed = [len(x) * (b[runs == r] ** 2).sum() for r in folds]
    left = [((k[runs == r][:, None] * x) ** 2).sum() for r in folds]
    expected = np.mean([rm / (rm + lf) - 0.5 for rm, lf in zip(removed, left, strict=True)])
    assert results["rezeroing_hides_drift"].effect == pytest.approx(expected, rel=1e-6)
    # b is exactly linear in relative temperatures: on them the held-out b is exact,
    # on absolute ones each run's offset is missed.
    assert results["intercept_relative"].effect > 0
    assert results["intercept_relative"].lo > 0
    # The workflow's model comparisons are absent here: those claims are not expressed.
    assert results["decoupled_mlr"] is None
    table = claims_table("eq9", results, SETTINGS)
    assert tuple(table.columns) == CLAIM_COLUMNS
    assert set(table["verdict"]) <= {"holds", "reversed", "not resolved"}
    done = table.dropna(subset=["effect"])
    assert ((done["lo"] <= done["effect"]) & (done["effect"] <= done["hi"])).all()
    assert table.loc[table["effect"].isna(), "verdict"].eq("not resolved").all()


def test_a_single_position_dataset_expresses_only_the_claims_it_can():
    X, Y, errors = _eq9_dataset(runs=("R1", "R2"))
    Y1 = Y.iloc[:, [0]]
    errors1 = errors.loc[errors["position_mm"] == POSITIONS[0]]
    results = claim_results({}, X, Y1, errors1, ["R1", "R2"], selection(), SETTINGS)
    for name in ("intercept_drift", "slope_absolute", "rezeroing_hides_drift"):
        assert results[name] is None
    # Two folds: the Wilcoxon test's smallest two-sided p is 2 / 2^2, it resolves nothing.
    assert results["intercept_relative"].p_wilcoxon >= 0.5
    assert np.isfinite(results["intercept_relative"].p_permutation)


def test_share_statistic_is_one_half_off_the_share():
    np.testing.assert_allclose(share_above_half(np.array([3.0]), np.array([1.0]), None), [0.25])


def test_share_statistic_is_nan_without_a_warning_where_there_is_nothing_to_share():
    # A bootstrap replicate that drew only runs' first measurements: no drift on either side.
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        shares = share_above_half(np.array([0.0, 1.0]), np.array([0.0, 3.0]), None)
    np.testing.assert_allclose(shares, [np.nan, -0.25])


# --------------------------------------------------------------------------- stability


def test_stability_of_fixed_and_all_selections_is_known_and_one_training_run_is_not_resolved():
    X, Y, _ = _eq9_dataset()
    fixed = selection(method="fixed", fixed={"k": ["T1", "T6"], "b": ["T2"], "pointwise": ["T3"]})
    table = selection_stability(X, Y, ["E4"], fixed, 1, True, (12, 5))
    chosen = table.loc[table["frequency"] == 1.0].groupby("target")["sensor"].apply(set)
    assert chosen.to_dict() == {"k": {"T1", "T6"}, "b": {"T2"}, "pointwise": {"T3"}}
    assert (table["n_subsets"] == 3).all()
    assert table.loc[table["frequency"] == 0.0, "chosen"].eq(False).all()
    everything = selection_stability(X, Y, ["E4"], selection(method="all"), 1, True, (12, 5))
    assert (everything["frequency"] == 1.0).all()
    X2, Y2, _ = _eq9_dataset(runs=("R1", "R2"))
    two = selection_stability(X2, Y2, ["R1"], fixed, 1, True, (12, 5))
    assert (two["n_subsets"] == 0).all() and two["frequency"].isna().all()
    # Above max_loco_runs (2) the three training runs fall into 2 groups, E1+E2 and E3:
    # two subsets, each leaving one group out.
    grouped = selection_stability(X, Y, ["E4"], fixed, 1, True, (2, 2))
    assert (grouped["n_subsets"] == 2).all()
    assert grouped.loc[grouped["chosen"], "frequency"].eq(1.0).all()


# --------------------------------------------------------------------------- cross-dataset


def test_cross_dataset_means_get_scipys_fold_bootstrap_interval():
    from thermaxis.reports.crossdataset import summarise

    rmse = [1.0, 3.5, 2.0, 1.5]
    metrics = pd.DataFrame(
        {"fold": ["E1", "E2", "E3", "E4"], "approach": "decoupled", "algorithm": "mlr",
         "target": "error", "rmse": rmse, "max_abs": [2.0, 5.0, 3.0, 2.5]}
    )  # fmt: skip
    settings = StatisticsSettings(
        level=0.9, n_resamples=999, seed=5, block_length=0, stability_subsets=(12, 5)
    )
    row = summarise({"twin": metrics}, {"twin": "simulated"}, settings).iloc[0]
    ci = stats.bootstrap(
        (np.array(rmse),), np.mean, n_resamples=999, confidence_level=0.9,
        method="percentile", rng=np.random.default_rng(5),
    ).confidence_interval  # fmt: skip
    assert (row["mean_rmse_um_lo"], row["mean_rmse_um_hi"]) == (ci.low, ci.high)
    assert row["mean_rmse_um_lo"] <= row["mean_rmse_um"] <= row["mean_rmse_um_hi"]


# --------------------------------------------------------------------------- figures


def test_fold_comparison_bars_carry_their_intervals_and_the_stability_map_its_shares():
    from matplotlib.collections import LineCollection

    from thermaxis.figures.predictions import fig_fold_comparison
    from thermaxis.figures.statistics import fig_selection_stability

    metrics = pd.DataFrame(
        {"fold": ["E1", "E2"], "approach": "decoupled", "algorithm": "mlr", "target": "error",
         "rmse": [2.0, 3.0], "rmse_lo": [1.5, 2.0], "rmse_hi": [2.5, 4.5],
         "max_abs": [4.0, 5.0], "max_abs_lo": [3.0, 4.0], "max_abs_hi": [4.0, 5.0]}
    )  # fmt: skip
    fig = fig_fold_comparison(metrics)
    bars = [c for c in fig.axes[0].collections if isinstance(c, LineCollection)]
    spans = sorted((float(s[:, 1].min()), float(s[:, 1].max())) for s in bars[0].get_segments())
    assert spans == [(1.5, 2.5), (2.0, 4.5)]
    stability = pd.DataFrame(
        {"fold": ["E1", "E1", "E2", "E2"], "target": "k", "sensor": ["T1", "T2", "T1", "T2"],
         "chosen": [True, False, False, True], "frequency": [1.0, 0.5, 0.0, 2 / 3]}
    )  # fmt: skip
    image = fig_selection_stability(stability).axes[0].images[0].get_array()
    np.testing.assert_allclose(image, [[1.0, 0.0], [0.5, 2 / 3]])


def test_the_stability_map_of_many_sensors_keeps_the_sensors_some_subset_chose():
    from thermaxis.figures.statistics import fig_selection_stability

    # 100 sensors; chosen by a fold: T5 (E1), T7 (E2); chosen by a subset only: T50 (E2).
    rows = []
    for fold in ("E1", "E2"):
        for i in range(1, 101):
            sensor = f"T{i}"
            chosen = (fold, sensor) in {("E1", "T5"), ("E2", "T7")}
            share = {("E1", "T5"): 1.0, ("E2", "T7"): 0.5, ("E2", "T50"): 0.25}
            rows.append({"fold": fold, "target": "k", "sensor": sensor, "chosen": chosen,
                         "frequency": share.get((fold, sensor), 0.0)})  # fmt: skip
    ax = fig_selection_stability(pd.DataFrame(rows)).axes[0]
    assert [t.get_text() for t in ax.get_yticklabels()] == ["T5", "T7", "T50"]
    np.testing.assert_allclose(ax.images[0].get_array(), [[1.0, 0.0], [0.0, 0.5], [0.0, 0.25]])
    assert ax.get_ylabel() == "Sensor (the 3 of 100 chosen in some subset)"


def test_candidates_means_over_folds_get_scipys_fold_bootstrap_interval():
    from thermaxis.statistics import fold_means

    loco = pd.DataFrame(
        {"candidate": ["paper"] * 3 + ["all"] * 3, "held_out": ["E1", "E2", "E3"] * 2,
         "rmse": [1.0, 2.0, 4.0, 1.0, 1.0, 1.0], "max_abs": [2.0, 3.0, 7.0, 2.0, 2.5, 2.0]}
    )  # fmt: skip
    out = fold_means(loco, SETTINGS)
    assert list(out.index) == ["paper", "all"]
    ci = stats.bootstrap(
        (np.array([1.0, 2.0, 4.0]),), np.mean, n_resamples=1999, method="percentile",
        rng=np.random.default_rng(0),
    ).confidence_interval  # fmt: skip
    assert out.loc["paper", "loco_rmse_um"] == pytest.approx(7 / 3)
    assert (out.loc["paper", "loco_rmse_um_lo"], out.loc["paper", "loco_rmse_um_hi"]) == (
        ci.low,
        ci.high,
    )
    # Equal folds: nothing varies, the interval is the value.
    assert out.loc["all", "loco_rmse_um_lo"] == out.loc["all", "loco_rmse_um_hi"] == 1.0


def test_a_single_position_dataset_without_k_b_rows_is_compared_in_numbers():
    from thermaxis.statistics import compare_models, model_sums

    rng = np.random.default_rng(8)
    kb, errors = _predictions(rng.normal(0.0, 1.0, (12, 1)))
    kb = kb.astype(object)  # as pandas reads an empty kb_predictions.csv
    other = errors.assign(algorithm="svr", measured=errors["measured"] * 0.5)
    sums = measurement_sums(kb, pd.concat([errors, other], ignore_index=True))
    assert sums["sq"].dtype == float
    row = compare_models(model_sums(sums), SETTINGS).iloc[0]
    r = errors["measured"].to_numpy()
    assert row["difference"] == pytest.approx(np.sqrt(np.mean(r**2)) * 0.5)
