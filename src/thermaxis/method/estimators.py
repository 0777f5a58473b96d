"""Thermal-error models of the linear axis: the paper's Eq. 8 and Eq. 9 as estimators.

Two approaches, both scikit-learn estimators taking the same data:

* :class:`DecoupledAxisModel` (the paper's step-by-step model, Eq. 9): every training
  measurement's unzeroed error curve is decoupled into slope k and intercept b
  (:func:`thermaxis.method.decouple.decouple_measurement`); k is regressed on ABSOLUTE
  temperatures of its sensitive points and b on temperatures RELATIVE to the run's first
  measurement.  A prediction recomposes the whole error curve.
* :class:`PointwiseAxisModel` (the point-by-point baseline, Eq. 8): one regression per
  target position on relative temperatures.

Data conventions
----------------
``X`` is a DataFrame with one row per measurement: ``run`` (str), ``measurement`` (int,
1-based time order within the run) and one float column per sensor id, absolute degrees C.
``Y`` has the same rows (matched by position, not by index); its columns are the target
positions in mm, ascending, values the unzeroed errors in um (NaN where a reading is missing).
Relative temperatures are referenced to each run's lowest ``measurement`` present in X,
so an X passed to ``predict`` must hold the run's first measurement.

Each regression is a :func:`~thermaxis.method.regressors.make_regressor` pipeline, its
hyper-parameters searched on the training runs (:mod:`thermaxis.method.search`); the
estimators' ``coefficients()`` tables give the affine fits in the paper's units.
"""

from __future__ import annotations

import json
from collections.abc import Sequence

import numpy as np
import pandas as pd
from sklearn.base import BaseEstimator, RegressorMixin
from sklearn.model_selection import LeaveOneGroupOut

from thermaxis.config import schema_default
from thermaxis.method.decouple import compose_curve, stroke_powers
from thermaxis.method.features import ID_COLUMNS as _ID_COLUMNS
from thermaxis.method.features import KB_COLUMNS as _KB_COLUMNS
from thermaxis.method.features import decouple_rows, relative_temperatures
from thermaxis.method.regressors import (
    check_algorithm,
    check_params,
    checked_once,
    linear_terms,
    make_regressor,
    predict_with_std,
)
from thermaxis.method.search import fit_by_group_search, inner_group_splitter
from thermaxis.vocabulary import SEARCHABLE

__all__ = [
    "COEFFICIENT_COLUMNS",
    "DecoupledAxisModel",
    "PointwiseAxisModel",
]


COEFFICIENT_COLUMNS = ("target", "position_mm", "term", "temperature", "value")

# The estimators' keyword defaults, read from the config schema once at import:
# scikit-learn's get_params/clone need plain keyword parameters, and the values must be
# the schema's, not a second copy. The sensors are the paper's (Tables 3 and 6), the
# defaults of the sweep's method "fixed".
_INNER = schema_default("models", "inner_search")
_PAPER_SENSORS = schema_default("sweep", "fixed")
_DEFAULTS = {
    "k_sensors": tuple(_PAPER_SENSORS["k"]),
    "b_sensors": tuple(_PAPER_SENSORS["b"]),
    "sensors": tuple(_PAPER_SENSORS["pointwise"]),
    "algorithm": schema_default("compensation", "algorithm"),
    "degree": schema_default("decoupling", "degree"),
    "random_state": schema_default("models", "random_state"),
    "signals": tuple(schema_default("models", "signals")),
    "inner_search": (_INNER["max_loco_runs"], _INNER["group_folds"]),
    "gpr_max_samples": schema_default("models", "gpr_max_samples"),
    "svr_max_samples": schema_default("models", "svr_max_samples"),
    "svr_search_folds": _INNER["svr_folds"],
    "svr_max_loco_runs": _INNER["svr_max_loco_runs"],
}


# --------------------------------------------------------------------------- data checks


def _check_X(X, sensors: Sequence[str]) -> None:
    if not isinstance(X, pd.DataFrame):
        raise ValueError(f"X must be a pandas DataFrame, got {type(X).__name__}")
    missing = [c for c in (*_ID_COLUMNS, *sensors) if c not in X.columns]
    if missing:
        raise ValueError(
            f"X lacks column(s) {missing}; expected run, measurement and sensors {list(sensors)}"
        )
    if X[list(sensors)].isna().to_numpy().any():
        raise ValueError(
            f"X has missing temperatures in sensor column(s) {list(sensors)}; fill or drop those rows"
        )
    if X.duplicated(list(_ID_COLUMNS)).any():
        raise ValueError(
            "X has duplicate (run, measurement) rows; expected one row per measurement"
        )


def _positions_of(X: pd.DataFrame, Y, min_positions: int = 2) -> np.ndarray:
    if not isinstance(Y, pd.DataFrame):
        raise ValueError(f"Y must be a pandas DataFrame, got {type(Y).__name__}")
    if len(Y) != len(X):
        raise ValueError(
            f"Y has {len(Y)} rows but X has {len(X)}; expected one row of errors per measurement"
        )
    try:
        positions = np.asarray(Y.columns, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError("Y's columns must be target positions in mm (numbers)") from exc
    if positions.size < min_positions or np.any(np.diff(positions) <= 0):
        raise ValueError(
            f"Y's columns must be at least {min_positions} target position(s) in strictly ascending order"
        )
    return positions


def _features(
    X: pd.DataFrame, sensors: Sequence[str], temperature: str, signals: Sequence[str] = ()
) -> np.ndarray:
    """Temperatures of the given kind, then operating signals as logged (a speed has no 'rise')."""
    if temperature == "absolute":
        values = X[list(sensors)].to_numpy(dtype=float)
    else:
        values = relative_temperatures(X, sensors).to_numpy(dtype=float)
    if signals:
        values = np.hstack([values, X[list(signals)].to_numpy(dtype=float)])
    return values


def _evenly_spaced(n: int, at_most: int) -> np.ndarray:
    """Indices of at most ``at_most`` of ``n`` rows, spread evenly (the first and last kept)."""
    return np.unique(np.linspace(0, n - 1, at_most).round().astype(int))


def _fitted_rows(estimator, n: int) -> np.ndarray:
    """The training rows a fit uses: all ``n``, or for an SVR or a GP beyond its limit
    (config ``models.svr_max_samples``, ``models.gpr_max_samples``) that many, evenly spaced."""
    limit = {"svr": estimator.svr_max_samples, "gpr": estimator.gpr_max_samples}.get(
        estimator.algorithm
    )
    return np.arange(n) if limit is None or n <= limit else _evenly_spaced(n, limit)


def _search_split(estimator) -> tuple[int, int]:
    """``(max_loco_runs, group_folds)`` of an estimator's inner search.

    An SVR's leaves one run out only up to ``svr_max_loco_runs`` training runs: each of
    its grid points is a kernel fit, and nested in leave-one-condition-out (and again in
    the recommendation's loops) a search over every run made the cost grow with the cube
    of the runs.
    """
    loco, folds = (int(v) for v in estimator.inner_search)
    if estimator.algorithm == "svr":
        loco = min(loco, int(estimator.svr_max_loco_runs))
    return loco, folds


def _fit_one(features, target, groups, estimator):
    """One regression; returns (fitted pipeline, chosen searched parameters or None)."""
    algorithm, params = estimator.algorithm, estimator.params
    inner = _search_split(estimator)
    if algorithm == "svr":
        if estimator.svr_grid is None:
            # No default grid here: the one default is the schema's (config models.svr_grid).
            raise ValueError(
                "algorithm 'svr' needs svr_grid (the workflow passes config models.svr_grid)"
            )
        # Fixed parameters (e.g. kernel) apply to every grid point unless the grid varies them.
        grid = {
            **{k: [v] for k, v in check_params("svr", params).items()},
            **dict(estimator.svr_grid),
        }
        # libsvm's cost grows faster than the square of the rows (at C = 100 and
        # epsilon = 0.01, 0.15 s for 300 rows, 1.2 s for 1,260): beyond the limit the
        # search and the fit use evenly spaced training rows, every run thinned alike, and
        # the search scores the grid on its first group folds only (config
        # models.svr_max_samples and models.inner_search.svr_folds; the model report says so).
        keep = _fitted_rows(estimator, len(target))
        return fit_by_group_search(
            "svr",
            features[keep],
            target[keep],
            groups[keep],
            grid,
            estimator.random_state,
            inner,
            max_group_folds=estimator.svr_search_folds,
        )
    if estimator.search_grid is not None and algorithm in SEARCHABLE:
        return fit_by_group_search(
            algorithm,
            features,
            target,
            groups,
            estimator.search_grid,
            estimator.random_state,
            inner,
        )
    model = make_regressor(
        algorithm, params, random_state=estimator.random_state, n_features=features.shape[1]
    )
    # An exact GP costs n^3: beyond the limit it is fitted on evenly spaced training rows
    # (config models.gpr_max_samples; the model report says so).
    keep = _fitted_rows(estimator, len(target)) if algorithm == "gpr" else slice(None)
    X, y = features[keep], target[keep]
    with checked_once([model.named_steps["regress"].regressor], X, y):
        return model.fit(X, y), None


def _fit_note(estimator, target: str, position_mm: float, rows: int, groups, chosen) -> dict:
    """What one regression's fit did: its inner search's split and choice, the rows a GP used.

    Follows :func:`_fit_one`, :func:`fit_by_group_search` and :func:`inner_group_splitter`
    (the model report states it; config ``models.inner_search``, ``models.gpr_max_samples``
    and ``models.svr_max_samples``).
    """
    algorithm = estimator.algorithm
    searched = algorithm == "svr" or (estimator.search_grid is not None and algorithm in SEARCHABLE)
    runs = int(np.unique(groups).size)
    if not searched:
        split = ""
    elif runs < 2:
        split = "none (one training run): the grid's first point"
    else:
        # The splitter the search used, so the note cannot drift from it.
        splitter = inner_group_splitter(groups, *_search_split(estimator))
        if isinstance(splitter, LeaveOneGroupOut):
            split = f"leave one of {runs} training runs out"
        else:
            folds = splitter.get_n_splits()
            split = f"{folds} group folds of {runs} training runs"
            if algorithm == "svr" and estimator.svr_search_folds < folds:
                first = "" if estimator.svr_search_folds == 1 else f" {estimator.svr_search_folds}"
                split = f"the first{first} of {split}"
    fitted = int(_fitted_rows(estimator, rows).size)
    return {
        "target": target,
        "position_mm": position_mm,
        "inner_search": split,
        "chosen": json.dumps(chosen, sort_keys=True) if chosen else "",
        "training_rows": int(rows),
        "rows_fitted": fitted,
    }


def _coefficient_rows(
    target, position_mm, temperature, terms: dict | None, signals: Sequence[str] = ()
) -> list[dict]:
    if terms is None:
        return []
    return [
        {
            "target": target,
            "position_mm": position_mm,
            "term": term,
            "temperature": "signal" if term in signals else temperature,
            "value": value,
        }
        for term, value in terms.items()
    ]


def _coefficient_frame(rows: list[dict]) -> pd.DataFrame:
    frame = pd.DataFrame(rows, columns=list(COEFFICIENT_COLUMNS))
    return frame.astype({"position_mm": float, "value": float})


def _z_score(level: float) -> float:
    if not 0.0 < level < 1.0:
        raise ValueError(f"interval level must lie strictly between 0 and 1, got {level}")
    # Imported here: scipy.stats costs seconds at import, and only intervals need it.
    from scipy.stats import norm

    return float(norm.ppf(0.5 + level / 2.0))


# --------------------------------------------------------------------------- decoupled


class DecoupledAxisModel(RegressorMixin, BaseEstimator):
    """Step-by-step model (Eq. 9): k from absolute, b from relative temperatures.

    Parameters
    ----------
    k_sensors : tuple of str
        Sensitive points of the slope k (absolute temperatures).  Higher decoupling
        coefficients (c2, c3) use the same sensors, also absolute: like k they describe
        the curve's shape, which follows the temperature field, not its drift.
    b_sensors : tuple of str
        Sensitive points of the intercept b (temperatures relative to the run's first
        measurement).
    algorithm : {"mlr", "svr", "ridge", "pls", "gpr"}
    params : dict, optional
        Hyper-parameters for :func:`make_regressor`; for svr, fixed values added to the grid.
    svr_grid : dict, optional
        SVR search grid (inner leave-one-run-out on the training runs); required for
        ``algorithm="svr"`` (the workflow passes config ``models.svr_grid``).
    search_grid : dict, optional
        For ridge, lasso and pls: a grid of their strength (``alpha``, ``n_components``)
        chosen by the same inner search; None fits ``params`` as given.
    inner_search : (int, int)
        ``(max_loco_runs, group_folds)``: the inner search leaves one run out up to
        ``max_loco_runs`` training runs and uses ``group_folds`` group folds above
        (config ``models.inner_search``).
    gpr_max_samples : int
        An exact Gaussian process is fitted on at most this many training rows, evenly
        spaced, beyond it (config ``models.gpr_max_samples``).
    svr_max_samples : int
        Likewise for an SVR's search and fit (config ``models.svr_max_samples``).
    svr_search_folds : int
        With group folds, an SVR's grid is scored on the first this many of them
        (config ``models.inner_search.svr_folds``).
    svr_max_loco_runs : int
        An SVR's search leaves one run out up to this many training runs (and never above
        ``inner_search``'s own limit), group folds above: a kernel search costs a fixed
        number of fits however many runs there are
        (config ``models.inner_search.svr_max_loco_runs``).
    degree : {1, 2, 3}
        Decoupling polynomial degree; 1 is the paper's straight line.
    random_state : int
    signals : tuple of str
        Operating signals (columns of X, e.g. a spindle speed) added as inputs to every
        coefficient's regression, as logged.

    Attributes
    ----------
    positions_mm_ : ndarray
        Target positions seen in fit; predictions are on these.
    origin_mm_ : float
        First target; the shifted stroke starts here and b is the error at it.
    kb_ : DataFrame
        Training decoupling: run, measurement, k_um_per_m, b_um (c2_um_per_m2,
        c3_um_per_m3 for higher degrees), r2, rms_um.
    estimators_ : dict
        Fitted pipeline per target ("k", "b", "c2", "c3").
    searched_params_ : dict
        Parameters chosen by the inner search per target (empty without a search).
    fit_notes_ : list of dict
        Per regression: its inner search's split and choice, its training rows and the rows
        a Gaussian process was fitted on (the model report's "How each model was fitted").
    """

    # Every parameter has a default because scikit-learn asks it of an estimator (clone,
    # get_params, construction without arguments); the defaults are the paper's Eq. 9 model.
    # The workflow sets each one from the settings (thermaxis.method.folds).
    def __init__(
        self,
        k_sensors=_DEFAULTS["k_sensors"],
        b_sensors=_DEFAULTS["b_sensors"],
        algorithm=_DEFAULTS["algorithm"],
        params=None,
        svr_grid=None,
        degree=_DEFAULTS["degree"],
        random_state=_DEFAULTS["random_state"],
        signals=_DEFAULTS["signals"],
        search_grid=None,
        inner_search=_DEFAULTS["inner_search"],
        gpr_max_samples=_DEFAULTS["gpr_max_samples"],
        svr_max_samples=_DEFAULTS["svr_max_samples"],
        svr_search_folds=_DEFAULTS["svr_search_folds"],
        svr_max_loco_runs=_DEFAULTS["svr_max_loco_runs"],
    ):
        self.k_sensors = k_sensors
        self.b_sensors = b_sensors
        self.algorithm = algorithm
        self.params = params
        self.svr_grid = svr_grid
        self.search_grid = search_grid
        self.inner_search = inner_search
        self.gpr_max_samples = gpr_max_samples
        self.svr_max_samples = svr_max_samples
        self.svr_search_folds = svr_search_folds
        self.svr_max_loco_runs = svr_max_loco_runs
        self.degree = degree
        self.random_state = random_state
        self.signals = signals

    def _targets(self) -> list[tuple[str, tuple[str, ...], str]]:
        """(target, sensors, temperature kind) per modelled coefficient."""
        targets = [
            ("k", tuple(self.k_sensors), "absolute"),
            ("b", tuple(self.b_sensors), "relative"),
        ]
        targets += [(f"c{p}", tuple(self.k_sensors), "absolute") for p in range(2, self.degree + 1)]
        return targets

    def fit(self, X: pd.DataFrame, Y: pd.DataFrame) -> DecoupledAxisModel:
        """Decouple every training measurement and regress its coefficients on temperature."""
        check_algorithm(self.algorithm)
        if self.degree not in (1, 2, 3):
            raise ValueError(f"decoupling degree must be 1, 2 or 3, got {self.degree}")
        _check_X(X, (*self.k_sensors, *self.b_sensors, *self.signals))
        self.positions_mm_ = _positions_of(X, Y)
        self.origin_mm_ = float(self.positions_mm_[0])
        self.kb_ = decouple_rows(X, Y, self.degree)
        groups = X["run"].to_numpy()
        self.estimators_, self.searched_params_, self.fit_notes_ = {}, {}, []
        for target, sensors, temperature in self._targets():
            features = _features(X, sensors, temperature, self.signals)
            y = self.kb_[_KB_COLUMNS[target]].to_numpy(dtype=float)
            model, chosen = _fit_one(features, y, groups, self)
            self.estimators_[target] = model
            self.fit_notes_.append(_fit_note(self, target, np.nan, len(y), groups, chosen))
            if chosen is not None:
                self.searched_params_[target] = chosen
        return self

    def predict_kb(self, X: pd.DataFrame, return_std: bool = False) -> pd.DataFrame:
        """Predicted decoupling coefficients per row of X.

        Parameters
        ----------
        X : DataFrame
            Temperatures of the runs to predict (each run's first measurement included).
        return_std : bool
            Also return each coefficient's predictive standard deviation as a
            ``<column>_std`` column (gpr only, else ``NotImplementedError``).

        Returns
        -------
        DataFrame
            Index aligned with X; columns k_um_per_m, b_um (c2_um_per_m2, c3_um_per_m3 for
            higher degrees), then the ``_std`` columns if asked for.
        """
        if return_std and self.algorithm != "gpr":
            raise NotImplementedError(
                "predictive standard deviations are only available for algorithm 'gpr'"
            )
        _check_X(X, (*self.k_sensors, *self.b_sensors, *self.signals))
        means, stds = {}, {}
        for target, sensors, temperature in self._targets():
            features = _features(X, sensors, temperature, self.signals)
            column = _KB_COLUMNS[target]
            if return_std:
                means[column], stds[f"{column}_std"] = predict_with_std(
                    self.estimators_[target], features
                )
            else:
                means[column] = np.asarray(self.estimators_[target].predict(features)).ravel()
        return pd.DataFrame({**means, **stds}, index=X.index)

    def predict(self, X: pd.DataFrame) -> np.ndarray:
        """Predicted error curves, shape (n rows, n positions) in um."""
        return self.compose(self.predict_kb(X))

    def compose(self, kb: pd.DataFrame) -> np.ndarray:
        """Error curves (n rows, n positions, um) from :meth:`predict_kb`'s coefficients (Eq. 7)."""
        coefficients = np.column_stack(
            [
                kb["b_um"],
                kb["k_um_per_m"],
                *(kb[_KB_COLUMNS[f"c{p}"]] for p in range(2, self.degree + 1)),
            ]
        )
        return compose_curve(coefficients, self.positions_mm_, self.origin_mm_)

    def predict_kb_interval(
        self, X: pd.DataFrame, level: float
    ) -> dict[str, tuple[np.ndarray, np.ndarray]]:
        """Gaussian interval of each decoupling coefficient (gpr only): column -> (lower, upper)."""
        z = _z_score(level)
        kb = self.predict_kb(X, return_std=True)
        columns = [c for c in kb.columns if not c.endswith("_std")]
        return {
            c: (
                kb[c].to_numpy() - z * kb[f"{c}_std"].to_numpy(),
                kb[c].to_numpy() + z * kb[f"{c}_std"].to_numpy(),
            )
            for c in columns
        }

    def predict_interval(self, X: pd.DataFrame, level: float) -> tuple[np.ndarray, np.ndarray]:
        """Pointwise prediction interval of the error curves (gpr only).

        The k, b (and c2, c3) models are fitted separately, so their predictive
        uncertainties are taken as independent: var e(x) = sum_p s_p^2 x^(2p) on the
        shifted stroke x.  Gaussian quantiles at ``level``.

        Raises
        ------
        NotImplementedError
            For algorithms other than gpr.
        """
        if self.algorithm != "gpr":
            raise NotImplementedError("prediction intervals are only available for algorithm 'gpr'")
        z = _z_score(level)
        kb = self.predict_kb(X, return_std=True)
        columns = [_KB_COLUMNS[t] for t in ("b", "k", "c2", "c3")[: self.degree + 1]]
        means = kb[columns].to_numpy()
        stds = kb[[f"{c}_std" for c in columns]].to_numpy()
        powers = stroke_powers(self.positions_mm_, self.origin_mm_, self.degree).T
        centre = means @ powers
        half = z * np.sqrt(stds**2 @ powers**2)
        return centre - half, centre + half

    def coefficients(self) -> pd.DataFrame:
        """Fitted terms in the paper's units (Eq. 9); no rows for svr and gpr.

        Returns
        -------
        DataFrame
            Columns target ("k", "b", "c2", "c3"), position_mm (NaN), term ("const" or a
            sensor id), temperature ("absolute" or "relative", the kind the model uses),
            value (k: um/m and um/m per degree C; b: um and um per degree C).
        """
        rows = []
        for target, sensors, temperature in self._targets():
            terms = linear_terms(self.estimators_[target], (*sensors, *self.signals))
            rows += _coefficient_rows(target, np.nan, temperature, terms, self.signals)
        return _coefficient_frame(rows)


# --------------------------------------------------------------------------- pointwise


class PointwiseAxisModel(RegressorMixin, BaseEstimator):
    """Point-by-point baseline (Eq. 8): one regression per target position.

    Inputs are temperatures relative to the run's first measurement, as Eq. 8's small
    constants show.  A position's fit skips the rows where its error is missing.

    Parameters
    ----------
    sensors : tuple of str
        Sensitive points used for every position (the paper: T1, T11, T12).
    algorithm, params, svr_grid, search_grid, inner_search, gpr_max_samples, svr_max_samples, svr_search_folds, svr_max_loco_runs, random_state, signals
        As for :class:`DecoupledAxisModel`.

    Attributes
    ----------
    positions_mm_ : ndarray
    estimators_ : list
        Fitted pipeline per position.
    searched_params_ : dict
        Parameters chosen by the inner search per position (empty without a search).
    fit_notes_ : list of dict
        As for :class:`DecoupledAxisModel`, one per position.
    """

    # Defaults for scikit-learn, as for DecoupledAxisModel: the paper's Eq. 8 model.
    def __init__(
        self,
        sensors=_DEFAULTS["sensors"],
        algorithm=_DEFAULTS["algorithm"],
        params=None,
        svr_grid=None,
        random_state=_DEFAULTS["random_state"],
        signals=_DEFAULTS["signals"],
        search_grid=None,
        inner_search=_DEFAULTS["inner_search"],
        gpr_max_samples=_DEFAULTS["gpr_max_samples"],
        svr_max_samples=_DEFAULTS["svr_max_samples"],
        svr_search_folds=_DEFAULTS["svr_search_folds"],
        svr_max_loco_runs=_DEFAULTS["svr_max_loco_runs"],
    ):
        self.sensors = sensors
        self.algorithm = algorithm
        self.params = params
        self.svr_grid = svr_grid
        self.search_grid = search_grid
        self.inner_search = inner_search
        self.gpr_max_samples = gpr_max_samples
        self.svr_max_samples = svr_max_samples
        self.svr_search_folds = svr_search_folds
        self.svr_max_loco_runs = svr_max_loco_runs
        self.random_state = random_state
        self.signals = signals

    def fit(self, X: pd.DataFrame, Y: pd.DataFrame) -> PointwiseAxisModel:
        """Fit one regression per position on relative temperatures."""
        check_algorithm(self.algorithm)
        _check_X(X, (*self.sensors, *self.signals))
        self.positions_mm_ = _positions_of(X, Y, min_positions=1)
        features = _features(X, self.sensors, "relative", self.signals)
        groups = X["run"].to_numpy()
        errors = Y.to_numpy(dtype=float)
        self.estimators_, self.searched_params_, self.fit_notes_ = [], {}, []
        for j, position in enumerate(self.positions_mm_):
            valid = np.isfinite(errors[:, j])
            if valid.sum() < 2:
                raise ValueError(
                    f"position {position:g} mm has {valid.sum()} error reading(s); need at least 2"
                )
            model, chosen = _fit_one(features[valid], errors[valid, j], groups[valid], self)
            self.estimators_.append(model)
            self.fit_notes_.append(
                _fit_note(self, "error", float(position), int(valid.sum()), groups[valid], chosen)
            )
            if chosen is not None:
                self.searched_params_[float(position)] = chosen
        return self

    def predict(self, X: pd.DataFrame) -> np.ndarray:
        """Predicted errors, shape (n rows, n positions) in um."""
        _check_X(X, (*self.sensors, *self.signals))
        features = _features(X, self.sensors, "relative", self.signals)
        return np.column_stack([np.asarray(m.predict(features)).ravel() for m in self.estimators_])

    def predict_interval(self, X: pd.DataFrame, level: float) -> tuple[np.ndarray, np.ndarray]:
        """Pointwise Gaussian prediction interval (gpr only; else NotImplementedError)."""
        if self.algorithm != "gpr":
            raise NotImplementedError("prediction intervals are only available for algorithm 'gpr'")
        z = _z_score(level)
        _check_X(X, (*self.sensors, *self.signals))
        features = _features(X, self.sensors, "relative", self.signals)
        mean, std = zip(*(predict_with_std(m, features) for m in self.estimators_), strict=False)
        mean, std = np.column_stack(mean), np.column_stack(std)
        return mean - z * std, mean + z * std

    def coefficients(self) -> pd.DataFrame:
        """Fitted terms per position in um and um per degree C (Eq. 8); no rows for svr/gpr."""
        rows = []
        for position, model in zip(self.positions_mm_, self.estimators_, strict=False):
            terms = linear_terms(model, (*self.sensors, *self.signals))
            rows += _coefficient_rows("error", float(position), "relative", terms, self.signals)
        return _coefficient_frame(rows)
