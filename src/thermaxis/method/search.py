"""The inner group search: a regressor's hyper-parameters chosen on the training runs alone.

:func:`fit_by_group_search` scores a grid as GridSearchCV would over
:func:`~thermaxis.method.regressors.make_regressor`'s pipeline, with fast paths that give
its numbers for a whole strength grid at once: one SVD for ridge, one LARS path for the
lasso, the SVR's grid on libsvm without the estimator's re-validation
(:mod:`thermaxis.method.svr_grid`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
from sklearn.model_selection import GroupKFold, LeaveOneGroupOut, ParameterGrid

from thermaxis.method.regressors import (
    base_regressor,
    check_params,
    checked_once,
    make_regressor,
    pls_fits,
)
from thermaxis.method.scaling import scaler_moments
from thermaxis.method.svr_grid import svr_grid_predictions

__all__ = [
    "inner_group_splitter",
    "fit_by_group_search",
    "standardised_split",
    "ridge_grid_predictions",
    "lasso_path_predictions",
]


def inner_group_splitter(groups, max_loco_groups: int, group_folds: int):
    """The inner search's split of the training runs: leave one out, or k group folds.

    Leave-one-condition-out costs one fit per run and candidate: above
    ``max_loco_groups`` runs (config ``models.inner_search.max_loco_runs``) the runs are
    dealt into ``group_folds`` folds instead (scikit-learn's GroupKFold, deterministic).
    """
    n_groups = np.unique(groups).size
    if n_groups <= max_loco_groups:
        return LeaveOneGroupOut()
    return GroupKFold(n_splits=min(group_folds, n_groups))


def fit_by_group_search(
    algorithm: str,
    X,
    y,
    groups,
    grid: Mapping,
    random_state: int,
    inner: tuple[int, int],
    max_group_folds: int | None = None,
):
    """Fit a regressor whose hyper-parameters are chosen by a group search on the runs.

    Only the data passed in is used, so calling this on the training conditions of an
    outer leave-one-condition-out fold keeps the held-out condition unseen.

    Parameters
    ----------
    algorithm : {"svr", "ridge", "lasso", "pls"}
    X : array-like, shape (n, f)
    y : array-like, shape (n,)
    groups : array-like, shape (n,)
        Group label per row (the run id): each group is held out once in the inner search
        (or each of k group folds, see :func:`inner_group_splitter`).
    grid : mapping of str to list
        Candidate values per parameter (svr ``C``, ``epsilon``, ``gamma``, ``kernel``:
        C and epsilon act on the STANDARDISED target, so epsilon 0.05 means 5 % of the
        target's spread; ridge and lasso ``alpha``; pls ``n_components``). The
        workflow's grids are config ``models.svr_grid`` and ``models.search_grids``.
    random_state : int
        Passed to :func:`make_regressor` for symmetry (these algorithms are deterministic).
    inner : (int, int)
        ``(max_loco_groups, group_folds)`` of :func:`inner_group_splitter`.
    max_group_folds : int, optional
        With group folds (above ``max_loco_groups`` groups), score the grid on the first
        this many of them only (config ``models.inner_search.svr_folds``); leave-one-out
        always uses every group.

    Returns
    -------
    estimator : Pipeline
        Refitted on all rows with the chosen parameters.
    chosen : dict
        The chosen parameters, by their plain names.  With fewer than two groups there
        is nothing to hold out, so the first grid point (each parameter's first value) is
        used without search.  Scoring is RMSE; ties go to the earlier grid point.
    """
    grid = dict(grid)
    check_params(algorithm, grid)
    if not grid or any(len(values) == 0 for values in grid.values()):
        raise ValueError(
            f"{algorithm} search grid must give at least one value for each listed parameter"
        )
    X = np.asarray(X, dtype=float)
    y = np.asarray(y, dtype=float)
    groups = np.asarray(groups)
    candidates = list(ParameterGrid(grid))
    n_features = X.shape[1]
    if np.unique(groups).size < 2:
        chosen = dict(candidates[0])
        return make_regressor(
            algorithm, chosen, random_state=random_state, n_features=n_features
        ).fit(X, y), chosen
    # GridSearchCV over make_regressor's pipeline, without its per-candidate cloning,
    # re-validation and scorer calls: each hold-out is standardised once, the regressor
    # fitted per candidate on the same arrays the pipeline would give it, so the scores,
    # the choice and the refitted model are the ones GridSearchCV gives (test_models checks).
    splits = _search_splits(X, y, groups, inner, max_group_folds)
    scores = np.empty((len(candidates), len(splits)))
    regressors = [base_regressor(algorithm, p, random_state, n_features) for p in candidates]
    # Every grid point's parameters and the inputs checked once, for the inner fits and
    # the refit alike.
    with checked_once(regressors, X, y):
        _search_scores(algorithm, X, y, splits, regressors, scores)
        means = np.average(scores, axis=1)
        # The first best candidate, NaN scores last, as GridSearchCV ranks them.
        chosen = dict(candidates[int(np.argmax(np.where(np.isnan(means), -np.inf, means)))])
        refit = make_regressor(algorithm, chosen, random_state=random_state, n_features=n_features)
        return refit.fit(X, y), chosen


def _search_splits(X, y, groups, inner: tuple[int, int], max_group_folds: int | None) -> list:
    """The (train, test) splits a search scores its grid on (:func:`fit_by_group_search`)."""
    splitter = inner_group_splitter(groups, *inner)
    splits = list(splitter.split(X, y, groups))
    if max_group_folds is None or isinstance(splitter, LeaveOneGroupOut):
        return splits
    return splits[:max_group_folds]


def standardised_split(X, y, train, test) -> tuple:
    """A hold-out as the pipeline sees it: ``StandardScaler`` fitted on the training rows of
    X and of y (one output (n,) or several (n, m), each scaled on its own).

    Returns X's training and held-out rows and y's training rows standardised, and y's
    mean and scale to undo it (scalars for one output).
    """
    y_train = y[train]
    x_mean, x_scale = scaler_moments(X[train])
    y_mean, y_scale = scaler_moments(y_train.reshape(len(y_train), -1))
    if y_train.ndim == 1:
        y_mean, y_scale = y_mean[0], y_scale[0]
    # StandardScaler.transform's own arithmetic (minus mean_, over scale_).
    return (
        (X[train] - x_mean) / x_scale,
        (X[test] - x_mean) / x_scale,
        (y_train - y_mean) / y_scale,
        y_mean,
        y_scale,
    )


def _search_scores(algorithm, X, y, splits, regressors, scores):
    """Fill ``scores[candidate, split]`` with minus the RMSE of each hold-out, as
    GridSearchCV's ``neg_root_mean_squared_error`` scores it; ``regressors``: one
    :func:`base_regressor` per grid point, fitted afresh on each hold-out."""
    for split, (train, test) in enumerate(splits):
        X_train, X_test, y_train, y_mean, y_scale = standardised_split(X, y, train, test)
        if algorithm == "lasso":
            standardised = lasso_path_predictions(
                X_train, y_train, X_test, [r.alpha for r in regressors]
            )
        elif algorithm == "ridge":
            standardised = ridge_grid_predictions(
                X_train, y_train, X_test, [r.alpha for r in regressors]
            )
        elif algorithm == "svr":
            standardised = svr_grid_predictions(X_train, y_train, X_test, regressors)
        else:
            standardised = [
                r.fit(X_train, y_train).predict(X_test)
                if algorithm != "pls" or pls_fits(r.n_components, len(train), X.shape[1])
                else np.full(len(test), np.nan)
                for r in regressors
            ]
        for c, values in enumerate(standardised):
            # StandardScaler.inverse_transform's own arithmetic (times scale_, plus
            # mean_), without its input checks, which cost more than the prediction.
            predicted = np.asarray(values, dtype=float).reshape(-1)
            predicted = predicted * y_scale + y_mean
            scores[c, split] = -np.sqrt(np.mean((y[test] - predicted) ** 2))


def ridge_grid_predictions(X_train, y_train, X_test, alphas: Sequence[float]) -> list:
    """Ridge's predictions of ``X_test`` at every strength in ``alphas``, from one SVD.

    ``y_train`` is one output (n,) or several (n, m), each fitted on its own.

    Ridge with its intercept is w = V diag(s / (s^2 + alpha)) U'(y - mean y) on the
    centred inputs X - mean X = U diag(s) V', so a search over the strength grid costs one
    decomposition per inner split, not one solve per strength (a strength grid on many
    lagged inputs was most of a compensation job). Ridge's own fit to rounding
    (test_models); a direction the training rows do not span (s = 0) gets no weight.
    """
    x_mean, y_mean = X_train.mean(axis=0), y_train.mean(axis=0)
    U, s, Vt = np.linalg.svd(X_train - x_mean, full_matrices=False)
    projected = U.T @ (y_train - y_mean)
    test = (X_test - x_mean) @ Vt.T
    predictions = []
    for alpha in alphas:
        denominator = s**2 + alpha
        shrink = np.divide(s, denominator, out=np.zeros_like(s), where=denominator > 0)
        # Transposed twice so that a 2-D y_train (one column per output) scales each row.
        predictions.append(test @ (shrink * projected.T).T + y_mean)
    return predictions


def lasso_path_predictions(X_train, y_train, X_test, alphas: Sequence[float]) -> list:
    """The lasso's predictions of ``X_test`` at every strength in ``alphas``, from one LARS path.

    The lasso's coefficients are piecewise linear in alpha between the path's knots, so one
    path down to the smallest alpha (LassoLars, with its path) gives every larger alpha by
    the interpolation LassoLars makes at its own: a search over the strength grid costs
    one fit, not one per strength.
    """
    smallest = base_regressor("lasso", {"alpha": min(alphas)}, 0, None).fit(X_train, y_train)
    knots, path = np.asarray(smallest.alphas_), np.asarray(smallest.coef_path_)
    x_offset, y_offset = X_train.mean(axis=0), y_train.mean()
    predictions = []
    for alpha in alphas:
        # The knots fall: i is the last knot at or above alpha.
        i = int(np.searchsorted(-knots, -alpha, side="right")) - 1
        if i < 0:
            coef = np.zeros(X_train.shape[1])
        elif knots[i] == alpha or i == knots.size - 1:
            coef = path[:, i]
        else:
            step = (knots[i] - alpha) / (knots[i] - knots[i + 1])
            coef = path[:, i] + step * (path[:, i + 1] - path[:, i])
        predictions.append((X_test - x_offset) @ coef + y_offset)
    return predictions
