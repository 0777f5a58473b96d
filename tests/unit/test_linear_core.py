"""The numpy linear core against scikit-learn's own pipelines, one pipeline per output.

The reference is built here exactly as make_regressor builds it (StandardScaler, then
TransformedTargetRegressor(regressor, transformer=StandardScaler())), not imported.
Coefficients are the pipeline's composed affine map in original units; every comparison
is relative to the largest magnitude of the compared quantity per output, within 1e-9.
"""

from __future__ import annotations

import itertools
import warnings

import numpy as np
import pytest
from sklearn.compose import TransformedTargetRegressor
from sklearn.cross_decomposition import PLSRegression
from sklearn.linear_model import LinearRegression, Ridge
from sklearn.pipeline import Pipeline
from sklearn.preprocessing import StandardScaler

from thermaxis.method import linear
from thermaxis.method.linear import loco_fit, standardised_fit, subset_fit
from thermaxis.method.scaling import scaler_moments

RTOL = 1e-9
ALPHA = 0.7
COMPONENTS = 2
ALGORITHMS = ("mlr", "ridge", "pls")
LARGEST = [0.0]  # largest relative difference seen, for the record


def pipeline(algorithm, n_inputs, n_components=COMPONENTS, alpha=ALPHA):
    if algorithm == "mlr":
        regressor = LinearRegression()
    elif algorithm == "ridge":
        regressor = Ridge(alpha=alpha)
    else:
        regressor = PLSRegression(n_components=min(n_components, n_inputs), scale=False)
    return Pipeline(
        [
            ("standardise", StandardScaler()),
            (
                "regress",
                TransformedTargetRegressor(regressor=regressor, transformer=StandardScaler()),
            ),
        ]
    )


def reference(algorithm, X, Y, X_new, n_components=COMPONENTS, alpha=ALPHA):
    """Intercept (m,), slopes (s, m) and predictions of X_new (rows, m): one pipeline per column."""
    s = X.shape[1]
    intercept, slopes, predictions = [], [], []
    for y in Y.T:
        fitted = pipeline(algorithm, s, n_components, alpha).fit(X, y)
        scaler = fitted.named_steps["standardise"]
        target = fitted.named_steps["regress"].transformer_
        # The regressor is affine in standardised units: probe it there, then compose.
        probe = np.ravel(
            fitted.named_steps["regress"].regressor_.predict(np.vstack([np.zeros(s), np.eye(s)]))
        )
        slope = (probe[1:] - probe[0]) * target.scale_[0] / scaler.scale_
        intercept.append(target.mean_[0] + target.scale_[0] * probe[0] - scaler.mean_ @ slope)
        slopes.append(slope)
        predictions.append(fitted.predict(X_new))
    return np.array(intercept), np.array(slopes).T, np.array(predictions).T


def assert_close(actual, expected):
    """Within RTOL of the largest |expected| of each output (the last axis)."""
    actual, expected = np.asarray(actual), np.asarray(expected)
    assert actual.shape == expected.shape
    flat_a = actual.reshape(-1, actual.shape[-1])
    flat_e = expected.reshape(-1, expected.shape[-1])
    scale = np.abs(flat_e).max(axis=0)
    scale = np.where(scale > 0, scale, 1.0)
    worst = float((np.abs(flat_a - flat_e).max(axis=0) / scale).max())
    LARGEST[0] = max(LARGEST[0], worst)
    assert worst <= RTOL, f"relative difference {worst:.3g} > {RTOL}"


def check_against_reference(algorithm, X, Y, X_new, intercept, slopes, predictions, **options):
    ref_intercept, ref_slopes, ref_predictions = reference(algorithm, X, Y, X_new, **options)
    assert_close(intercept, ref_intercept)
    assert_close(slopes, ref_slopes)
    assert_close(predictions, ref_predictions)


def thermal_data(rng, n=60, p=5, m=6, correlation=0.0):
    """Temperatures near 20 degrees C (optionally with equicorrelated sensors) and outputs."""
    common = rng.normal(size=(n, 1))
    X = 20.0 + 2.0 * (
        np.sqrt(correlation) * common + np.sqrt(1.0 - correlation) * rng.normal(size=(n, p))
    )
    Y = 3.0 + (X - 20.0) @ rng.normal(size=(p, m)) + 0.3 * rng.normal(size=(n, m))
    return X, Y


# --------------------------------------------------------------------------- one fit, many outputs


@pytest.mark.parametrize("algorithm", ALGORITHMS)
@pytest.mark.parametrize("correlation", [0.0, 0.999])
def test_standardised_fit_equals_one_pipeline_per_output(algorithm, correlation):
    X, Y = thermal_data(np.random.default_rng(1), n=80, p=5, m=14, correlation=correlation)
    fit = standardised_fit(X, Y, algorithm, alpha=ALPHA, n_components=COMPONENTS)
    assert (
        fit.intercept.shape == (14,)
        and fit.slopes.shape == (5, 14)
        and fit.predictions.shape == (80, 14)
    )
    assert not fit.refitted
    check_against_reference(algorithm, X, Y, X, fit.intercept, fit.slopes, fit.predictions)


def test_scaler_moments_are_standard_scalers_bit_for_bit():
    # The inner searches standardise every hold-out with these instead of fitting a
    # StandardScaler: the same bits, or the searches' choices could move.
    rng = np.random.default_rng(3)
    columns = [
        rng.normal(0.0, 1.0, 37),
        1e6 + rng.normal(0.0, 1e-3, 37),  # a large level, a small spread
        np.full(37, 21.3),  # a sensor that never moved: scale 1
        np.r_[np.full(36, 7.0), 7.0 + 1e-15],  # constant to rounding: scale 1
        np.linspace(-3.0, 5.0, 37) ** 3,
        np.zeros(37),
    ]
    for W in (np.column_stack(columns), np.column_stack(columns)[:5], rng.normal(size=(2, 1))):
        scaler = StandardScaler().fit(W)
        mean, scale = scaler_moments(W)
        assert mean.tobytes() == scaler.mean_.tobytes()
        assert scale.tobytes() == scaler.scale_.tobytes()
    assert scaler_moments(np.column_stack(columns))[1][2:4].tolist() == [1.0, 1.0]


@pytest.mark.filterwarnings("ignore:y residual is constant")
@pytest.mark.parametrize("algorithm", ALGORITHMS)
def test_constant_sensor_and_constant_output_behave_as_standard_scaler(algorithm):
    X, Y = thermal_data(np.random.default_rng(2), n=40, p=4, m=3)
    X[:, 2] = 21.3  # a sensor that never moved: StandardScaler keeps scale 1
    Y[:, 1] = 4.2  # an output that never moved
    fit = standardised_fit(X, Y, algorithm, alpha=ALPHA)
    assert not fit.refitted
    assert np.all(fit.slopes[2] == 0.0) and np.all(fit.slopes[:, 1] == 0.0)
    assert fit.intercept[1] == pytest.approx(4.2, rel=1e-15)
    check_against_reference(algorithm, X, Y, X, fit.intercept, fit.slopes, fit.predictions)


def test_pls_components_are_capped_at_the_subset_size():
    X, Y = thermal_data(np.random.default_rng(3), n=30, p=3, m=2)
    fit = standardised_fit(X, Y, "pls", n_components=5)
    check_against_reference(
        "pls", X, Y, X, fit.intercept, fit.slopes, fit.predictions, n_components=3
    )
    # With all components PLS is least squares.
    mlr = standardised_fit(X, Y, "mlr")
    np.testing.assert_allclose(fit.slopes, mlr.slopes, rtol=1e-9)


# -------------------------------------------------------------- many sensitive-point subsets


@pytest.mark.parametrize("algorithm", ALGORITHMS)
@pytest.mark.parametrize("correlation", [0.0, 0.999])
def test_every_subset_equals_its_own_pipelines(algorithm, correlation):
    rng = np.random.default_rng(4)
    X, Y = thermal_data(rng, n=50, p=7, m=4, correlation=correlation)
    X_new = 20.0 + 2.0 * rng.normal(size=(9, 7))
    subsets = list(itertools.combinations(range(7), 3))
    fit = subset_fit(X, Y, subsets, algorithm, alpha=ALPHA, X_new=X_new)
    assert fit.slopes.shape == (35, 3, 4) and fit.predictions.shape == (9, 35, 4)
    assert not fit.refitted.any()
    for q, subset in enumerate(subsets):
        cols = list(subset)
        check_against_reference(
            algorithm,
            X[:, cols],
            Y,
            X_new[:, cols],
            fit.intercept[q],
            fit.slopes[q],
            fit.predictions[:, q],
        )


def test_subsets_must_share_one_size():
    X, Y = thermal_data(np.random.default_rng(5), n=20, p=4, m=1)
    with pytest.raises(ValueError, match="same size"):
        subset_fit(X, Y, [(0, 1), (0, 1, 2)], "mlr")
    with pytest.raises(ValueError, match="unknown linear algorithm"):
        subset_fit(X, Y, [(0, 1)], "svr")


# ------------------------------------------------------------------- leave one condition out


def conditions(rng, sizes, p, m):
    """Runs of unequal length, each at its own temperature level (the conditions)."""
    groups = np.repeat([f"E{i + 1}" for i in range(len(sizes))], sizes)
    X = (
        20.0
        + rng.normal(size=(len(groups), p))
        + np.repeat(3.0 * rng.normal(size=(len(sizes), p)), sizes, axis=0)
    )
    X[:, 1] = 0.999 * X[:, 0] + 0.02 + 0.05 * rng.normal(size=len(groups))  # near-collinear pair
    Y = (X - 20.0) @ rng.normal(size=(p, m)) + 0.5 * rng.normal(size=(len(groups), m))
    return groups, X, Y


@pytest.mark.parametrize("algorithm", ALGORITHMS)
def test_loco_equals_a_pipeline_per_fold_subset_and_output(algorithm):
    rng = np.random.default_rng(6)
    groups, X, Y = conditions(rng, [17, 40, 9, 26], p=6, m=5)
    X[groups != "E3", 4] = 22.5  # sensor 4 moves only in E3: constant in fold E3's training rows
    subsets = list(itertools.combinations(range(6), 3))
    labels, fit = loco_fit(X, Y, groups, subsets, algorithm, alpha=ALPHA)
    assert list(labels) == ["E1", "E2", "E3", "E4"]
    assert fit.slopes.shape == (4, 20, 3, 5) and fit.predictions.shape == (92, 20, 5)
    assert not fit.refitted.any()
    for f, label in enumerate(labels):
        train, held = groups != label, groups == label
        for q, subset in enumerate(subsets):
            cols = list(subset)
            check_against_reference(
                algorithm,
                X[train][:, cols],
                Y[train],
                X[held][:, cols],
                fit.intercept[f, q],
                fit.slopes[f, q],
                fit.predictions[held, q],
            )


def test_loco_downdates_the_full_statistics_instead_of_refitting(monkeypatch):
    rng = np.random.default_rng(7)
    groups, X, Y = conditions(rng, [30, 12, 21], p=4, m=3)
    summed = []
    moments = linear._moments
    monkeypatch.setattr(linear, "_moments", lambda W: summed.append(len(W)) or moments(W))
    labels, fit = loco_fit(X, Y, groups, None, "mlr")
    # The full data once, each held-out condition once; no fold summed from its rows.
    assert sorted(summed) == sorted([len(groups), 30, 12, 21])
    for f, label in enumerate(labels):
        train, held = groups != label, groups == label
        check_against_reference(
            "mlr",
            X[train],
            Y[train],
            X[held],
            fit.intercept[f, 0],
            fit.slopes[f, 0],
            fit.predictions[held, 0],
        )


def test_loco_sums_a_fold_from_its_rows_where_the_downdate_would_cancel(monkeypatch):
    rng = np.random.default_rng(8)
    groups, X, Y = conditions(rng, [25, 25, 25], p=3, m=2)
    X[groups == "E2", 2] += 1e4  # sensor 2's variance is almost all condition E2's
    summed = []
    moments = linear._moments
    monkeypatch.setattr(linear, "_moments", lambda W: summed.append(len(W)) or moments(W))
    labels, fit = loco_fit(X, Y, groups, None, "ridge", alpha=ALPHA)
    # Fold E2's training rows (E1 and E3) are summed again; the other folds keep E2's spread.
    assert sorted(summed) == [25, 25, 25, 50, 75]
    for f, label in enumerate(labels):
        train, held = groups != label, groups == label
        check_against_reference(
            "ridge",
            X[train],
            Y[train],
            X[held],
            fit.intercept[f, 0],
            fit.slopes[f, 0],
            fit.predictions[held, 0],
        )


# --------------------------------------------------------------------------- singular systems


def duplicated_sensor():
    groups, X, Y = conditions(np.random.default_rng(9), [20, 14, 18], p=5, m=3)
    X[:, 3] = X[:, 2]  # two channels on one spot
    subsets = list(itertools.combinations(range(5), 3))
    both = np.array([2 in subset and 3 in subset for subset in subsets])
    return groups, X, Y, subsets, both


@pytest.mark.parametrize(
    ("algorithm", "refit"),
    [("mlr", True), ("ridge", False), ("pls", False)],  # alpha > 0 and 2 of 3 components: regular
)
def test_duplicated_sensor_is_refitted_where_singular_and_matches(algorithm, refit):
    groups, X, Y, subsets, both = duplicated_sensor()
    labels, fit = loco_fit(X, Y, groups, subsets, algorithm, alpha=ALPHA, n_components=COMPONENTS)
    assert np.array_equal(fit.refitted, np.broadcast_to(both & refit, fit.refitted.shape))
    if algorithm == "mlr":
        # lstsq's truncated minimum-norm solution shares the slope between the duplicates.
        q = subsets.index((1, 2, 3))
        np.testing.assert_allclose(fit.slopes[:, q, 1], fit.slopes[:, q, 2], rtol=1e-9)
    for f, label in enumerate(labels):
        train, held = groups != label, groups == label
        for q in np.flatnonzero(both):
            cols = list(subsets[q])
            check_against_reference(
                algorithm,
                X[train][:, cols],
                Y[train],
                X[held][:, cols],
                fit.intercept[f, q],
                fit.slopes[f, q],
                fit.predictions[held, q],
            )


@pytest.mark.filterwarnings("ignore:An ill-conditioned matrix")
@pytest.mark.parametrize(
    ("algorithm", "options"), [("ridge", {"alpha": 0.0}), ("pls", {"n_components": 3})]
)
def test_singular_ridge_without_penalty_and_pls_with_all_components_are_refitted(
    algorithm, options
):
    # scikit-learn's answer here is rounding noise (slopes ~1e16 for pls); the core hands
    # those subsets to scikit-learn rather than solve them from the Gram matrix.
    groups, X, Y, subsets, both = duplicated_sensor()
    labels, fit = loco_fit(X, Y, groups, subsets, algorithm, **options)
    assert np.array_equal(fit.refitted, np.broadcast_to(both, fit.refitted.shape))
    f, q = 0, int(np.flatnonzero(both)[0])
    train = groups != labels[f]
    cols = list(subsets[q])
    _, slopes, _ = reference(algorithm, X[train][:, cols], Y[train], X[~train][:, cols], **options)
    np.testing.assert_array_equal(fit.slopes[f, q], slopes)


def test_ill_conditioned_system_is_refitted_not_solved_from_the_gram_matrix():
    X, Y = thermal_data(np.random.default_rng(10), n=60, p=3, m=2, correlation=0.9999999)
    fit = standardised_fit(X, Y, "mlr")
    assert fit.refitted
    check_against_reference("mlr", X, Y, X, fit.intercept, fit.slopes, fit.predictions)


def test_a_repeated_fallback_fit_gives_the_same_numbers_and_raises_its_warnings_again():
    # The nested recommendation repeats fits; a fallback fit seen before is looked up. Its
    # numbers and its warnings (scipy's ill-conditioned matrix, from the unpenalised
    # ridge on a duplicated sensor) are those of fitting it again, both times.
    groups, X, Y, subsets, both = duplicated_sensor()
    calls = []
    for _ in range(2):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            calls.append((loco_fit(X, Y, groups, subsets, "ridge", alpha=0.0)[1], caught))
    (first, first_warnings), (second, second_warnings) = calls
    assert first.refitted.any()
    for name in ("intercept", "slopes", "predictions"):
        np.testing.assert_array_equal(getattr(first, name), getattr(second, name))
    raised = [(w.category, str(w.message)) for w in first_warnings]
    assert any("ill-conditioned" in message for _, message in raised)
    assert [(w.category, str(w.message)) for w in second_warnings] == raised
