"""The chronological protocol: blocks, the ridge path against scikit-learn, an honest choice."""

import numpy as np
import pytest
from sklearn.linear_model import Ridge
from sklearn.pipeline import make_pipeline
from sklearn.preprocessing import StandardScaler

from thermaxis.benchmark.chronological import (
    _ridge_path_mae,
    block,
    choose,
    evaluate_channel,
    input_sets,
)


def test_blocks_are_floors_of_the_fractions():
    assert block(11115, [0.0, 0.6]) == slice(0, 6669)
    assert block(11115, [0.6, 0.8]) == slice(6669, 8892)
    with pytest.raises(ValueError, match="empty or outside"):
        block(10, [0.5, 0.5])


def test_ridge_path_equals_scikit_learn_at_every_alpha():
    rng = np.random.default_rng(3)
    X = rng.normal(size=(200, 6))
    X[:, 5] = 2.0  # a constant column, left unscaled as StandardScaler leaves it
    y = X[:, :3] @ [1.0, -2.0, 0.5] + rng.normal(0, 0.3, 200)
    fit, score = np.arange(150), np.arange(150, 200)
    alphas = np.array([100.0, 1.0, 0.01])
    path = _ridge_path_mae(X, y, fit, score, alphas)
    for alpha, mae in zip(alphas, path, strict=True):
        model = make_pipeline(StandardScaler(), Ridge(alpha=alpha)).fit(X[fit], y[fit])
        assert mae == pytest.approx(np.mean(np.abs(model.predict(X[score]) - y[score])), rel=1e-9)


def lagged_record(tau_min=60.0, n=3000, seed=0):
    """A drift that follows a 60 min lag of a wandering temperature; the test block is never
    looked at."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * 60.0
    u = 20 + np.cumsum(rng.normal(0, 0.05, n))
    a = np.exp(-60.0 / (60.0 * tau_min))
    y = np.empty(n)
    y[0] = u[0]
    for k in range(1, n):  # the same first-order lag, by a plain zero-order-hold recursion
        y[k] = a * y[k - 1] + (1 - a) * u[k]
    return t, {"T1": u}, 3.0 * (y - y[0]) + rng.normal(0, 0.01, n)


def test_the_time_constant_that_made_the_data_is_chosen():
    t, temperatures, y = lagged_record()
    sets = input_sets(t, temperatures, {}, ["temperatures", "signals"], [[], [15], [60], [240]])
    assert [s.lags_min for s in sets[:1]] == [
        ()
    ]  # simplest first; signals fall back to temperatures
    inputs, alpha, _ = choose(sets, y, slice(0, 1800), [0.01, 1.0, 100.0], 5)
    assert inputs.lags_min == (60.0,)
    result = evaluate_channel(sets, y, slice(0, 1800), slice(1800, 2400), [0.01, 1.0, 100.0], 5)
    assert result["mae_um"] < 0.05


def test_the_test_block_reaches_no_choice():
    t, temperatures, y = lagged_record()
    sets = input_sets(t, temperatures, {}, ["temperatures"], [[], [15], [60]])
    poisoned = y.copy()
    poisoned[1800:] = 1e3  # nothing after the training part may change the choice
    assert (
        choose(sets, y, slice(0, 1800), [1.0], 5)[0].label
        == choose(sets, poisoned, slice(0, 1800), [1.0], 5)[0].label
    )


def test_a_rate_that_made_the_data_is_chosen_and_named():
    rng = np.random.default_rng(1)
    t = np.arange(3000) * 15.0
    u = 20 + np.cumsum(rng.normal(0, 0.05, t.size))
    # The drift follows (u(t) - u(t - 2 min)) / 2 min, in C per minute, and not u itself;
    # before the record's first 2 min the rate is from the start's value, as offline.
    previous = np.interp(t - 120.0, t, u, left=u[0])
    y = 40.0 * (u - previous) / 2.0 + rng.normal(0, 0.01, t.size)
    sets = input_sets(t, {"T1": u}, {}, ["temperatures"], [[]], [[], [2], [10]])
    assert [s.rates_min for s in sets] == [(), (2.0,), (10.0,)]
    assert sets[1].names == ("T1", "T1@rate2min")
    inputs, _, _ = choose(sets, y, slice(0, 1800), [0.01, 1.0], 5)
    assert inputs.rates_min == (2.0,)
    assert inputs.label == "temperatures; lags (min): none; rates (min): 2"
