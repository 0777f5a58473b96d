"""The nested leave-one-condition-out recommendation, on data whose best model is known."""

from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from thermaxis.config import Settings
from thermaxis.method.folds import run_groups
from thermaxis.method.recommend import (
    BASELINE,
    Candidate,
    Recommendation,
    _choose,
    candidate_view,
    default_candidates,
    fold_scores,
    held_out_scores,
    recommend,
    recommendation_markdown,
    training_sets,
)

DEFAULTS = Settings.from_config({})
POSITIONS = (0.0, 200.0, 400.0)


def make_runs(n_runs=5, n_measurements=8, seed=0, driver="T1"):
    """Errors driven by ``driver``'s rise alone (plus 0.05 um noise); T1..T4 wander
    independently."""
    rng = np.random.default_rng(seed)
    rows, errors = [], []
    for r in range(1, n_runs + 1):
        walk = 20 + np.cumsum(rng.normal(0.4, 0.3, size=(n_measurements, 4)), axis=0)
        for m in range(n_measurements):
            rows.append({"run": f"R{r}", "measurement": m + 1, "time_min": 20.0 * m,
                         **{f"T{s + 1}": walk[m, s] for s in range(4)}})  # fmt: skip
        rise = walk[:, int(driver[1]) - 1] - walk[0, int(driver[1]) - 1]
        slope = np.array([1.0, 2.0, 3.0])
        errors.append(
            rise[:, None] * slope[None, :] + rng.normal(0, 0.05, size=(n_measurements, 3))
        )
    X = pd.DataFrame(rows)
    Y = pd.DataFrame(np.vstack(errors), columns=list(POSITIONS))
    return X, Y


def fixed(sensor):
    selection = replace(
        DEFAULTS.selection,
        method="fixed",
        fixed=(("b", (sensor,)), ("k", (sensor,)), ("pointwise", (sensor,))),
    )
    return Candidate(
        name=f"pointwise-mlr-{sensor}",
        approach="pointwise",
        algorithm="mlr",
        selection=selection,
        models=DEFAULTS.models,
        time_inputs=False,
    )


CANDIDATES = [fixed("T3"), fixed("T2"), fixed("T1"), fixed("T4")]


def run(X, Y, **kwargs):
    return recommend(X, Y, CANDIDATES, reference="pointwise-mlr-T3", degree=1, score="max_abs",
                     level=0.05, max_loco_runs=12, n_group_folds=5, **kwargs)  # fmt: skip


def test_the_candidate_that_made_the_data_is_chosen_on_every_fold():
    X, Y = make_runs()
    result = run(X, Y)
    assert result.final == "pointwise-mlr-T1"
    assert list(result.folds["chosen"]) == ["pointwise-mlr-T1"] * 5
    # The chosen candidate's held-out error is that of T1 fitted on the other four runs:
    # about the noise, far below the reference (T3, unrelated to the errors).
    assert (result.folds["rmse_um"] < 0.2).all()
    assert (result.folds["paper_rmse_um"] > 5 * result.folds["rmse_um"]).all()


def test_the_held_out_run_never_reaches_the_inner_choice():
    X, Y = make_runs()
    honest = run(X, Y)
    # Make R3's errors follow T2 instead of T1: only R3 changes.
    X2, Y2 = make_runs(driver="T1")
    rise = X2.loc[X2.run == "R3", "T2"].to_numpy() - X2.loc[X2.run == "R3", "T2"].to_numpy()[0]
    Y2.loc[(X2.run == "R3").to_numpy()] = rise[:, None] * np.array([[1.0, 2.0, 3.0]])
    poisoned = run(X2, Y2)
    fold = honest.folds.set_index("fold")
    other = poisoned.folds.set_index("fold")
    # Fold R3's choice is made on R1, R2, R4, R5 alone: it cannot see the change ...
    assert other.loc["R3", "chosen"] == fold.loc["R3", "chosen"]
    assert other.loc["R3", "inner_score"] == pytest.approx(fold.loc["R3", "inner_score"], rel=1e-12)
    # ... but its held-out error does (R3 no longer follows T1).
    assert other.loc["R3", "rmse_um"] > 10 * fold.loc["R3", "rmse_um"]
    inner = poisoned.inner
    assert not ((inner["fold"] == "R3") & (inner["held_out"] == "R3")).any()


def test_ties_go_to_the_candidate_listed_first():
    X, Y = make_runs()
    twin = replace(fixed("T1"), name="pointwise-mlr-T1-again")
    result = recommend(
        X,
        Y,
        [fixed("T3"), twin, fixed("T1")],
        reference="pointwise-mlr-T3",
        degree=1,
        score="rmse",
        level=0.05,
        max_loco_runs=12,
        n_group_folds=5,
    )
    assert result.final == "pointwise-mlr-T1-again"


def test_run_groups_become_group_folds_above_the_limit():
    runs = [f"R{i}" for i in range(1, 12)]
    assert run_groups(runs[:4], 12, 5) == [("R1",), ("R2",), ("R3",), ("R4",)]
    groups = run_groups(runs, 6, 5)
    assert len(groups) == 5
    assert sorted(r for g in groups for r in g) == sorted(runs)
    assert groups[0] == ("R1", "R2", "R3")  # contiguous, in natural order


def test_an_inner_group_fold_is_fitted_once_and_scored_over_all_its_rows():
    X, Y = make_runs(n_runs=6)
    group = ("R2", "R3")
    (row,) = held_out_scores(X, Y, ["R1", "R2", "R3", "R4"], [group], fixed("T1"), 1, [], {})
    # By hand: per position, least squares of the error on T1's rise since the run's first
    # measurement, fitted on R1 and R4 (R5, R6 are outside the training runs), pooled
    # over R2 and R3's rows.
    rise = X["T1"] - X.groupby("run")["T1"].transform("first")
    train, test = X["run"].isin(["R1", "R4"]).to_numpy(), X["run"].isin(group).to_numpy()
    A = np.column_stack([np.ones(train.sum()), rise[train]])
    coef, *_ = np.linalg.lstsq(A, Y.to_numpy()[train], rcond=None)
    residual = Y.to_numpy()[test] - np.column_stack([np.ones(test.sum()), rise[test]]) @ coef
    assert row["held_out"] == "R2+R3"
    assert row["rmse"] == pytest.approx(np.sqrt(np.mean(residual**2)), rel=1e-9)
    assert row["max_abs"] == pytest.approx(np.abs(residual).max(), rel=1e-9)


def test_evaluations_on_the_same_training_runs_share_one_fit():
    runs = ["R1", "R2", "R3", "R4"]
    sets = {s.train: dict(s.scored) for s in training_sets(runs, [(r,) for r in runs], 12, 5)}
    # By hand: four outer fits (three runs each) and the C(4, 2) = 6 pairs of runs the inner
    # loops train on, each pair serving two outer folds: 10 fits where 4 x (1 + 3) = 16
    # evaluations need one.
    assert len(sets) == 10
    assert sets[("R2", "R3", "R4")] == {("R1",): True}
    assert sets[("R3", "R4")] == {("R2",): True, ("R1",): True}
    # Above the limit an inner group fold of several runs is scored over its rows.
    grouped = training_sets([f"R{i}" for i in range(1, 7)], [("R1", "R2")], 3, 2)
    assert [dict(s.scored) for s in grouped] == [
        {("R1", "R2"): True},
        {("R3", "R4"): False},
        {("R5", "R6"): False},
    ]


def test_shared_fits_give_the_scores_of_one_fit_per_evaluation():
    X, Y = make_runs(n_runs=4)
    candidates = [fixed("T1"), fixed("T2")]
    runs = ["R1", "R2", "R3", "R4"]
    shared = pd.concat(fold_scores(X, Y, candidates, runs, 1, 12, 5), ignore_index=True)
    for row in shared.itertuples():
        train = [r for r in runs if r not in (row.fold, row.held_out)]
        by_hand = [c for c in candidates if c.name == row.candidate]
        (alone,) = held_out_scores(
            X, Y, [*train, row.held_out], [row.held_out], by_hand[0], 1, [], {}
        )
        assert row.rmse == pytest.approx(alone["rmse"], rel=1e-12)
        assert row.max_abs == pytest.approx(alone["max_abs"], rel=1e-12)
        # And by hand: a line per position on the sensor's rise, numpy least squares.
        sensor = by_hand[0].name.rsplit("-", 1)[1]
        rise = X[sensor] - X.groupby("run")[sensor].transform("first")
        fit, test = X["run"].isin(train).to_numpy(), (X["run"] == row.held_out).to_numpy()
        design = np.column_stack([np.ones(len(X)), rise])
        coef, *_ = np.linalg.lstsq(design[fit], Y.to_numpy()[fit], rcond=None)
        residual = Y.to_numpy()[test] - design[test] @ coef
        assert row.rmse == pytest.approx(np.sqrt(np.mean(residual**2)), rel=1e-9)
        assert row.max_abs == pytest.approx(np.abs(residual).max(), rel=1e-9)
    assert len(shared) == 4 * 2 * (1 + 3)


def test_above_the_limit_the_outer_loop_holds_out_groups_of_runs():
    X, Y = make_runs(n_runs=6)
    result = recommend(X, Y, CANDIDATES, reference="pointwise-mlr-T3", degree=1,
                       score="max_abs", level=0.05, max_loco_runs=4,
                       n_group_folds=3)  # fmt: skip
    # Six runs above a limit of four: three outer groups, R1+R2, R3+R4, R5+R6, every run
    # still a row, each chosen without its group.
    assert list(result.folds["fold"]) == [f"R{i}" for i in range(1, 7)]
    assert list(result.folds["chosen"]) == ["pointwise-mlr-T1"] * 6
    inner = result.inner.loc[result.inner["fold"] == "R1"]
    assert set(inner["held_out"]) == {"R3", "R4", "R5", "R6"}
    # By hand: R1's error from T1's rise fitted on R3-R6 alone (R2 is in R1's group).
    rise = X["T1"] - X.groupby("run")["T1"].transform("first")
    train, test = X["run"].isin(["R3", "R4", "R5", "R6"]).to_numpy(), (X["run"] == "R1").to_numpy()
    coef, *_ = np.linalg.lstsq(np.column_stack([np.ones(train.sum()), rise[train]]),
                               Y.to_numpy()[train], rcond=None)  # fmt: skip
    residual = Y.to_numpy()[test] - np.column_stack([np.ones(test.sum()), rise[test]]) @ coef
    first = result.folds.iloc[0]
    assert first["rmse_um"] == pytest.approx(np.sqrt(np.mean(residual**2)), rel=1e-9)


def test_time_inputs_and_signals_are_seen_only_by_candidates_that_use_them():
    X = pd.DataFrame({"run": ["R1"], "measurement": [1], "time_min": [0.0], "T1": [20.0],
                      "T1@lag30min": [19.0], "T1@lag20min": [19.5], "S": [100.0],
                      "S@lag30min": [90.0]})  # fmt: skip
    keys = ["run", "measurement", "time_min"]
    plain = fixed("T1")
    view, selectable, models = candidate_view(X, plain, ["S"])
    assert list(view.columns) == selectable == [*keys, "T1"] and models.signals == ()
    # Only the lags at the candidate's own time constants: T1@lag20min is another's.
    lagged = replace(plain, time_inputs=True, lags_min=(30.0,))
    view, selectable, _ = candidate_view(X, lagged, ["S"])
    assert list(view.columns) == selectable == [*keys, "T1", "T1@lag30min"]
    both = replace(lagged, models=replace(DEFAULTS.models, signals=("S",)))
    view, selectable, models = candidate_view(X, both, ["S"])
    # The signal and its lag go into every model's inputs; only temperatures are selected.
    assert list(view.columns) == [*keys, "T1", "T1@lag30min", "S", "S@lag30min"]
    assert selectable == [*keys, "T1", "T1@lag30min"]
    assert models.signals == ("S", "S@lag30min")


def test_with_two_runs_no_fold_is_chosen_but_the_final_choice_is_made():
    X, Y = make_runs(n_runs=2)
    result = run(X, Y)
    # One training run per fold leaves nothing to choose on: the reference stands there.
    assert list(result.folds["chosen"]) == ["pointwise-mlr-T3"] * 2
    assert result.folds["inner_score"].isna().all() and result.inner.empty
    assert result.final == "pointwise-mlr-T1"


def test_a_candidate_displaces_the_baseline_only_with_evidence_in_mean_and_in_ranks():
    def rows(name, values):
        return [
            {"candidate": name, "held_out": f"R{i}", "max_abs": v} for i, v in enumerate(values)
        ]

    def choose(*tables, order):
        return _choose(pd.DataFrame([r for t in tables for r in t]), order, "max_abs", 0.05)

    # Five inner runs, worked by hand. "lucky" has a lower mean than the baseline (0.96 vs
    # 1.1) but its paired differences -0.6, +0.6, -0.3, -0.2, +0.2 have mean -0.06 and
    # standard error 0.21: no evidence. "steady" is 0.2 better on every run: mean -0.2,
    # standard error 0, and all five signs negative, which one of the 2**5 equally likely
    # sign patterns under "no improvement" matches: one-sided p = 1/32 <= 0.05.
    base = rows(BASELINE, [1.0, 1.0, 1.3, 1.1, 1.1])
    lucky = rows("lucky", [0.4, 1.6, 1.0, 0.9, 1.3])
    steady = rows("steady", [0.8, 0.8, 1.1, 0.9, 0.9])
    assert choose(base, lucky, order=["lucky", BASELINE]) == (BASELINE, pytest.approx(1.1))
    assert choose(base, lucky, steady, order=["lucky", "steady", BASELINE]) == (
        "steady",
        pytest.approx(0.9),
    )
    # Three inner runs, "steady" better on each: p = 1/2**3 = 0.125, so the baseline
    # stands though the standard error is 0. Below five runs nothing reaches 0.05.
    assert choose(base[:3], steady[:3], order=["steady", BASELINE])[0] == BASELINE
    # Without the baseline the lowest mean chooses, as before.
    assert choose(lucky, steady, order=["lucky", "steady"])[0] == "steady"


def test_the_plain_baseline_is_always_a_candidate_and_sees_only_its_own_lags():
    candidates = default_candidates(
        DEFAULTS.selection, DEFAULTS.models, True, ["S"], (30.0,), (20.0, 60.0, 180.0)
    )
    baseline = candidates[-1]
    assert (baseline.name, baseline.approach, baseline.algorithm) == (
        BASELINE,
        "pointwise",
        "ridge",
    )
    assert baseline.selection.method == "all" and baseline.models.signals == ()
    assert baseline.models.searched == ("ridge",) and baseline.lags_min == (20.0, 60.0, 180.0)
    X = pd.DataFrame({"run": ["R1"], "measurement": [1], "time_min": [0.0], "T1": [20.0],
                      "T1@lag20min": [19.0], "T1@lag30min": [19.2], "S": [1.0]})  # fmt: skip
    _, selectable, _ = candidate_view(X, baseline, ["S"])
    assert selectable == ["run", "measurement", "time_min", "T1", "T1@lag20min"]


def test_the_page_says_which_folds_had_no_inner_split_to_choose_on():
    # Two runs: each fold trains on one run, so it keeps the reference, unchosen.
    folds = pd.DataFrame(
        {"fold": ["R1", "R2"], "chosen": ["paper", "paper"], "inner_score": [np.nan, np.nan],
         "rmse_um": [5.0, 1.5], "max_abs_um": [8.0, 3.5],
         "paper_rmse_um": [5.0, 1.5], "paper_max_abs_um": [8.0, 3.5]}
    )  # fmt: skip
    page = recommendation_markdown(
        Recommendation(folds, pd.DataFrame(), pd.DataFrame(), "baseline-ridge+lags", "max_abs"),
        "Dataset `two`: SIMULATED data.",
    )
    assert (
        "Fold(s) R1, R2 had a single training run, so no inner split to choose on: they keep "
        "the paper's configuration." in page
    )
    # The means over the two folds: RMSE (5.0 + 1.5) / 2, largest |residual| (8.0 + 3.5) / 2.
    assert (
        "a mean held-out RMSE of 3.25 µm and a mean largest |residual| of 5.75 µm, against "
        "3.25 and 5.75 µm for the paper's configuration" in page
    )
    chosen = folds.assign(inner_score=[0.9, np.nan])
    page = recommendation_markdown(
        Recommendation(chosen, pd.DataFrame(), pd.DataFrame(), "paper", "max_abs"), "x"
    )
    assert "Fold(s) R2 had a single training run" in page
