"""The batched linear evaluations equal evaluate_configuration's scikit-learn fits to 1e-9."""

from dataclasses import replace
from itertools import combinations

import numpy as np
import pandas as pd
import pytest

from helpers import DEFAULTS
from thermaxis.method.batched import batchable, decoupled_metrics, pointwise_metrics
from thermaxis.method.folds import FoldSelection, evaluate_configuration
from thermaxis.method.metrics import METRIC_COLUMNS
from thermaxis.method.selection import SensitivePoints

SENSORS = [f"T{i}" for i in range(1, 7)]
POSITIONS = np.linspace(0.0, 600.0, 7)


def runs(collinear: bool = False, seed: int = 3, noise_um: float = 0.2):
    """Four runs of nine measurements; errors linear in two sensors plus a curvature and noise.

    ``collinear``: T6 is T5 plus a few millikelvin, the near-duplicate sensors of a real rig."""
    rng = np.random.default_rng(seed)
    rows, curves = [], []
    for r in range(4):
        heat = np.cumsum(rng.uniform(0.2, 1.0, 9))
        for m in range(9):
            t = 22.0 + r + heat[m] * rng.uniform(0.5, 1.5, len(SENSORS))
            if collinear:
                t[5] = t[4] + rng.normal(0.0, 0.003)
            rows.append({"run": f"E{r + 1}", "measurement": m + 1, "time_min": 15.0 * m,
                         **dict(zip(SENSORS, t, strict=True))})  # fmt: skip
            k, b = 4.0 * (t[0] - 22.0), -3.0 * (t[2] - t[3]) + 0.5 * t[1]
            curve = k * POSITIONS / 1000.0 + b + 1e-5 * t[4] * POSITIONS**2 / 100.0
            curves.append(curve + rng.normal(0.0, noise_um, POSITIONS.size))
    return pd.DataFrame(rows), pd.DataFrame(curves, columns=POSITIONS)


def points(selected) -> SensitivePoints:
    return SensitivePoints(clusters=tuple((s,) for s in selected), selected=tuple(selected),
                           grades={}, eta=0.0)  # fmt: skip


def selection(k, b, pointwise) -> FoldSelection:
    return FoldSelection("any", points(k), points(b), pointwise=tuple(pointwise))


MODELS = replace(DEFAULTS.models, ridge_alpha=0.7, pls_components=2)


def assert_same(got: pd.DataFrame, expected: pd.DataFrame):
    assert list(got.columns) == list(expected.columns)
    assert got[["fold", "approach", "algorithm", "target"]].equals(
        expected[["fold", "approach", "algorithm", "target"]]
    )
    np.testing.assert_allclose(
        got[list(METRIC_COLUMNS)].to_numpy(),
        expected[list(METRIC_COLUMNS)].to_numpy(),
        rtol=1e-9,
        atol=1e-12,
    )


@pytest.mark.parametrize("collinear", [False, True])
@pytest.mark.parametrize("algorithm", ["mlr", "ridge", "pls"])
@pytest.mark.parametrize("degree", [1, 2, 3])
def test_decoupled_equals_scikit_learn(algorithm, degree, collinear):
    X, Y = runs(collinear)
    pairs = [
        (("T1", "T5", "T6"), ("T3", "T4")),
        (("T2",), ("T1", "T3", "T4")),
        (("T5", "T6"), ("T2",)),
    ]
    for fold in ("E1", "E3"):
        got = decoupled_metrics(X, Y, fold, algorithm, MODELS, degree, pairs)
        for (k, b), frame in zip(pairs, got, strict=True):
            expected = evaluate_configuration(
                X, Y, fold, "decoupled", algorithm, selection(k, b, ()), MODELS, degree
            ).metrics
            assert_same(frame, expected)


@pytest.mark.parametrize("collinear", [False, True])
@pytest.mark.parametrize("algorithm", ["mlr", "ridge", "pls"])
def test_pointwise_equals_scikit_learn(algorithm, collinear):
    X, Y = runs(collinear)
    sets = list(combinations(SENSORS, 3)) + [("T2",), ("T5", "T6")]
    got = pointwise_metrics(X, Y, "E2", algorithm, MODELS, sets)
    for points, frame in zip(sets, got, strict=True):
        expected = evaluate_configuration(
            X, Y, "E2", "pointwise", algorithm, selection((), (), points), MODELS, None
        ).metrics
        assert_same(frame, expected)


SEARCHED = replace(MODELS, searched=("ridge", "pls"))
# Three training runs above max_loco_runs 2: the inner search deals them into group folds.
GROUP_FOLDS = replace(SEARCHED, inner_search=(2, 2))


@pytest.mark.parametrize("models", [SEARCHED, GROUP_FOLDS], ids=["leave-one-out", "group-folds"])
@pytest.mark.parametrize("algorithm", ["ridge", "pls"])
def test_searched_strengths_equal_scikit_learn(algorithm, models):
    # 3 um of noise: the inner search then picks different strengths for different outputs
    # (ridge alpha from 0.01 to 100 here), so each output's choice is checked.
    X, Y = runs(collinear=True, noise_um=3.0)
    pairs = [(("T1", "T5", "T6"), ("T3", "T4")), (tuple(SENSORS), tuple(SENSORS))]
    for (k, b), frame in zip(
        pairs, decoupled_metrics(X, Y, "E3", algorithm, models, 2, pairs), strict=True
    ):
        expected = evaluate_configuration(
            X, Y, "E3", "decoupled", algorithm, selection(k, b, ()), models, 2
        )
        assert_same(frame, expected.metrics)
    sets = [tuple(SENSORS), ("T2", "T3")]
    for points, frame in zip(
        sets, pointwise_metrics(X, Y, "E1", algorithm, models, sets), strict=True
    ):
        expected = evaluate_configuration(
            X, Y, "E1", "pointwise", algorithm, selection((), (), points), models, None
        )
        assert_same(frame, expected.metrics)


def test_a_pls_grid_point_past_the_inner_rows_ranks_last_as_the_pipelines_rank_it():
    # Two measurements a run: fold E3's inner splits train on 4 rows, fewer than 6
    # components on all six sensors. Such a point scores NaN in both paths (scikit-learn's
    # GridSearchCV does the same, test_models) instead of stopping. (Between the rank and
    # the rows, 3 and 4 components, PLS fits rounding noise: no grid point there.)
    X, Y = runs(collinear=True, noise_um=3.0)
    few = (X["measurement"] <= 2).to_numpy()
    X, Y = X[few].reset_index(drop=True), Y[few].reset_index(drop=True)
    grids = tuple((a, (("n_components", (6, 1, 2)),) if a == "pls" else g)
                  for a, g in SEARCHED.search_grids)  # fmt: skip
    models = replace(SEARCHED, search_grids=grids)
    every = tuple(SENSORS)
    (decoupled,) = decoupled_metrics(X, Y, "E3", "pls", models, 1, [(every, every)])
    expected = evaluate_configuration(
        X, Y, "E3", "decoupled", "pls", selection(every, every, ()), models, 1
    )
    assert_same(decoupled, expected.metrics)
    (pointwise,) = pointwise_metrics(X, Y, "E3", "pls", models, [every])
    expected = evaluate_configuration(
        X, Y, "E3", "pointwise", "pls", selection((), (), every), models, None
    )
    assert_same(pointwise, expected.metrics)


@pytest.mark.parametrize("models", [MODELS, SEARCHED], ids=["fixed", "searched"])
def test_operating_signals_join_every_point_set(models):
    X, Y = runs(noise_um=1.0)
    speed = np.tile(np.r_[0.0, np.full(8, 1.0)], 4) * np.repeat([1000.0, 2000.0, 1500.0, 3000.0], 9)
    X["S"], Y = speed, Y.add(0.002 * speed, axis=0)
    with_speed = replace(models, signals=("S",))
    pairs = [(("T1", "T5"), ("T3",))]
    (frame,) = decoupled_metrics(X, Y, "E2", "ridge", with_speed, 1, pairs)
    expected = evaluate_configuration(
        X, Y, "E2", "decoupled", "ridge", selection(*pairs[0], ()), with_speed, 1
    )
    assert_same(frame, expected.metrics)
    (frame,) = pointwise_metrics(X, Y, "E2", "pls", with_speed, [("T2", "T4")])
    expected = evaluate_configuration(
        X, Y, "E2", "pointwise", "pls", selection((), (), ("T2", "T4")), with_speed, None
    )
    assert_same(frame, expected.metrics)


def test_a_perfect_model_is_exact_by_hand():
    # Errors exactly 2 um per degree of T1's rise at every position: MLR on T1 predicts a
    # held-out run without residual, whatever the other runs' temperatures.
    X, _ = runs()
    rise = X["T1"] - X.groupby("run")["T1"].transform("first")
    Y = pd.DataFrame(np.outer(2.0 * rise, np.ones(POSITIONS.size)), columns=POSITIONS)
    (frame,) = pointwise_metrics(X, Y, "E4", "mlr", MODELS, [("T1",)])
    assert frame["max_abs"].iloc[0] < 1e-9


def test_what_is_not_batched():
    _, Y = runs()
    assert batchable("mlr", MODELS, Y) and batchable("pls", MODELS, Y)
    assert not batchable("svr", MODELS, Y) and not batchable("gpr", MODELS, Y)
    assert not batchable("lasso", MODELS, Y) and batchable("ridge", SEARCHED, Y)
    Y.iloc[3, 2] = np.nan
    assert not batchable("mlr", MODELS, Y)


@pytest.mark.parametrize("n_inputs", [5, 40])
def test_the_ridge_search_scores_every_strength_as_scikit_learns_pipeline(n_inputs):
    # Inner leave-one-run-out RMSE of StandardScaler + Ridge (y standardised too), one
    # pipeline per output, strength and held-out run, averaged over the runs: fewer and
    # more inputs than training rows (3 runs x 6 rows = 18).
    from sklearn.compose import TransformedTargetRegressor
    from sklearn.linear_model import Ridge
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import StandardScaler

    from thermaxis.method.batched import _ridge_inner_rmse

    rng = np.random.default_rng(5)
    held = np.repeat(np.arange(4), 6)
    X = rng.normal(size=(held.size, n_inputs)) + held[:, None]
    Y = np.column_stack([X[:, 0] - 2 * X[:, 1], X[:, 2] ** 2]) + rng.normal(0, 0.1, (held.size, 2))
    alphas = [0.01, 1.0, 100.0]
    expected = np.zeros((len(alphas), 2))
    for a, alpha in enumerate(alphas):
        for output in range(2):
            for group in range(4):
                model = make_pipeline(
                    StandardScaler(),
                    TransformedTargetRegressor(
                        regressor=Ridge(alpha=alpha), transformer=StandardScaler()
                    ),
                )
                model.fit(X[held != group], Y[held != group, output])
                residual = Y[held == group, output] - model.predict(X[held == group])
                expected[a, output] += np.sqrt(np.mean(residual**2)) / 4
    np.testing.assert_allclose(_ridge_inner_rmse(X, Y, held, alphas), expected, rtol=1e-9)


def test_the_held_out_rows_never_reach_the_ridge_search():
    # The searched ridge predicts held-out rows A and B; B's temperatures are then changed
    # wildly. A's predictions do not move: the strength was chosen, and the model fitted,
    # on the training runs alone.
    from thermaxis.method.batched import _Fitter

    rng = np.random.default_rng(9)
    runs = np.repeat(np.array(["R1", "R2", "R3", "R4"]), 6)
    train = rng.normal(size=(runs.size, 30)) + np.repeat(np.arange(4), 6)[:, None]
    targets = np.column_stack([train[:, 0] - train[:, 3], train[:, 5]])
    targets = targets + rng.normal(0, 0.2, targets.shape)
    held_a, held_b = rng.normal(size=(5, 30)), rng.normal(size=(5, 30))
    fitter = _Fitter("ridge", replace(DEFAULTS.models, searched=("ridge",)), runs)
    assert fitter.grid is not None and len(fitter.grid) > 1
    before = fitter._searched(train, targets, np.vstack([held_a, held_b]))
    after = fitter._searched(train, targets, np.vstack([held_a, 100.0 * held_b + 50.0]))
    np.testing.assert_array_equal(before[:5], after[:5])
    assert not np.allclose(before[5:], after[5:])
