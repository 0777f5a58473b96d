"""The nested leave-one-condition-out recommendation, on data whose best model is known."""

from dataclasses import replace

import numpy as np
import pandas as pd
import pytest
from scipy.optimize import nnls

from thermaxis.config import Settings
from thermaxis.method.candidates import (
    BASELINE,
    EVIDENCE,
    Candidate,
    candidate_view,
    candidates_for,
    default_candidates,
)
from thermaxis.method.folds import run_groups
from thermaxis.method.nested import (
    COMBINED,
    Combination,
    Recommendation,
    fold_scores,
    held_out_predictions,
    held_out_scores,
    recommend,
    run_rmse_weights,
    selector_weights,
    super_learner_weights,
    training_sets,
)
from thermaxis.reports.recommendation import recommendation_markdown

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
MEMBERS = [c.name for c in CANDIDATES]


def run(X, Y, **kwargs):
    return recommend(X, Y, CANDIDATES, reference="pointwise-mlr-T3", degree=1, members=MEMBERS,
                     max_loco_runs=12, n_group_folds=5, **kwargs)  # fmt: skip


def weights_of(result, fold):
    return dict(zip(result.combination.members, result.combination.folds[fold], strict=True))


def test_the_member_that_made_the_data_takes_the_weight_on_every_fold():
    X, Y = make_runs()
    result = run(X, Y)
    assert list(result.folds["chosen"]) == [COMBINED] * 5
    for fold in result.folds["fold"]:
        assert weights_of(result, fold)["pointwise-mlr-T1"] > 0.95
        assert sum(weights_of(result, fold).values()) == pytest.approx(1.0, abs=1e-12)
    assert dict(zip(MEMBERS, result.combination.final, strict=True))["pointwise-mlr-T1"] > 0.95
    # The table carries each fold's weights.
    assert result.folds["weight_pointwise-mlr-T1"].tolist() == [
        weights_of(result, f)["pointwise-mlr-T1"] for f in result.folds["fold"]
    ]
    # The combination's held-out error is about the noise, far below the reference's (T3,
    # unrelated to the errors).
    assert (result.folds["rmse_um"] < 0.2).all()
    assert (result.folds["paper_rmse_um"] > 5 * result.folds["rmse_um"]).all()


def by_hand_predictions(X, Y, sensor, train, test):
    """Least squares of each position's error on ``sensor``'s rise, fitted on ``train``."""
    rise = X[sensor] - X.groupby("run")[sensor].transform("first")
    fit, out = X["run"].isin(train).to_numpy(), X["run"].isin(test).to_numpy()
    coef, *_ = np.linalg.lstsq(np.column_stack([np.ones(fit.sum()), rise[fit]]),
                               Y.to_numpy()[fit], rcond=None)  # fmt: skip
    return np.column_stack([np.ones(out.sum()), rise[out]]) @ coef


def two_member_recommendation(t1: float, t2: float, weighting: str, n_runs: int = 4):
    """``n_runs`` runs whose errors are t1 T1's rise + t2 T2's rise at three positions, and
    the recommendation over the members on T1 alone and on T2 alone, weighted by ``weighting``."""
    X, Y = make_runs(n_runs=n_runs, seed=2)
    rises = X[["T1", "T2"]] - X.groupby("run")[["T1", "T2"]].transform("first")
    Y = pd.DataFrame((t1 * rises["T1"] + t2 * rises["T2"]).to_numpy()[:, None] * np.array([[1.0, 2.0, 3.0]]),
                     columns=Y.columns)  # fmt: skip
    members = ["pointwise-mlr-T1", "pointwise-mlr-T2"]
    result = recommend(X, Y, CANDIDATES, reference="pointwise-mlr-T3", degree=1, members=members,
                       max_loco_runs=12, n_group_folds=5, weighting=weighting)  # fmt: skip
    return X, Y, result


def test_the_weights_are_nnls_on_the_inner_predictions_worked_out_by_hand():
    # Two members that each explain part of the errors: the errors follow T1 + T2's rises.
    X, Y, result = two_member_recommendation(1.0, 0.5, "nnls")
    runs = ["R1", "R2", "R3", "R4"]

    def weights(pairs):
        P = np.vstack([np.column_stack([by_hand_predictions(X, Y, s, train, [run]).ravel()
                                        for s in ("T1", "T2")]) for train, run in pairs])  # fmt: skip
        y = np.concatenate([Y.to_numpy()[(X["run"] == run).to_numpy()].ravel() for _, run in pairs])
        w, _ = nnls(P, y)
        return w / w.sum()

    # Fold R2: each of R1, R3, R4 predicted by the members fitted on the other two.
    inner = [([r for r in runs if r not in ("R2", i)], i) for i in ("R1", "R3", "R4")]
    np.testing.assert_allclose(result.combination.folds["R2"], weights(inner), rtol=1e-9)
    # Final: every run predicted by the members fitted on the other three.
    every = [([r for r in runs if r != i], i) for i in runs]
    np.testing.assert_allclose(result.combination.final, weights(every), rtol=1e-9)
    # Fold R2's held-out error: its weights on the members fitted on R1, R3, R4.
    train = ["R1", "R3", "R4"]
    combined = np.column_stack([by_hand_predictions(X, Y, s, train, ["R2"]).ravel()
                                for s in ("T1", "T2")]) @ weights(inner)  # fmt: skip
    residual = Y.to_numpy()[(X["run"] == "R2").to_numpy()].ravel() - combined
    row = result.folds.set_index("fold").loc["R2"]
    assert row["rmse_um"] == pytest.approx(np.sqrt(np.mean(residual**2)), rel=1e-9)
    assert row["max_abs_um"] == pytest.approx(np.abs(residual).max(), rel=1e-9)


def test_the_selector_weights_the_member_of_the_lowest_mean_inner_rmse_worked_out_by_hand():
    # T2's rise makes most of the errors; both members fitted by plain least squares.
    X, Y, result = two_member_recommendation(0.3, 1.0, "select")
    runs = ["R1", "R2", "R3", "R4"]

    def weights(pairs):
        mean_rmse = [
            np.mean([np.sqrt(np.mean((Y.to_numpy()[(X["run"] == run).to_numpy()]
                                      - by_hand_predictions(X, Y, s, train, [run])) ** 2))
                     for train, run in pairs])
            for s in ("T1", "T2")
        ]  # fmt: skip
        return [1.0, 0.0] if mean_rmse[0] <= mean_rmse[1] else [0.0, 1.0]

    for fold in runs:
        inner = [([r for r in runs if r not in (fold, i)], i) for i in runs if i != fold]
        assert list(result.combination.folds[fold]) == weights(inner)
    every = [([r for r in runs if r != i], i) for i in runs]
    assert list(result.combination.final) == weights(every) == [0.0, 1.0]
    # The held-out error is the chosen member's, fitted on the fold's training runs.
    row = result.folds.set_index("fold").loc["R2"]
    chosen = "T1" if result.combination.folds["R2"][0] == 1.0 else "T2"
    residual = (Y.to_numpy()[(X["run"] == "R2").to_numpy()]
                - by_hand_predictions(X, Y, chosen, ["R1", "R3", "R4"], ["R2"]))  # fmt: skip
    assert row["rmse_um"] == pytest.approx(np.sqrt(np.mean(residual**2)), rel=1e-9)


def test_the_selector_counts_each_run_once_on_a_toy_problem_solved_by_hand():
    # Run A has one reading, run B nine. Member 1 is 4 off on A and exact on B: mean run RMSE
    # (4 + 0) / 2 = 2, though pooled over the ten readings sqrt(16 / 10) = 1.26. Member 2 is
    # 1.5 off everywhere: 1.5 either way. Each run counted once, member 2 is chosen.
    measured = [np.array([0.0]), np.zeros(9)]
    predictions = [np.array([[4.0, 1.5]]), np.column_stack([np.zeros(9), np.full(9, 1.5)])]
    np.testing.assert_array_equal(selector_weights(predictions, measured), [0.0, 1.0])
    # A missing measurement is left out of its run's RMSE: member 1 is then exact on A.
    measured = [np.array([4.0, np.nan]), np.zeros(9)]
    predictions = [np.array([[4.0, 1.5], [-50.0, 0.0]]), predictions[1]]
    np.testing.assert_array_equal(selector_weights(predictions, measured), [1.0, 0.0])
    # A tie goes to the first member.
    np.testing.assert_array_equal(
        selector_weights([np.array([[1.0, -1.0]])], [np.array([0.0])]), [1.0, 0.0]
    )


def test_run_rmse_weights_minimise_the_mean_run_rmse_worked_out_by_hand():
    # One reading a run, measured 0. Member 1 predicts 1 and 3, member 2 -1 and -1: the
    # combination's residuals are 2 w1 - 1 and 4 w1 - 1, their mean |.| falls until
    # w1 = 1/4 (0.25) and rises after: weights (1/4, 3/4).
    measured = [np.array([0.0]), np.array([0.0])]
    predictions = [np.array([[1.0, -1.0]]), np.array([[3.0, -1.0]])]
    np.testing.assert_allclose(run_rmse_weights(predictions, measured), [0.25, 0.75], atol=1e-6)
    # Random runs of unequal length, two members: a plain numpy grid over w1 in steps of
    # 5e-5 finds the same weights, and nothing on it does better.
    rng = np.random.default_rng(7)
    measured = [rng.normal(size=n) for n in (3, 8, 20)]
    predictions = [np.column_stack([m + rng.normal(0.3, 1.0, m.size), 0.5 * m + rng.normal(size=m.size)])
                   for m in measured]  # fmt: skip

    def mean_run_rmse(w):
        return np.mean(
            [np.sqrt(np.mean((m - p @ w) ** 2)) for p, m in zip(predictions, measured, strict=True)]
        )

    grid = np.linspace(0.0, 1.0, 20_001)
    risks = [mean_run_rmse(np.array([g, 1.0 - g])) for g in grid]
    w = run_rmse_weights(predictions, measured)
    assert w.sum() == pytest.approx(1.0, abs=1e-12) and (w >= 0).all()
    assert w[0] == pytest.approx(grid[int(np.argmin(risks))], abs=1e-4)
    assert mean_run_rmse(w) <= min(risks) + 1e-12
    # Three members, one of them useless: nothing on a simplex grid in steps of 0.01 does better.
    predictions = [np.column_stack([p, np.full(p.shape[0], 5.0)]) for p in predictions]
    w = run_rmse_weights(predictions, measured)
    simplex = [np.array([a, b, 1.0 - a - b]) for a in np.linspace(0, 1, 101)
               for b in np.linspace(0, 1, 101) if a + b <= 1.0 + 1e-12]  # fmt: skip
    assert mean_run_rmse(w) <= min(mean_run_rmse(np.clip(v, 0, None)) for v in simplex) + 1e-12
    assert w[2] == pytest.approx(0.0, abs=1e-9)
    # Errors of 1e4 um that the combination fits exactly: members m + e and m - 2e give
    # m + (3 w1 - 2) e, exact at w1 = 2/3. Moments (w'Aw - 2b'w + c) would cancel to
    # rounding noise of the squared errors' size there and leave w1 about 1e-5 off.
    big = [1e4 + 50.0 * rng.standard_normal(n) for n in (4, 6, 9)]
    wobble = [rng.standard_normal(m.size) for m in big]
    exact = [np.column_stack([m + e, m - 2.0 * e]) for m, e in zip(big, wobble, strict=True)]
    np.testing.assert_allclose(run_rmse_weights(exact, big), [2 / 3, 1 / 3], rtol=0, atol=1e-9)
    # Inputs changed in their last digits, as another CPU's BLAS kernels change them, move
    # the weights by no more than rounding: the minimum is found, not where a solver stopped.
    nudged = [p * (1.0 + 1e-15 * rng.standard_normal(p.shape)) for p in predictions]
    np.testing.assert_allclose(run_rmse_weights(nudged, measured), w, rtol=0, atol=1e-12)


def test_super_learner_weights_on_a_toy_problem_solved_by_hand():
    # Unconstrained least squares of y = (1, 2, 3) on the columns (1, 0, 1), (0, 1, 1):
    # normal equations [[2, 1], [1, 2]] w = (4, 5), w = (1, 2), scaled to (1/3, 2/3).
    P = np.array([[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]])
    np.testing.assert_allclose(super_learner_weights(P, np.array([1.0, 2.0, 3.0])), [1 / 3, 2 / 3])
    # A member that would need a negative weight gets 0: y = (1, -1) on the identity.
    np.testing.assert_allclose(super_learner_weights(np.eye(2), np.array([1.0, -1.0])), [1.0, 0.0])
    # No member helps (NNLS all zero): equal weights, as SuperLearner's method.NNLS.
    np.testing.assert_allclose(super_learner_weights(np.eye(2), np.array([-1.0, -1.0])), [0.5, 0.5])
    # A missing measurement is left out of the fit.
    y = np.array([1.0, 2.0, 3.0, np.nan])
    np.testing.assert_allclose(super_learner_weights(np.vstack([P, [5.0, 5.0]]), y), [1 / 3, 2 / 3])
    # scipy's NNLS on a random problem, scaled.
    rng = np.random.default_rng(3)
    P, y = rng.normal(size=(40, 3)), rng.normal(size=40)
    w, _ = nnls(P, y)
    np.testing.assert_allclose(super_learner_weights(P, y), w / w.sum())


def test_a_kernel_candidate_cannot_join_the_combination():
    with pytest.raises(ValueError, match=r"^config recommend.combine: 'pointwise-svr' is a kernel"):
        Settings.from_config({"recommend": {"combine": ["paper", "pointwise-svr"]}})
    extra = {"name": "my-gpr", "approach": "pointwise", "algorithm": "gpr"}
    with pytest.raises(ValueError, match="'my-gpr' is a kernel candidate"):
        Settings.from_config({"recommend": {"combine": ["my-gpr"], "extra_candidates": [extra]}})
    assert DEFAULTS.recommend.combine == (EVIDENCE, BASELINE)
    X, Y = make_runs(n_runs=3)
    with pytest.raises(ValueError, match="'nope' is not a candidate"):
        recommend(X, Y, CANDIDATES, reference="pointwise-mlr-T3", degree=1, members=["nope"],
                  max_loco_runs=12, n_group_folds=5)  # fmt: skip


def test_run_groups_become_group_folds_above_the_limit():
    runs = [f"R{i}" for i in range(1, 12)]
    assert run_groups(runs[:4], 12, 5) == [("R1",), ("R2",), ("R3",), ("R4",)]
    groups = run_groups(runs, 6, 5)
    assert len(groups) == 5
    assert sorted(r for g in groups for r in g) == sorted(runs)
    assert groups[0] == ("R1", "R2", "R3")  # contiguous, in natural order


def test_a_group_of_held_out_runs_is_fitted_once_and_scored_run_by_run():
    X, Y = make_runs(n_runs=6)
    group = ("R2", "R3")
    rows = held_out_scores(X, Y, ["R1", "R2", "R3", "R4"], [group], fixed("T1"), 1, [], {})
    # By hand: per position, least squares of the error on T1's rise since the run's first
    # measurement, fitted on R1 and R4 (R5, R6 are outside the training runs), each of R2
    # and R3 scored over its own rows.
    rise = X["T1"] - X.groupby("run")["T1"].transform("first")
    train = X["run"].isin(["R1", "R4"]).to_numpy()
    A = np.column_stack([np.ones(train.sum()), rise[train]])
    coef, *_ = np.linalg.lstsq(A, Y.to_numpy()[train], rcond=None)
    assert [row["held_out"] for row in rows] == ["R2", "R3"]
    for row in rows:
        test = (X["run"] == row["held_out"]).to_numpy()
        residual = Y.to_numpy()[test] - np.column_stack([np.ones(test.sum()), rise[test]]) @ coef
        assert row["rmse"] == pytest.approx(np.sqrt(np.mean(residual**2)), rel=1e-9)
        assert row["max_abs"] == pytest.approx(np.abs(residual).max(), rel=1e-9)


def test_evaluations_on_the_same_training_runs_share_one_fit():
    runs = ["R1", "R2", "R3", "R4"]
    sets = {s.train: s.scored for s in training_sets(runs, [(r,) for r in runs])}
    # By hand: four outer fits (three runs each) and the C(4, 2) = 6 pairs of runs the inner
    # loops train on, each pair serving two outer folds: 10 fits where 4 x (1 + 3) = 16
    # evaluations need one.
    assert len(sets) == 10
    assert sets[("R2", "R3", "R4")] == ("R1",)
    assert sets[("R3", "R4")] == ("R2", "R1")
    # An outer group of two runs out of six: its training set, then the inner loop leaves
    # each of the other four runs out alone, however many runs there are.
    grouped = training_sets([f"R{i}" for i in range(1, 7)], [("R1", "R2")])
    assert [(s.train, s.scored) for s in grouped] == [
        (("R3", "R4", "R5", "R6"), ("R1", "R2")),
        (("R4", "R5", "R6"), ("R3",)),
        (("R3", "R5", "R6"), ("R4",)),
        (("R3", "R4", "R6"), ("R5",)),
        (("R3", "R4", "R5"), ("R6",)),
    ]


def test_shared_fits_give_the_scores_of_one_fit_per_evaluation():
    X, Y = make_runs(n_runs=4)
    candidates = [fixed("T1"), fixed("T2")]
    runs = ["R1", "R2", "R3", "R4"]
    frames, combination = fold_scores(X, Y, candidates, runs, 1)
    shared = pd.concat(frames, ignore_index=True)
    assert combination is None
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
                       members=["pointwise-mlr-T1"], max_loco_runs=4,
                       n_group_folds=3)  # fmt: skip
    # Six runs above a limit of four: three outer groups, R1+R2, R3+R4, R5+R6, every run
    # still a row, each weighted without its group (one member: weight 1).
    assert list(result.folds["fold"]) == [f"R{i}" for i in range(1, 7)]
    assert result.folds["weight_pointwise-mlr-T1"].tolist() == [1.0] * 6
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


def test_with_two_runs_the_folds_and_the_final_weights_are_equal():
    X, Y = make_runs(n_runs=2)
    result = run(X, Y)
    # One training run per fold leaves no inner prediction: equal weights there; and each
    # run's held-out prediction is a fit on the other run alone, which weighs nothing.
    for fold in ("R1", "R2"):
        assert result.combination.folds[fold] == pytest.approx((0.25,) * 4)
    assert result.inner.empty
    assert result.combination.final == pytest.approx((0.25,) * 4)
    assert result.combination.equal_folds == ("R1", "R2")
    assert not result.combination.final_fitted


def test_with_three_runs_fits_on_one_run_weigh_nothing_but_the_final_weights_are_fitted():
    # The errors follow T1 + 0.5 T2's rises: members on T1 alone and on T2 alone each
    # explain part, so fitted weights are far from equal (0.5, 0.5).
    X, Y, result = two_member_recommendation(1.0, 0.5, "rmse", n_runs=3)
    runs = ["R1", "R2", "R3"]
    c = result.combination
    # Every fold trains on two runs, so its inner fits hold one run: equal weights, and the
    # fold's held-out error is the plain mean of the members fitted on the two runs.
    assert c.equal_folds == tuple(runs)
    for held in runs:
        assert c.folds[held] == (0.5, 0.5)
        train = [r for r in runs if r != held]
        mean = 0.5 * sum(by_hand_predictions(X, Y, s, train, [held]) for s in ("T1", "T2"))
        residual = Y.to_numpy()[(X["run"] == held).to_numpy()] - mean
        row = result.folds.set_index("fold").loc[held]
        assert row["rmse_um"] == pytest.approx(np.sqrt(np.mean(residual**2)), rel=1e-9)
    # The final weights weigh each run's held-out prediction by the fit on the other two:
    # the lowest mean run RMSE, on a plain numpy grid of w (T1's weight) in steps of 1e-4.
    assert c.final_fitted
    held_out = [
        (Y.to_numpy()[(X["run"] == r).to_numpy()],
         [by_hand_predictions(X, Y, s, [o for o in runs if o != r], [r]) for s in ("T1", "T2")])
        for r in runs
    ]  # fmt: skip
    grid = np.linspace(0.0, 1.0, 10001)
    risk = [np.mean([np.sqrt(np.mean((y - w * a - (1 - w) * b) ** 2)) for y, (a, b) in held_out])
            for w in grid]  # fmt: skip
    assert c.final[0] == pytest.approx(grid[int(np.argmin(risk))], abs=2e-4)
    assert 0.05 < c.final[0] < 0.95 and abs(c.final[0] - 0.5) > 0.05


def test_replacing_the_held_out_runs_data_changes_no_weight_of_its_fold():
    X, Y = make_runs(n_runs=5, seed=4)
    # Members that share the work: errors follow T1 and T2 (noise 0.05 um), and a
    # bayesridge member (not through the numpy core).
    rises = X[["T1", "T2"]] - X.groupby("run")[["T1", "T2"]].transform("first")
    Y = Y + (0.7 * rises["T2"]).to_numpy()[:, None]
    evidence = replace(fixed("T1"), name="evidence-T1", algorithm="bayesridge")
    candidates = [*CANDIDATES, evidence]
    members = ["pointwise-mlr-T1", "pointwise-mlr-T2", "evidence-T1"]
    kwargs = dict(reference="pointwise-mlr-T3", degree=1, members=members, max_loco_runs=12,
                  n_group_folds=5)  # fmt: skip
    honest = recommend(X, Y, candidates, **kwargs)
    assert min(honest.combination.folds["R2"]) < 0.99  # more than one member weighs
    # R2's temperatures and errors replaced by noise, and by a constant: fold R2's weights,
    # and the inner scores they are fitted beside, come from R1, R3, R4, R5 alone.
    rng = np.random.default_rng(11)
    at = (X["run"] == "R2").to_numpy()
    noisy_X, noisy_Y = X.copy(), Y.copy()
    noisy_X.loc[at, ["T1", "T2", "T3", "T4"]] = rng.normal(50.0, 9.0, size=(at.sum(), 4))
    noisy_Y.loc[at] = 123.0
    constant_Y = Y.copy()
    constant_Y.loc[at] = -4.0
    for replaced_X, replaced_Y in ((noisy_X, noisy_Y), (X, constant_Y)):
        other = recommend(replaced_X, replaced_Y, candidates, **kwargs)
        np.testing.assert_allclose(
            other.combination.folds["R2"], honest.combination.folds["R2"], rtol=1e-9, atol=1e-12
        )
        before = honest.folds.set_index("fold").loc["R2"]
        after = other.folds.set_index("fold").loc["R2"]
        for m in members:
            assert after[f"weight_{m}"] == pytest.approx(before[f"weight_{m}"], rel=1e-9, abs=1e-12)
        inner = [
            r.inner.loc[r.inner["fold"] == "R2"].reset_index(drop=True) for r in (honest, other)
        ]
        pd.testing.assert_frame_equal(inner[0], inner[1], rtol=1e-12)
        # The held-out error itself sees the new data (a constant far from the fit).
        assert after["rmse_um"] > 10 * before["rmse_um"]
        # The other folds' weights see R2: it is one of their inner runs.
        assert not np.allclose(other.combination.folds["R1"], honest.combination.folds["R1"])


def test_the_inner_loop_leaves_one_run_out_above_the_outer_limit():
    X, Y = make_runs(n_runs=7, n_measurements=5)
    result = recommend(X, Y, CANDIDATES[:2], reference="pointwise-mlr-T3", degree=1,
                       members=MEMBERS[:2], max_loco_runs=3, n_group_folds=2)  # fmt: skip
    # Seven runs above an outer limit of three: two outer groups (R1-R4, R5-R7); inside
    # each, every training run is held out on its own.
    inner = result.inner.loc[result.inner["fold"] == "R1"]
    assert sorted(set(inner["held_out"])) == ["R5", "R6", "R7"]
    inner = result.inner.loc[result.inner["fold"] == "R6"]
    assert sorted(set(inner["held_out"])) == ["R1", "R2", "R3", "R4"]


def test_the_plain_references_are_always_candidates_and_see_only_their_own_lags():
    candidates = default_candidates(
        DEFAULTS.selection, DEFAULTS.models, True, ["S"], (30.0,), (20.0, 60.0, 180.0)
    )
    by_name = {c.name: c for c in candidates}
    assert list(by_name) == [
        "paper", EVIDENCE, f"{EVIDENCE}+lags", BASELINE, "decoupled-pls-all",
        "decoupled-pls-all+lags", "pointwise-svr",
    ]  # fmt: skip
    # The evidence ridge: decoupled over every sensor with the declared signal, no search.
    evidence = by_name[EVIDENCE]
    assert (evidence.approach, evidence.algorithm, evidence.selection.method) == (
        "decoupled", "bayesridge", "all",
    )  # fmt: skip
    assert evidence.models.signals == ("S",) and evidence.models.searched == ()
    assert by_name[f"{EVIDENCE}+lags"].lags_min == (20.0, 60.0, 180.0)
    # One position: point by point; beyond recommend.kernel_max_runs, no kernel candidate.
    single = default_candidates(
        DEFAULTS.selection, DEFAULTS.models, False, [], (), (60.0,), kernel=False
    )
    assert [c.name for c in single] == [
        "paper", EVIDENCE, f"{EVIDENCE}+lags", BASELINE, "pointwise-pls-all",
    ]  # fmt: skip
    assert {c.approach for c in single} == {"pointwise"}
    baseline = by_name[BASELINE]
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


def test_the_page_says_which_folds_and_whether_the_final_weights_were_weighed():
    # Two runs: each fold trains on one run, so it weights its members equally.
    folds = pd.DataFrame(
        {"fold": ["R1", "R2"], "chosen": [COMBINED] * 2, "weight_a": [0.5, 0.5],
         "weight_b": [0.5, 0.5], "rmse_um": [5.0, 1.5], "max_abs_um": [8.0, 3.5],
         "paper_rmse_um": [5.0, 1.5], "paper_max_abs_um": [8.0, 3.5]}
    )  # fmt: skip
    combination = Combination(("a", "b"), {"R1": (0.5, 0.5), "R2": (0.5, 0.5)}, (0.5, 0.5),
                              ("R1", "R2"), False)  # fmt: skip
    page = recommendation_markdown(
        Recommendation(folds, pd.DataFrame(), pd.DataFrame(), COMBINED, combination),
        "Dataset `two`: SIMULATED data.",
    )
    assert (
        "Fold(s) R1, R2 had fewer than three training runs, so no inner fit on two runs or "
        "more to weigh the members on: they weight them equally." in page
    )
    assert (
        "with equal weights (every run's held-out prediction is a fit on a single run) "
        "(a 0.500, b 0.500)" in page
    )
    # The means over the two folds: RMSE (5.0 + 1.5) / 2, largest |residual| (8.0 + 3.5) / 2.
    assert (
        "a mean held-out RMSE of 3.25 µm and a mean largest |residual| of 5.75 µm, against "
        "3.25 and 5.75 µm for the paper's configuration" in page
    )
    fitted = Combination(("a", "b"), {"R1": (0.5, 0.5), "R2": (0.1, 0.9)}, (0.25, 0.75),
                         ("R1",), True)  # fmt: skip
    page = recommendation_markdown(
        Recommendation(folds, pd.DataFrame(), pd.DataFrame(), COMBINED, fitted), "x"
    )
    assert "with the weights fitted on every run's held-out predictions (a 0.250, b 0.750)" in page
    assert "Fold(s) R1 had fewer than three training runs" in page and "R1, R2" not in page


def test_held_out_predictions_are_the_fit_on_the_other_runs():
    X, Y = make_runs(n_runs=4)
    runs, predicted = held_out_predictions(X, Y, ("R2", "R4"), fixed("T1"), 1, [], {})
    # By hand: least squares of each position's error on T1's rise, fitted on R1 and R3.
    rise = X["T1"] - X.groupby("run")["T1"].transform("first")
    train, test = X["run"].isin(["R1", "R3"]).to_numpy(), X["run"].isin(["R2", "R4"]).to_numpy()
    A = np.column_stack([np.ones(train.sum()), rise[train]])
    coef, *_ = np.linalg.lstsq(A, Y.to_numpy()[train], rcond=None)
    expected = np.column_stack([np.ones(test.sum()), rise[test]]) @ coef
    assert list(runs) == list(X.loc[test, "run"])
    np.testing.assert_allclose(predicted, expected, rtol=1e-9, atol=1e-9)


def test_the_kernel_candidate_is_capped_by_the_runs_not_the_others():
    settings = Settings.from_config({"recommend": {"kernel_max_runs": 6}})

    def names(n_runs):
        return [c.name for c in candidates_for(settings.selection, settings.models,
                                               settings.recommend, False, [], n_runs)]  # fmt: skip

    assert names(6)[-1] == "pointwise-svr"
    assert names(7) == names(6)[:-1]
