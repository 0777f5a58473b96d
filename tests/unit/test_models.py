"""Tests of thermaxis.method.estimators, regressors and search against coefficients known by construction or computed
directly."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from sklearn.base import clone
from threadpoolctl import threadpool_limits

from helpers.builders import synthetic_temperatures
from helpers.truth import EQ8, EQ9_B, EQ9_K, POSITIONS, SENSORS, eq8_errors, eq9_errors, eq9_truth
from thermaxis.method.estimators import DecoupledAxisModel, PointwiseAxisModel
from thermaxis.method.features import relative_temperatures
from thermaxis.method.regressors import linear_terms, make_regressor, predict_with_std
from thermaxis.method.search import fit_by_group_search
from thermaxis.vocabulary import ALGORITHMS

pytestmark = pytest.mark.filterwarnings("ignore::sklearn.exceptions.ConvergenceWarning")


@pytest.fixture(autouse=True, scope="module")
def _single_blas_thread():
    # The matrices here are tiny: BLAS threads only add start-up and contention cost.
    with threadpool_limits(limits=1):
        yield


# --------------------------------------------------------------------------- relative temperatures


def test_relative_temperatures_use_each_runs_own_first_measurement():
    X = pd.DataFrame(
        {
            "run": ["B", "A", "A", "B", "A"],
            "measurement": [2, 3, 1, 1, 2],
            "T1": [25.0, 12.0, 10.0, 20.0, 11.5],
        },
        index=[10, 11, 12, 13, 14],
    )
    rel = relative_temperatures(X.assign(note="text columns are not sensors"))
    # A's reference is 10.0 (measurement 1), B's is 20.0.
    assert rel.index.tolist() == [10, 11, 12, 13, 14] and list(rel.columns) == ["T1"]
    np.testing.assert_allclose(rel["T1"].to_numpy(), [5.0, 2.0, 0.0, 0.0, 1.5])


# --------------------------------------------------------------------------- exact recovery


def test_decoupled_mlr_recovers_eq9_and_predicts_exactly():
    X = synthetic_temperatures()
    Y = eq9_errors(X)
    model = DecoupledAxisModel().fit(X, Y)

    coefs = model.coefficients()
    assert len(coefs) == 8 and coefs["position_mm"].isna().all()
    found = {(r.target, r.term, r.temperature): r.value for r in coefs.itertuples()}
    for target, eq, kind in (("k", EQ9_K, "absolute"), ("b", EQ9_B, "relative")):
        for term, value in eq.items():
            assert found[(target, term, kind)] == pytest.approx(value, abs=1e-6), (target, term)

    k, b = eq9_truth(X)
    np.testing.assert_allclose(model.kb_["k_um_per_m"], k, atol=1e-8)
    np.testing.assert_allclose(model.kb_["b_um"], b, atol=1e-8)

    # A run never seen in training, predicted from its own temperatures only.
    X_new = synthetic_temperatures(runs=("E5",), seed=7)
    np.testing.assert_allclose(model.predict(X_new), eq9_errors(X_new).to_numpy(), atol=1e-6)
    kb = model.predict_kb(X_new)
    k_new, b_new = eq9_truth(X_new)
    np.testing.assert_allclose(kb["k_um_per_m"], k_new, atol=1e-6)
    np.testing.assert_allclose(kb["b_um"], b_new, atol=1e-6)


def test_decoupled_skips_missing_readings():
    X = synthetic_temperatures()
    Y = eq9_errors(X)
    Y.iloc[3, 0] = np.nan  # lost first target: b is still defined at 185 mm through origin_mm
    Y.iloc[10, 7] = np.nan
    model = DecoupledAxisModel().fit(X, Y)
    k, b = eq9_truth(X)
    np.testing.assert_allclose(model.kb_["b_um"], b, atol=1e-8)
    coefs = model.coefficients().set_index(["target", "term"])["value"]
    assert coefs[("k", "T6")] == pytest.approx(EQ9_K["T6"], abs=1e-6)
    assert coefs[("b", "T2")] == pytest.approx(EQ9_B["T2"], abs=1e-6)


def test_decoupled_degree_two_models_curvature_on_absolute_temperatures():
    X = synthetic_temperatures()
    c2_terms = {"const": 40.0, "T1": -2.0, "T6": 1.5, "T12": 0.5}  # um/m^2
    c2 = c2_terms["const"] + sum(v * X[s].to_numpy() for s, v in c2_terms.items() if s != "const")
    model = DecoupledAxisModel(degree=2).fit(X, eq9_errors(X, c2=c2))
    coefs = model.coefficients().set_index(["target", "term"])
    for term, value in c2_terms.items():
        assert coefs.loc[("c2", term), "value"] == pytest.approx(value, abs=1e-6)
        assert coefs.loc[("c2", term), "temperature"] == "absolute"
    assert coefs.loc[("k", "T1"), "value"] == pytest.approx(EQ9_K["T1"], abs=1e-6)
    X_new = synthetic_temperatures(runs=("E5",), seed=3)
    c2_new = c2_terms["const"] + sum(
        v * X_new[s].to_numpy() for s, v in c2_terms.items() if s != "const"
    )
    np.testing.assert_allclose(
        model.predict(X_new), eq9_errors(X_new, c2=c2_new).to_numpy(), atol=1e-6
    )


def test_pointwise_mlr_recovers_eq8_per_position():
    X = synthetic_temperatures()
    Y = eq8_errors(X)
    Y.iloc[5, 2] = np.nan  # one missing reading: that position's fit uses the other 31 rows
    model = PointwiseAxisModel().fit(X, Y)
    coefs = model.coefficients()
    assert set(coefs["target"]) == {"error"} and set(coefs["temperature"]) == {"relative"}
    table = coefs.pivot(index="position_mm", columns="term", values="value")
    np.testing.assert_allclose(table.index.to_numpy(), POSITIONS)
    np.testing.assert_allclose(table[["const", "T1", "T11", "T12"]].to_numpy(), EQ8, atol=1e-6)
    X_new = synthetic_temperatures(runs=("E5",), seed=11)
    np.testing.assert_allclose(model.predict(X_new), eq8_errors(X_new).to_numpy(), atol=1e-6)


# --------------------------------------------------------------------------- leakage


def _noisy_eq9():
    X = synthetic_temperatures()
    rng = np.random.default_rng(5)
    Y = eq9_errors(X) + rng.normal(0.0, 0.3, (len(X), POSITIONS.size))
    return X, Y


SMALL_GRID = {"C": [1.0, 10.0], "epsilon": [0.05], "gamma": ["scale"]}


@pytest.mark.parametrize("algorithm", ALGORITHMS)
@pytest.mark.parametrize("approach", ["decoupled", "pointwise"])
def test_held_out_errors_do_not_reach_the_fold_model(algorithm, approach):
    X, Y = _noisy_eq9()
    if approach == "pointwise":
        Y = Y.iloc[:, ::4]  # four positions are enough and keep the svr search fast
    held_out = "E3"
    perturbed = Y.copy()
    rows = (X["run"] == held_out).to_numpy()
    perturbed.loc[rows, :] = perturbed.loc[rows, :].to_numpy() + 50.0 * np.random.default_rng(
        1
    ).normal(size=(rows.sum(), Y.shape[1]))
    cls = DecoupledAxisModel if approach == "decoupled" else PointwiseAxisModel
    estimator = cls(algorithm=algorithm, svr_grid=SMALL_GRID)

    def folds(Y):
        """Fold -> (model fitted without the run, its prediction of the run)."""
        out = {}
        for fold in sorted(set(X["run"])):
            test = (X["run"] == fold).to_numpy()
            model = clone(estimator).fit(
                X[~test].reset_index(drop=True), Y[~test].reset_index(drop=True)
            )
            out[fold] = model, np.asarray(model.predict(X[test].reset_index(drop=True)))
        return out

    original, changed = folds(Y), folds(perturbed)
    np.testing.assert_array_equal(original[held_out][1], changed[held_out][1])
    pd.testing.assert_frame_equal(
        original[held_out][0].coefficients(), changed[held_out][0].coefficients()
    )
    assert original[held_out][0].searched_params_ == changed[held_out][0].searched_params_
    # The perturbation is large enough to show up wherever E3 IS used for training.
    assert any(not np.allclose(original[f][1], changed[f][1]) for f in original if f != held_out)


def test_prediction_uses_only_the_predicted_runs_temperatures():
    X = synthetic_temperatures()
    Y = eq9_errors(X)
    model = DecoupledAxisModel(algorithm="ridge").fit(X, Y)
    alone = model.predict(X[X["run"] == "E2"])
    shuffled = X.sample(frac=1.0, random_state=0)
    together = pd.DataFrame(model.predict(shuffled), index=shuffled.index).loc[
        X.index[X["run"] == "E2"]
    ]
    np.testing.assert_allclose(together.to_numpy(), alone, rtol=0, atol=1e-12)


# --------------------------------------------------------------------------- regressors


def _noisy_linear(n=40, seed=0):
    rng = np.random.default_rng(seed)
    X = rng.normal(30.0, 3.0, (n, 3)) + np.array([0.0, 5.0, -2.0])
    y = 4.0 + X @ np.array([1.5, -0.7, 0.2]) + rng.normal(0.0, 0.5, n)
    return X, y


def test_mlr_matches_plain_least_squares_and_is_unit_invariant():
    X, y = _noisy_linear()
    names = ["a", "b", "c"]
    terms = linear_terms(make_regressor("mlr", random_state=0).fit(X, y), names)
    design = np.column_stack([np.ones(len(X)), X])
    direct, *_ = np.linalg.lstsq(design, y, rcond=None)
    np.testing.assert_allclose([terms[n] for n in ("const", *names)], direct, rtol=1e-9, atol=1e-9)

    # Same data in degrees Fahrenheit: identical predictions, slopes divided by 1.8.
    X_f = X * 1.8 + 32.0
    model_f = make_regressor("mlr", random_state=0).fit(X_f, y)
    np.testing.assert_allclose(model_f.predict(X_f), design @ direct, atol=1e-9)
    terms_f = linear_terms(model_f, names)
    np.testing.assert_allclose([terms_f[n] for n in names], direct[1:] / 1.8, rtol=1e-9)


def _standardised(X, y):
    mx, sx = X.mean(axis=0), X.std(axis=0)
    my, sy = y.mean(), y.std()
    return (X - mx) / sx, (y - my) / sy, (mx, sx, my, sy)


def _to_original(beta_s, stats):
    mx, sx, my, sy = stats
    slopes = beta_s * sy / sx
    return np.concatenate([[my - slopes @ mx], slopes])


def test_ridge_linear_terms_match_closed_form():
    X, y = _noisy_linear()
    alpha = 7.0
    terms = linear_terms(
        make_regressor("ridge", {"alpha": alpha}, random_state=0).fit(X, y), ["a", "b", "c"]
    )
    Xs, ys, stats = _standardised(X, y)
    beta_s = np.linalg.solve(Xs.T @ Xs + alpha * np.eye(3), Xs.T @ ys)
    np.testing.assert_allclose(
        list(terms.values()), _to_original(beta_s, stats), rtol=1e-9, atol=1e-9
    )


def test_pls_linear_terms_match_one_component_closed_form():
    X, y = _noisy_linear()
    terms = linear_terms(
        make_regressor("pls", {"n_components": 1}, random_state=0).fit(X, y), ["a", "b", "c"]
    )
    Xs, ys, stats = _standardised(X, y)
    w = Xs.T @ ys
    w /= np.linalg.norm(w)
    t = Xs @ w
    q = (t @ ys) / (t @ t)
    np.testing.assert_allclose(
        list(terms.values()), _to_original(w * q, stats), rtol=1e-8, atol=1e-8
    )


def test_pls_with_all_components_is_least_squares():
    X, y = _noisy_linear()
    model = make_regressor("pls", {"n_components": 5}, random_state=0, n_features=3).fit(X, y)
    direct, *_ = np.linalg.lstsq(np.column_stack([np.ones(len(X)), X]), y, rcond=None)
    np.testing.assert_allclose(
        list(linear_terms(model, ["a", "b", "c"]).values()), direct, rtol=1e-7, atol=1e-7
    )


def test_linear_terms_is_none_for_nonlinear_algorithms():
    X, y = _noisy_linear()
    for algorithm in ("svr", "gpr"):
        assert (
            linear_terms(make_regressor(algorithm, random_state=0).fit(X, y), ["a", "b", "c"])
            is None
        )


def test_gpr_interval_contains_mean_and_widens_away_from_data():
    x = np.linspace(0.0, 3.0, 15)[:, None]
    y = np.sin(x).ravel()
    model = make_regressor("gpr", random_state=0).fit(x, y)
    mean, std = predict_with_std(model, np.array([[1.5], [9.0]]))
    np.testing.assert_allclose(mean, model.predict(np.array([[1.5], [9.0]])), atol=1e-9)
    assert np.all(std > 0)
    assert std[1] > 5 * std[0]
    assert mean[0] == pytest.approx(np.sin(1.5), abs=0.05)


def test_decoupled_gpr_interval_brackets_prediction_and_widens_far_from_training():
    X, Y = _noisy_eq9()
    model = DecoupledAxisModel(algorithm="gpr").fit(X, Y)
    X_near = synthetic_temperatures(runs=("E5",), seed=7)
    X_far = X_near.assign(**{s: X_near[s] + 25.0 for s in SENSORS})  # same rise, hotter machine
    for X_new in (X_near, X_far):
        lower, upper = model.predict_interval(X_new, level=0.9)
        mean = model.predict(X_new)
        assert lower.shape == mean.shape == (8, 14)
        assert np.all(lower < mean) and np.all(mean < upper)
    width_near = np.subtract(*model.predict_interval(X_near, level=0.95)[::-1])
    width_far = np.subtract(*model.predict_interval(X_far, level=0.95)[::-1])
    # k uses absolute temperatures, so the far run's slope is uncertain: wider at the far end.
    assert np.all(width_far[:, -1] > width_near[:, -1])
    # Independence of k and b: half-width z*sd(b) at the origin,
    # z*sqrt(sd(b)^2 + (0.26 m sd(k))^2) at 445 mm.
    kb = model.predict_kb(X_near, return_std=True)
    np.testing.assert_allclose(kb[["k_um_per_m", "b_um"]], model.predict_kb(X_near), atol=1e-9)
    assert (kb["k_um_per_m_std"] > 0).all() and (kb["b_um_std"] > 0).all()
    z = 1.959963984540054
    np.testing.assert_allclose(width_near[:, 0], 2 * z * kb["b_um_std"], rtol=1e-9)
    np.testing.assert_allclose(
        width_near[:, -1], 2 * z * np.hypot(kb["b_um_std"], 0.26 * kb["k_um_per_m_std"]), rtol=1e-9
    )
    lower90, upper90 = model.predict_interval(X_near, level=0.9)
    lower99, upper99 = model.predict_interval(X_near, level=0.99)
    assert np.all(upper99 - lower99 > upper90 - lower90)


def test_pointwise_gpr_interval_and_non_gpr_refusal():
    X, Y = _noisy_eq9()
    model = PointwiseAxisModel(algorithm="gpr").fit(X, Y.iloc[:, ::4])
    lower, upper = model.predict_interval(X.iloc[:8], level=0.95)
    mean = model.predict(X.iloc[:8])
    assert mean.shape == (8, 4)
    assert np.all(lower < mean) and np.all(mean < upper)
    with pytest.raises(NotImplementedError):
        PointwiseAxisModel().fit(X, Y).predict_interval(X, level=0.95)
    with pytest.raises(NotImplementedError):
        DecoupledAxisModel().fit(X, Y).predict_interval(X, level=0.95)
    with pytest.raises(NotImplementedError):
        DecoupledAxisModel().fit(X, Y).predict_kb(X, return_std=True)


def test_svr_group_search_picks_the_known_best_point():
    rng = np.random.default_rng(3)
    x = rng.uniform(-2.0, 2.0, (30, 1))
    y = np.sin(2.0 * x).ravel()
    groups = np.repeat(["a", "b", "c"], 10)
    # C = 1e-3 keeps the prediction near the mean; C = 100 follows the curve.
    grid = {"C": [1e-3, 100.0], "epsilon": [0.01]}
    model, chosen = fit_by_group_search("svr", x, y, groups, grid, random_state=0, inner=(12, 5))
    assert chosen == {"C": 100.0, "epsilon": 0.01}

    # Independent leave-one-group-out computation of the mean fold RMSE per grid point.
    def mean_rmse(params):
        scores = []
        for g in "abc":
            test = groups == g
            fitted = make_regressor("svr", params, random_state=0).fit(x[~test], y[~test])
            scores.append(np.sqrt(np.mean((fitted.predict(x[test]) - y[test]) ** 2)))
        return np.mean(scores)

    assert mean_rmse({"C": 100.0, "epsilon": 0.01}) < mean_rmse({"C": 1e-3, "epsilon": 0.01})
    refit = make_regressor("svr", chosen, random_state=0).fit(x, y)
    np.testing.assert_allclose(model.predict(x), refit.predict(x))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_svr_group_search_chooses_what_gridsearchcv_chooses(seed):
    # The reference: scikit-learn's GridSearchCV over the same pipeline, leave one group out.
    from sklearn.model_selection import GridSearchCV, LeaveOneGroupOut

    rng = np.random.default_rng(seed)
    x = rng.normal(size=(40, 3))
    y = x @ np.array([1.0, -0.5, 0.2]) + 0.3 * np.sin(3.0 * x[:, 0]) + rng.normal(0.0, 0.1, 40)
    groups = np.repeat(["r1", "r2", "r3", "r4"], 10)
    # Two identical C values make a tie: the earlier grid point must win, as in GridSearchCV.
    grid = {"C": [10.0, 0.1, 10.0], "epsilon": [0.01, 0.1], "gamma": ["scale", 0.1]}
    model, chosen = fit_by_group_search("svr", x, y, groups, grid, random_state=0, inner=(12, 5))
    search = GridSearchCV(
        make_regressor("svr", random_state=0),
        {f"regress__regressor__{k}": v for k, v in grid.items()},
        scoring="neg_root_mean_squared_error",
        cv=LeaveOneGroupOut(),
    ).fit(x, y, groups=groups)
    assert chosen == {
        k.removeprefix("regress__regressor__"): v for k, v in search.best_params_.items()
    }
    np.testing.assert_array_equal(model.predict(x), search.best_estimator_.predict(x))


def test_svr_group_search_falls_back_to_first_grid_point_with_one_group():
    x = np.linspace(0.0, 1.0, 10)[:, None]
    _, chosen = fit_by_group_search(
        "svr",
        x,
        x.ravel(),
        ["a"] * 10,
        {"C": [100.0, 1.0], "epsilon": [0.2, 0.01]},
        random_state=0,
        inner=(12, 5),
    )
    assert chosen == {"C": 100.0, "epsilon": 0.2}


def test_svr_coefficients_are_empty_but_searched_params_recorded():
    X, Y = _noisy_eq9()
    model = DecoupledAxisModel(algorithm="svr", svr_grid=SMALL_GRID).fit(X, Y)
    assert model.coefficients().empty
    assert list(model.coefficients().columns) == [
        "target",
        "position_mm",
        "term",
        "temperature",
        "value",
    ]
    assert set(model.searched_params_) == {"k", "b"}
    # The reference: scikit-learn's GridSearchCV, leaving one run out, on k (absolute T1,
    # T6, T12) and b (the rises of T2, T7, T11) of each measurement's numpy line.
    from sklearn.model_selection import GridSearchCV, LeaveOneGroupOut

    x_m = (POSITIONS - POSITIONS[0]) / 1000.0
    k, b = np.polyfit(x_m, Y.to_numpy().T, 1)
    absolute = X[["T1", "T6", "T12"]]
    rise = X[["T2", "T7", "T11"]] - X.groupby("run")[["T2", "T7", "T11"]].transform("first")
    for target, inputs, y in (("k", absolute, k), ("b", rise, b)):
        search = GridSearchCV(
            make_regressor("svr", random_state=0),
            {f"regress__regressor__{key}": v for key, v in SMALL_GRID.items()},
            scoring="neg_root_mean_squared_error",
            cv=LeaveOneGroupOut(),
        ).fit(inputs.to_numpy(), y, groups=X["run"].to_numpy())
        best = {
            key.removeprefix("regress__regressor__"): v for key, v in search.best_params_.items()
        }
        assert model.searched_params_[target] == best, target


# --------------------------------------------------------------------------- bad input


def test_bad_input_raises_value_error():
    X = synthetic_temperatures()
    Y = eq9_errors(X)
    with pytest.raises(ValueError, match="unknown algorithm"):
        make_regressor("elasticnet", random_state=0)
    with pytest.raises(ValueError, match="unknown parameter"):
        make_regressor("ridge", {"C": 1.0}, random_state=0)
    with pytest.raises(ValueError, match="rows"):
        DecoupledAxisModel().fit(X, Y.iloc[:-1])
    with pytest.raises(ValueError, match="lacks column"):
        DecoupledAxisModel().fit(X.drop(columns="T6"), Y)
    with pytest.raises(ValueError, match="ascending"):
        PointwiseAxisModel().fit(X, Y[Y.columns[::-1]])
    X_missing = X.copy()
    X_missing.loc[4, "T1"] = np.nan
    with pytest.raises(ValueError, match="missing temperatures"):
        DecoupledAxisModel().fit(X_missing, Y)


@pytest.mark.parametrize(
    "algorithm, grid, splitter",
    [
        ("ridge", {"alpha": [100.0, 0.01, 1.0]}, "logo"),
        ("lasso", {"alpha": [0.3, 0.001, 0.03]}, "logo"),
        ("pls", {"n_components": [1, 3, 2]}, "logo"),
        ("ridge", {"alpha": [100.0, 0.01, 1.0]}, "groupkfold"),
    ],
)
def test_searched_strength_is_what_gridsearchcv_chooses(algorithm, grid, splitter):
    # The reference: scikit-learn's GridSearchCV over the same pipeline and group splitter.
    from sklearn.model_selection import GridSearchCV, GroupKFold, LeaveOneGroupOut

    rng = np.random.default_rng(7)
    x = rng.normal(size=(60, 4))
    x[:, 3] = x[:, 2] + rng.normal(0.0, 0.05, 60)  # nearly collinear, where the strength matters
    y = x @ np.array([1.0, -0.5, 0.2, 0.2]) + rng.normal(0.0, 0.3, 60)
    groups = np.repeat([f"r{i}" for i in range(6)], 10)
    # Up to 12 runs leave one out; with the limit at 4, the 6 runs go into 3 group folds.
    inner, cv = (
        ((12, 3), LeaveOneGroupOut()) if splitter == "logo" else ((4, 3), GroupKFold(n_splits=3))
    )
    model, chosen = fit_by_group_search(algorithm, x, y, groups, grid, random_state=0, inner=inner)
    search = GridSearchCV(
        make_regressor(algorithm, random_state=0),
        {f"regress__regressor__{k}": v for k, v in grid.items()},
        scoring="neg_root_mean_squared_error",
        cv=cv,
    ).fit(x, y, groups=groups)
    assert chosen == {
        k.removeprefix("regress__regressor__"): v for k, v in search.best_params_.items()
    }
    np.testing.assert_allclose(
        model.predict(x), search.best_estimator_.predict(x), rtol=1e-12, atol=1e-12
    )


def test_a_pls_grid_point_past_an_inner_splits_rows_ranks_last_as_in_gridsearchcv():
    # Three runs of three rows: each inner split trains on 6 rows, so 7 components of the 8
    # sensors cannot be fitted there. GridSearchCV scores the failed fit NaN (its
    # error_score) and ranks it last; the search must do the same, not stop.
    from sklearn.exceptions import FitFailedWarning
    from sklearn.model_selection import GridSearchCV, LeaveOneGroupOut

    rng = np.random.default_rng(11)
    x = rng.normal(size=(9, 8))
    y = x @ rng.normal(size=8) + rng.normal(0.0, 0.5, 9)
    groups = np.repeat(["r1", "r2", "r3"], 3)
    grid = {"n_components": [7, 1, 5, 2]}
    model, chosen = fit_by_group_search("pls", x, y, groups, grid, random_state=0, inner=(12, 3))
    with pytest.warns(FitFailedWarning):
        search = GridSearchCV(
            make_regressor("pls", random_state=0),
            {"regress__regressor__n_components": grid["n_components"]},
            scoring="neg_root_mean_squared_error",
            cv=LeaveOneGroupOut(),
        ).fit(x, y, groups=groups)
    assert np.isnan(search.cv_results_["mean_test_score"][0])
    assert chosen == {"n_components": search.best_params_["regress__regressor__n_components"]}
    np.testing.assert_allclose(
        model.predict(x), search.best_estimator_.predict(x), rtol=1e-12, atol=1e-12
    )


def test_a_searched_model_records_its_choice_and_a_fixed_one_does_not():
    X = synthetic_temperatures()
    Y = eq9_errors(X)
    searched = PointwiseAxisModel(algorithm="ridge", search_grid={"alpha": [0.01, 10.0]}).fit(X, Y)
    assert set(searched.searched_params_) == {float(p) for p in Y.columns}
    assert (
        PointwiseAxisModel(algorithm="ridge", params={"alpha": 1.0}).fit(X, Y).searched_params_
        == {}
    )


def test_gpr_beyond_its_sample_limit_is_fitted_on_evenly_spaced_rows():
    rng = np.random.default_rng(0)
    x = rng.normal(size=(40, 1))
    y = np.sin(x).ravel()
    X = pd.DataFrame(
        {
            "run": np.repeat(["a", "b"], 20),
            "measurement": np.tile(np.arange(20), 2),
            "T1": x.ravel(),
        }
    )
    Y = pd.DataFrame({0.0: y})
    model = PointwiseAxisModel(sensors=("T1",), algorithm="gpr", gpr_max_samples=10).fit(X, Y)
    # The fitted GP holds 10 training rows: 0, 4, 9, 13, ..., 39 (evenly spaced, both ends).
    gp = model.estimators_[0].named_steps["regress"].regressor_
    assert gp.X_train_.shape == (10, 1)
    kept = np.unique(np.linspace(0, 39, 10).round().astype(int))
    relative = x.ravel() - np.repeat(x.ravel()[[0, 20]], 20)  # the model's inputs are rises
    scaler = model.estimators_[0].named_steps["standardise"]
    np.testing.assert_allclose(scaler.inverse_transform(gp.X_train_).ravel(), relative[kept])


# --------------------------------------------------------------------------- the lasso


def test_lasso_reaches_its_optimum_on_many_correlated_sensors():
    # 60 temperatures that share three heat sources, 66 rows: the case where coordinate
    # descent stopped at its iteration cap. The lasso's optimality conditions (KKT) in the
    # pipeline's standardised units, checked directly: with r = y - X w, every sensor has
    # |x_j . r| / n <= alpha, with equality and the sign of w_j where w_j != 0.
    rng = np.random.default_rng(3)
    sources = rng.normal(size=(66, 3)).cumsum(axis=0)
    X = sources @ rng.uniform(0.2, 1.0, size=(3, 60)) + 0.05 * rng.normal(size=(66, 60))
    y = sources @ np.array([1.0, -0.5, 0.25]) + 0.1 * rng.normal(size=66)
    alpha = 0.001
    fitted = make_regressor("lasso", {"alpha": alpha}, random_state=0).fit(X, y)
    Xs = (X - X.mean(axis=0)) / X.std(axis=0)
    ys = (y - y.mean()) / y.std()
    w = fitted.named_steps["regress"].regressor_.coef_
    correlation = Xs.T @ (ys - Xs @ w) / len(ys)
    active = w != 0
    assert active.sum() >= 2
    assert np.abs(correlation).max() <= alpha * (1 + 1e-6)
    np.testing.assert_allclose(correlation[active], alpha * np.sign(w[active]), rtol=1e-6)


def test_one_lars_path_predicts_as_a_lasso_fitted_at_each_strength():
    # The inner search scores the whole strength grid from one path: each strength's
    # held-out predictions against scikit-learn's LassoLars fitted at that strength alone.
    from sklearn.linear_model import LassoLars

    from thermaxis.method.search import lasso_path_predictions

    rng = np.random.default_rng(11)
    sources = rng.normal(size=(40, 2)).cumsum(axis=0)
    X = sources @ rng.uniform(0.2, 1.0, size=(2, 25)) + 0.1 * rng.normal(size=(40, 25))
    y = sources @ np.array([1.0, -0.7]) + 0.2 * rng.normal(size=40)
    X_train, y_train, X_test = X[:30], y[:30] - y[:30].mean(), X[30:]
    alphas = [5.0, 0.3, 0.1, 0.03, 0.01, 0.003, 0.001]
    predictions = lasso_path_predictions(X_train, y_train, X_test, alphas)
    for alpha, predicted in zip(alphas, predictions, strict=True):
        alone = LassoLars(alpha=alpha).fit(X_train, y_train).predict(X_test)
        np.testing.assert_allclose(predicted, alone, rtol=1e-9, atol=1e-9)


@pytest.mark.parametrize("shape", [(30, 25), (30, 120)], ids=["tall", "wide"])
def test_one_svd_predicts_as_a_ridge_fitted_at_each_strength(shape):
    # The inner search scores the whole strength grid from one SVD: each strength's
    # held-out predictions against scikit-learn's Ridge fitted at that strength alone,
    # with more rows than inputs and fewer (many lagged inputs, Ridge's kernel solver).
    from sklearn.linear_model import Ridge

    from thermaxis.method.search import ridge_grid_predictions

    rows, columns = shape
    rng = np.random.default_rng(12)
    sources = rng.normal(size=(rows + 10, 2)).cumsum(axis=0)
    X = sources @ rng.uniform(0.2, 1.0, size=(2, columns)) + 0.1 * rng.normal(
        size=(rows + 10, columns)
    )
    y = sources @ np.array([1.0, -0.7]) + 0.2 * rng.normal(size=rows + 10)
    X_train, y_train, X_test = X[:rows], y[:rows], X[rows:]
    alphas = [100.0, 10.0, 1.0, 0.1, 0.01]
    predictions = ridge_grid_predictions(X_train, y_train, X_test, alphas)
    for alpha, predicted in zip(alphas, predictions, strict=True):
        alone = Ridge(alpha=alpha).fit(X_train, y_train).predict(X_test)
        np.testing.assert_allclose(predicted, alone, rtol=1e-9, atol=1e-9)


@pytest.mark.parametrize(
    "params",
    [
        {"C": 10.0, "epsilon": 0.05, "gamma": "scale"},
        {"C": 0.1, "epsilon": 0.01, "gamma": "auto"},
        {"C": 100.0, "epsilon": 0.1, "gamma": 0.1},
        {"C": 1.0, "kernel": "linear"},
        {"C": 3.0, "kernel": "poly", "degree": 2, "coef0": 1.0, "gamma": 0.5},
    ],
)
def test_the_svr_grid_predicts_as_the_svr_estimator_bit_for_bit(params):
    # The inner search fits its SVR grid through libsvm directly: each grid point's
    # held-out predictions against scikit-learn's SVR fitted and predicting on its own.
    from sklearn.svm import SVR

    from thermaxis.method.svr_grid import svr_grid_predictions

    rng = np.random.default_rng(5)
    X = rng.normal(size=(30, 4))
    y = np.sin(X[:, 0]) + 0.5 * X[:, 1] + 0.1 * rng.normal(size=30)
    # A column-major training block: SVR copies it to C order before computing the
    # "scale" gamma from its variance, and so must the grid.
    X_train, y_train, X_test = np.asfortranarray(X[:22]), y[:22], X[22:]
    alone = SVR(**params).fit(X_train, y_train).predict(X_test)
    (predicted,) = svr_grid_predictions(X_train, y_train, X_test, [SVR(**params)])
    np.testing.assert_array_equal(predicted, alone)
    assert alone.std() > 0.05  # a fitted response, not a constant


def test_the_svr_grid_refuses_a_precomputed_kernel():
    from sklearn.svm import SVR

    from thermaxis.method.svr_grid import svr_grid_predictions

    X = np.eye(3)
    with pytest.raises(ValueError, match="named kernel"):
        svr_grid_predictions(X, np.ones(3), X, [SVR(kernel="precomputed")])


def test_the_svr_grid_refuses_a_missing_value_as_the_svr_does():
    from sklearn.svm import SVR

    from thermaxis.method.svr_grid import svr_grid_predictions

    X = np.arange(12.0).reshape(6, 2)
    X[2, 1] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        SVR().fit(X, np.arange(6.0))
    with pytest.raises(ValueError, match="Input X contains NaN"):
        svr_grid_predictions(X, np.arange(6.0), X, [SVR()])


@pytest.mark.parametrize(
    ("shape", "restarts", "target"),
    [
        ((25, 3), 0, "smooth"),
        ((40, 1), 2, "smooth"),
        ((12, 5), 1, "linear"),
        ((60, 2), 0, "linear"),
    ],
)
def test_the_gp_kernel_fits_as_the_composite_kernel_bit_for_bit(shape, restarts, target):
    # One kernel object for scikit-learn's ConstantKernel * RBF + WhiteKernel, with the
    # model's starting point and bounds: the same optimum, weights, predictions and
    # standard deviations, to the last bit. A noise-free line drives the noise to its bound.
    from sklearn.gaussian_process import GaussianProcessRegressor
    from sklearn.gaussian_process.kernels import RBF, ConstantKernel, WhiteKernel

    from thermaxis.method.gp_kernel import ScaledRBFWithNoise

    rng = np.random.default_rng(shape[0])
    X = rng.normal(size=shape)
    y = X @ rng.normal(size=shape[1])
    if target == "smooth":
        y = np.sin(2 * X[:, 0]) + 0.1 * rng.normal(size=shape[0])
    X_test = rng.normal(size=(9, shape[1]))
    composite = ConstantKernel(1.0, (1e-3, 1e5)) * RBF(0.7, (1e-2, 1e4)) + WhiteKernel(
        0.1, (1e-6, 1e1)
    )
    one = ScaledRBFWithNoise(1.0, (1e-3, 1e5), 0.7, (1e-2, 1e4), 0.1, (1e-6, 1e1))
    fits = [
        GaussianProcessRegressor(kernel, n_restarts_optimizer=restarts, random_state=3).fit(X, y)
        for kernel in (composite, one)
    ]
    reference, ours = fits
    np.testing.assert_array_equal(ours.kernel_.theta, reference.kernel_.theta)
    np.testing.assert_array_equal(ours.kernel_.bounds, reference.kernel_.bounds)
    np.testing.assert_array_equal(ours.alpha_, reference.alpha_)
    assert ours.log_marginal_likelihood_value_ == reference.log_marginal_likelihood_value_
    got, want = ours.predict(X_test, return_std=True), reference.predict(X_test, return_std=True)
    np.testing.assert_array_equal(got[0], want[0])
    np.testing.assert_array_equal(got[1], want[1])
    # The fitted hyperparameters under the composite's names, by hand from theta.
    constant, scale, noise = np.exp(reference.kernel_.theta)
    assert (ours.kernel_.constant_value, ours.kernel_.length_scale) == (constant, scale)
    assert ours.kernel_.noise_level == noise
    K = ours.kernel_(X_test[:3])
    d2 = ((X_test[:3, None, :] - X_test[None, :3, :]) ** 2).sum(-1)
    np.testing.assert_allclose(K, constant * np.exp(-d2 / (2 * scale**2)) + noise * np.eye(3))


def test_the_gp_kernel_refuses_a_fixed_hyperparameter():
    from sklearn.gaussian_process import GaussianProcessRegressor

    from thermaxis.method.gp_kernel import ScaledRBFWithNoise

    kernel = ScaledRBFWithNoise(noise_level_bounds="fixed")
    with pytest.raises(ValueError, match="noise_level fixed"):
        GaussianProcessRegressor(kernel).fit(np.arange(6.0).reshape(3, 2), np.arange(3.0))
