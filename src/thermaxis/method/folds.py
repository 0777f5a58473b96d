"""One configuration on one leave-one-condition-out fold: select, fit, predict, score.

This module is the single implementation shared by the main workflow (one fold at a
time) and the sweep (hundreds of configurations in one process): selection results
are computed once per fold and selection setting and reused by every algorithm.

Leakage rule: everything fitted (sensitive points when ``scope='training'``, scalers,
hyper-parameter searches, regressions) sees only the training runs. The held-out
run contributes its temperatures (relative ones to its own first measurement) at
prediction time and its measured errors only to the metrics.
"""

from __future__ import annotations

import json
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace

import numpy as np
import pandas as pd

from thermaxis.config import ModelSettings, SelectionSettings
from thermaxis.errors import DataError, SelectionWarning
from thermaxis.labels import natural_sorted, sort_naturally
from thermaxis.method.features import decouple_rows, relative_temperatures
from thermaxis.method.metrics import metric_frame
from thermaxis.method.selection import (
    SensitivePoints,
    common_points,
    informative_sensors,
    rank_by_correlation,
    select_sensitive_points,
)

__all__ = [
    "SORT_KEYS",
    "FoldSelection",
    "FoldResult",
    "select_for_fold",
    "evaluate_configuration",
    "fold_metrics",
    "fit_held_out",
    "build_model",
    "selection_table",
    "selection_to_dict",
    "selection_from_dict",
    "fold_models",
    "run_groups",
    "held_out_runs",
    "fold_name",
]

META = ("run", "measurement", "time_min")

# Row order of the result tables, per fold and collected over folds (deterministic files).
SORT_KEYS = {
    "metrics": ["fold", "approach", "algorithm", "target"],
    "coefficients": [
        "fold",
        "approach",
        "algorithm",
        "target",
        "position_mm",
        "temperature",
        "term",
    ],
    "kb_predictions": ["fold", "approach", "algorithm", "target", "measurement"],
    "error_predictions": ["fold", "approach", "algorithm", "measurement", "position_mm"],
    "fitting": ["fold", "approach", "algorithm", "target", "position_mm"],
    "selection": ["fold", "target", "position_mm", "cluster", "sensor"],
}


@dataclass(frozen=True)
class FoldSelection:
    """Sensitive points of one fold: for k, for b, per position, and the pointwise common set."""

    fold: str
    k: SensitivePoints | None
    b: SensitivePoints | None
    per_position: Mapping[float, SensitivePoints] = field(default_factory=dict)
    pointwise: tuple[str, ...] = ()

    @property
    def k_sensors(self) -> tuple[str, ...]:
        return self.k.selected if self.k is not None else ()

    @property
    def b_sensors(self) -> tuple[str, ...]:
        return self.b.selected if self.b is not None else ()


def sensor_columns(X: pd.DataFrame) -> list[str]:
    return [c for c in X.columns if c not in META]


def _points(
    method: str, T: pd.DataFrame, y: np.ndarray, s: SelectionSettings, target: str
) -> SensitivePoints:
    if method == "fuzzy_grey":
        return select_sensitive_points(
            T,
            y,
            n_clusters=s.n_clusters,
            similarity=s.similarity,
            grade=s.grade,
            rho=s.rho,
            normalisation=s.normalisation,
        )
    if method == "correlation":
        chosen = rank_by_correlation(T, y, s.n_clusters)
        return SensitivePoints(
            clusters=tuple((c,) for c in chosen),
            selected=chosen,
            grades=_abs_correlation(T, y),
            eta=float("nan"),
        )
    if method == "all":
        names = tuple(T.columns)
        return SensitivePoints(clusters=(names,), selected=names, grades={}, eta=float("nan"))
    if method == "fixed":
        chosen = s.fixed_for(target)
        unknown = [c for c in chosen if c not in T.columns]
        if unknown:
            # A declared sensor is missing here when cleaning left it out (no reading in
            # some measurement): the clean job's warning says where.
            raise ValueError(
                f"config selection.fixed.{target}: sensor {unknown[0]!r} is not a candidate; "
                f"expected one of {', '.join(T.columns)} (a sensor that is not in dataset.yaml, "
                "or that lacks a reading in some measurement, is none)"
            )
        return SensitivePoints(
            clusters=tuple((c,) for c in chosen), selected=chosen, grades={}, eta=float("nan")
        )
    raise ValueError(f"config selection.method: unknown method {method!r}")


def _abs_correlation(T: pd.DataFrame, y: np.ndarray) -> dict[str, float]:
    """|Pearson r| of every sensor with y (0 for a constant sensor): the correlation ranking's scores."""
    values = T.to_numpy(dtype=float)
    centred = values - values.mean(axis=0)
    yc = np.asarray(y, dtype=float) - np.mean(y)
    denominator = np.sqrt((centred**2).sum(axis=0) * (yc @ yc))
    r = np.divide(
        np.abs(centred.T @ yc), denominator, out=np.zeros(values.shape[1]), where=denominator > 0
    )
    return {str(name): float(v) for name, v in zip(T.columns, r, strict=False)}


def _mean_scores(points: list[SensitivePoints]) -> dict[str, float]:
    """Each sensor's mean grade over the positions: the selection's own ranking for tie-breaks."""
    totals: dict[str, float] = {}
    for p in points:
        for sensor, grade in p.grades.items():
            totals[sensor] = totals.get(sensor, 0.0) + float(grade)
    return {sensor: total / len(points) for sensor, total in totals.items()}


def run_groups(
    runs: Sequence[str], max_loco_runs: int, n_group_folds: int
) -> list[tuple[str, ...]]:
    """Held-out run groups of a loop over runs: one run each, or k group folds when runs are many.

    Above ``max_loco_runs`` runs, leave-one-condition-out would cost one fit per run per
    candidate; k contiguous groups in natural run order (which usually follows the
    order the conditions were measured in) keep the cost fixed.
    """
    runs = natural_sorted(runs)
    if len(runs) <= max_loco_runs:
        return [(run,) for run in runs]
    k = min(n_group_folds, len(runs))
    return [tuple(chunk) for chunk in np.array_split(np.array(runs, dtype=object), k)]


def held_out_runs(fold: str | Sequence[str]) -> tuple[str, ...]:
    """The runs a fold holds out: one run, or a group of them (an inner group fold)."""
    return (fold,) if isinstance(fold, str) else tuple(fold)


def fold_name(fold: str | Sequence[str]) -> str:
    """A fold's label: its run, or its group's runs joined by "+"."""
    return "+".join(held_out_runs(fold))


def select_for_fold(
    X: pd.DataFrame,
    Y: pd.DataFrame,
    fold: str,
    settings: SelectionSettings,
    degree: int | None,
    decoupled: bool = True,
    pointwise: bool = True,
    relative: pd.DataFrame | None = None,
    cap_clusters: bool = True,
) -> FoldSelection:
    """Sensitive points for k (absolute temperatures), b and each position (relative ones).

    k and b are those of the decoupling of ``degree`` (config ``decoupling.degree``);
    ``None`` only with ``decoupled=False``, which decouples nothing.

    With ``scope='training'`` the held-out run (``fold``) is removed first, so the
    choice of inputs cannot depend on the condition being predicted.
    ``pointwise=False`` skips the per-position selection (empty ``per_position`` and
    ``pointwise``): the sweep selects k and b once per decoupling degree, but the
    point-by-point points, which do not depend on the degree, only once.
    ``relative``: :func:`relative_temperatures` of ``X``, when the caller has it (the
    sweep selects thousands of times on one X); a run's values depend on its own rows
    only, so they are the same whichever runs the fold keeps.
    ``cap_clusters``: more clusters than sensors that vary make each sensor a cluster (a
    warning); False (the sweep) refuses instead, so a swept cluster count is the one used.
    """
    name = fold_name(fold)
    if settings.scope == "training":
        keep = ~X["run"].isin(held_out_runs(fold)).to_numpy()
        X, Y = X.loc[keep], Y.loc[keep]
        relative = None if relative is None else relative.loc[keep]
    fixed = (
        tuple(s for _, names in settings.fixed for s in names) if settings.method == "fixed" else ()
    )
    sensors = informative_sensors(X[sensor_columns(X)], fixed, where=f"fold {name}")
    settings = _capped_clusters(settings, sensors, name, cap_clusters)
    absolute = X[sensors]
    relative = (relative_temperatures(X) if relative is None else relative)[sensors]
    k_points = b_points = None
    if decoupled:
        kb = decouple_rows(X, Y, degree=degree)
        k_points = _points(settings.method, absolute, kb["k_um_per_m"].to_numpy(), settings, "k")
        b_points = _points(settings.method, relative, kb["b_um"].to_numpy(), settings, "b")
    per_position, common = (
        _pointwise_points(Y, relative, sensors, settings, name) if pointwise else ({}, ())
    )
    return FoldSelection(
        fold=name, k=k_points, b=b_points, per_position=per_position, pointwise=tuple(common)
    )


def _capped_clusters(
    settings: SelectionSettings, sensors: list, name: str, cap_clusters: bool
) -> SelectionSettings:
    """The settings with at most one cluster per sensor that varies over the fold's training."""
    if settings.method in ("fuzzy_grey", "correlation") and settings.n_clusters > len(sensors):
        # More clusters than sensors that vary: each sensor is a cluster of its own, and
        # so a sensitive point (a dataset of two sensors, a fold whose others are constant).
        varying = "1 sensor varies" if len(sensors) == 1 else f"{len(sensors)} sensors vary"
        what = (
            f"fold {name}: {settings.n_clusters} clusters (selection.n_clusters) but only "
            f"{varying} over its training measurements"
        )
        if not cap_clusters:
            raise DataError(f"{what}; expected at most {len(sensors)}")
        warnings.warn(
            f"{what}; each is a cluster of its own, and a sensitive point",
            SelectionWarning,
            stacklevel=3,
        )
        settings = replace(settings, n_clusters=len(sensors))
    return settings


def _pointwise_points(
    Y: pd.DataFrame, relative: pd.DataFrame, sensors: list, settings: SelectionSettings, name: str
) -> tuple[dict, tuple]:
    """Point-by-point: the sensitive points of each position and their common set."""
    per_position = {}
    if settings.method == "all":
        # Every sensor ties under "all": the common set is every sensor, not the first n.
        common = tuple(sensors)
    elif settings.method == "fixed":
        common = settings.fixed_for("pointwise")
        _points("fixed", relative, np.zeros(len(relative)), settings, "pointwise")
    else:
        for position in Y.columns:
            y = Y[position].to_numpy(dtype=float)
            ok = ~np.isnan(y)
            per_position[float(position)] = _points(
                settings.method, relative.loc[ok], y[ok], settings, "pointwise"
            )
        chosen = [p.selected for p in per_position.values()]
        distinct = len({sensor for points in chosen for sensor in points})
        n_common = min(settings.pointwise_common, distinct)
        if n_common < settings.pointwise_common:
            warnings.warn(
                f"fold {name}: only {distinct} distinct sensor{'s were' if distinct != 1 else ' was'} "
                "selected over the positions; "
                f"the point-by-point common set has {n_common} instead of {settings.pointwise_common}",
                SelectionWarning,
                stacklevel=3,
            )
        common = common_points(
            chosen, n_common, order=sensors, scores=_mean_scores(list(per_position.values()))
        )
    return per_position, common


def selection_table(selection: FoldSelection) -> pd.DataFrame:
    """Tables 3 and 6 in long form: fold, target, position_mm, sensor, cluster, selected, grade."""
    rows = []

    def add(target, position, points: SensitivePoints):
        for c, cluster in enumerate(points.clusters, start=1):
            for sensor in cluster:
                rows.append(
                    (
                        selection.fold,
                        target,
                        position,
                        sensor,
                        c,
                        sensor in points.selected,
                        points.grades.get(sensor, np.nan),
                    )
                )

    if selection.k is not None:
        add("k", np.nan, selection.k)
    if selection.b is not None:
        add("b", np.nan, selection.b)
    for position, points in selection.per_position.items():
        add("error", position, points)
    for sensor in selection.pointwise:
        rows.append((selection.fold, "pointwise_common", np.nan, sensor, 0, True, np.nan))
    return pd.DataFrame(
        rows, columns=["fold", "target", "position_mm", "sensor", "cluster", "selected", "grade"]
    )


@dataclass(frozen=True)
class FoldResult:
    metrics: pd.DataFrame
    coefficients: pd.DataFrame
    kb_predictions: pd.DataFrame
    error_predictions: pd.DataFrame
    fitting: pd.DataFrame  # per regression: inner search, choice, rows (models' fit_notes_)


def build_model(
    approach: str,
    algorithm: str,
    selection: FoldSelection,
    model: ModelSettings,
    degree: int | None,
):
    """The unfitted estimator of an approach and algorithm on a fold's sensitive points:
    what the folds are scored with and the compensation deploys."""
    # Imported here: selecting sensitive points, which shares this module, needs no
    # scikit-learn, and a selection job should not pay for importing it.
    from thermaxis.method.estimators import DecoupledAxisModel, PointwiseAxisModel

    common = dict(
        algorithm=algorithm,
        params=model.params_for(algorithm),
        svr_grid=model.grid(),
        search_grid=model.search_grid_for(algorithm),
        inner_search=model.inner_search,
        gpr_max_samples=model.gpr_max_samples,
        svr_max_samples=model.svr_max_samples,
        svr_search_folds=model.svr_search_folds,
        svr_max_loco_runs=model.svr_max_loco_runs,
        random_state=model.random_state,
        signals=model.signals,
    )
    if approach == "decoupled":
        return DecoupledAxisModel(
            k_sensors=selection.k_sensors, b_sensors=selection.b_sensors, degree=degree, **common
        )
    if approach == "pointwise":
        return PointwiseAxisModel(sensors=selection.pointwise, **common)
    raise ValueError(f"unknown approach {approach!r} (expected decoupled or pointwise)")


def evaluate_configuration(
    X: pd.DataFrame,
    Y: pd.DataFrame,
    fold: str,
    approach: str,
    algorithm: str,
    selection: FoldSelection,
    model: ModelSettings,
    degree: int | None,
) -> FoldResult:
    """Fit on every run but ``fold``, predict ``fold`` from its temperatures, and score.

    ``degree`` is the decoupling's (config ``decoupling.degree``); the point-by-point
    approach never decouples and ignores it (``None`` allowed).
    """
    estimator, X_test, Y_test = fit_held_out(
        X, Y, fold, approach, algorithm, selection, model, degree
    )
    label = {"fold": fold_name(fold), "approach": approach, "algorithm": algorithm}
    kb_measured, kb_predicted, predicted = _predictions(estimator, X_test, Y_test, approach, degree)
    level = model.interval_level
    lower = upper = np.full_like(predicted, np.nan)
    if algorithm == "gpr":
        lower, upper = estimator.predict_interval(X_test, level=level)
    measured = Y_test.to_numpy(dtype=float)
    return FoldResult(
        metrics=metric_frame(label, _compared(measured, kb_measured, kb_predicted, predicted)),
        coefficients=_coefficient_table(estimator, label),
        kb_predictions=(
            _empty_kb()
            if kb_predicted is None
            else _kb_table(estimator, X_test, label, level, kb_measured, kb_predicted)
        ),
        error_predictions=_error_table(
            label, X_test, np.asarray(Y.columns, dtype=float), measured, predicted, lower, upper
        ),
        fitting=pd.DataFrame([{**label, **note} for note in estimator.fit_notes_]),
    )


def fold_metrics(
    X: pd.DataFrame,
    Y: pd.DataFrame,
    fold: str,
    approach: str,
    algorithm: str,
    selection: FoldSelection,
    model: ModelSettings,
    degree: int | None,
    per_run: bool = False,
) -> pd.DataFrame:
    """``evaluate_configuration(...).metrics`` alone: no intervals, coefficients or tables of
    predictions, which cost a sweep or a recommendation more than the metrics they score.

    ``per_run``: a fold of several runs (:func:`held_out_runs`) is scored run by run, each
    row's ``fold`` its run, from one fit.
    """
    estimator, X_test, Y_test = fit_held_out(
        X, Y, fold, approach, algorithm, selection, model, degree
    )
    label = {"fold": fold_name(fold), "approach": approach, "algorithm": algorithm}
    compared = _compared(
        Y_test.to_numpy(dtype=float), *_predictions(estimator, X_test, Y_test, approach, degree)
    )
    return metric_frame(label, compared, X_test["run"].to_numpy() if per_run else None)


def fit_held_out(X, Y, fold, approach, algorithm, selection, model, degree):
    """The configuration fitted on every run but ``fold``, and ``fold``'s own X and Y."""
    X_train, Y_train, X_test, Y_test = _split_fold(X, Y, fold)
    estimator = build_model(approach, algorithm, selection, model, degree).fit(X_train, Y_train)
    return estimator, X_test, Y_test


def _split_fold(X: pd.DataFrame, Y: pd.DataFrame, fold: str):
    """X and Y of the training runs (every run but ``fold``), then of ``fold``, each indexed from 0."""
    test = X["run"].isin(held_out_runs(fold)).to_numpy()
    if not test.any():
        raise ValueError(f"fold {fold_name(fold)!r}: no measurements of that run")
    train = X.loc[~test].reset_index(drop=True), Y.loc[~test].reset_index(drop=True)
    return (*train, X.loc[test].reset_index(drop=True), Y.loc[test].reset_index(drop=True))


def _predictions(estimator, X_test, Y_test, approach, degree):
    """Measured and predicted decoupling coefficients (both None point by point), then the
    predicted error curves; each regression predicts the held-out rows once."""
    if approach != "decoupled":
        return None, None, np.asarray(estimator.predict(X_test), dtype=float)
    kb_predicted = estimator.predict_kb(X_test)
    kb_measured = decouple_rows(X_test, Y_test, degree=degree)
    return kb_measured, kb_predicted, estimator.compose(kb_predicted)


_KB_TARGETS = (("k", "k_um_per_m"), ("b", "b_um"))


def _compared(measured, kb_measured, kb_predicted, predicted) -> list[tuple]:
    """(target, measured, predicted) of the slope k and the intercept b (decoupled only),
    then of the error curves: what :func:`metric_frame` scores."""
    rows = [
        (target, kb_measured[column].to_numpy(), kb_predicted[column].to_numpy())
        for target, column in (_KB_TARGETS if kb_predicted is not None else ())
    ]
    return [*rows, ("error", measured, predicted)]


def _kb_table(
    estimator, X_test, label: dict, level: float, kb_measured, kb_predicted
) -> pd.DataFrame:
    """Measured and predicted slope k and intercept b of the held-out measurements (a GPR's interval too)."""
    kb_interval = (
        estimator.predict_kb_interval(X_test, level) if label["algorithm"] == "gpr" else None
    )
    frames = []
    for target, column in _KB_TARGETS:
        predicted = kb_predicted[column].to_numpy()
        lower, upper = (
            kb_interval[column]
            if kb_interval is not None
            else (np.full_like(predicted, np.nan),) * 2
        )
        frames.append(
            pd.DataFrame(
                {
                    **label,
                    "run": X_test["run"].to_numpy(),
                    "measurement": X_test["measurement"].to_numpy(),
                    "time_min": X_test["time_min"].to_numpy(),
                    "target": target,
                    "measured": kb_measured[column].to_numpy(),
                    "predicted": predicted,
                    "lower": lower,
                    "upper": upper,
                }
            )
        )
    return pd.concat(frames, ignore_index=True)


def _error_table(
    label: dict, X_test, positions: np.ndarray, measured, predicted, lower, upper
) -> pd.DataFrame:
    """One row per held-out measurement and target position: measured, predicted, residual, interval."""
    n, p = measured.shape
    return pd.DataFrame(
        {
            **label,
            "run": np.repeat(X_test["run"].to_numpy(), p),
            "measurement": np.repeat(X_test["measurement"].to_numpy(), p),
            "time_min": np.repeat(X_test["time_min"].to_numpy(), p),
            "position_mm": np.tile(positions, n),
            "measured": measured.ravel(),
            "predicted": predicted.ravel(),
            "residual": (measured - predicted).ravel(),
            "lower": np.asarray(lower, dtype=float).ravel(),
            "upper": np.asarray(upper, dtype=float).ravel(),
        }
    )


def _coefficient_table(estimator, label: dict) -> pd.DataFrame:
    """The fitted terms (the paper's Eq. 8 or Eq. 9), labelled with the fold and the model."""
    coefficients = estimator.coefficients().assign(**label)
    return coefficients[
        ["fold", "approach", "algorithm", "target", "position_mm", "term", "temperature", "value"]
    ]


def _empty_kb() -> pd.DataFrame:
    return pd.DataFrame(
        columns=[
            "fold",
            "approach",
            "algorithm",
            "run",
            "measurement",
            "time_min",
            "target",
            "measured",
            "predicted",
            "lower",
            "upper",
        ]
    )


def _points_to_dict(points: SensitivePoints | None):
    if points is None:
        return None
    return {
        "clusters": [list(c) for c in points.clusters],
        "selected": list(points.selected),
        "grades": {k: float(v) for k, v in sorted(points.grades.items())},
        "eta": None if np.isnan(points.eta) else float(points.eta),
    }


def _points_from_dict(d) -> SensitivePoints | None:
    if d is None:
        return None
    return SensitivePoints(
        clusters=tuple(tuple(c) for c in d["clusters"]),
        selected=tuple(d["selected"]),
        grades=dict(d["grades"]),
        eta=float("nan") if d["eta"] is None else float(d["eta"]),
    )


def selection_to_dict(selection: FoldSelection) -> dict:
    """A JSON-ready form; floats of positions become strings so keys survive JSON."""
    return {
        "fold": selection.fold,
        "k": _points_to_dict(selection.k),
        "b": _points_to_dict(selection.b),
        "per_position": {
            repr(float(p)): _points_to_dict(v) for p, v in sorted(selection.per_position.items())
        },
        "pointwise": list(selection.pointwise),
    }


def selection_from_dict(d: dict) -> FoldSelection:
    return FoldSelection(
        fold=d["fold"],
        k=_points_from_dict(d["k"]),
        b=_points_from_dict(d["b"]),
        per_position={float(p): _points_from_dict(v) for p, v in d["per_position"].items()},
        pointwise=tuple(d["pointwise"]),
    )


def fold_models(
    fold: str,
    X_select: pd.DataFrame,
    X: pd.DataFrame,
    Y: pd.DataFrame,
    selection: SelectionSettings,
    models: ModelSettings,
    degree: int,
    decoupled: bool,
    approaches: Sequence[str],
    algorithms: Sequence[str],
) -> tuple[FoldSelection, str, dict[str, pd.DataFrame]]:
    """One fold of the models stage: its sensitive points, with their JSON record, and
    every approach x algorithm fitted on them, each table sorted by :data:`SORT_KEYS`.

    ``X_select`` holds the temperatures the selection reads, ``X`` those and the signals
    the models read. The models use the selection as read back from its record, as a
    later job reading the file does.
    """
    chosen = select_for_fold(X_select, Y, fold, selection, degree, decoupled=decoupled)
    record = json.dumps(selection_to_dict(chosen), indent=1, sort_keys=True) + "\n"
    read_back = selection_from_dict(json.loads(record))
    results = [
        evaluate_configuration(X, Y, fold, approach, algorithm, read_back, models, degree)
        for approach in approaches
        for algorithm in algorithms
    ]
    return (
        chosen,
        record,
        {
            name: sort_naturally(
                pd.concat([getattr(r, name) for r in results], ignore_index=True), keys
            )
            for name, keys in SORT_KEYS.items()
            if name != "selection"
        },
    )
