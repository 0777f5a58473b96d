"""Evaluating a sweep: every configuration of a batch on its fold, then the summary and ranking.

Each configuration is evaluated on every fold by
:func:`thermaxis.method.folds.fold_metrics`, the metrics of the function the main
workflow's ``models`` rule calls: the sweep has no model code of its own, and its metric
columns are :data:`thermaxis.method.metrics.METRIC_COLUMNS`. The grid, units and batches are
planned by :mod:`thermaxis.sweep.plan`; the figures are in :mod:`thermaxis.figures`.

How the cost is kept down
-------------------------
* Start-up and imports are paid per *batch*, not per configuration: a batch is one
  process that reads the assembled tables once and works through its share of the
  grid.
* A unit's sensitive points are selected once per decoupling degree and shared by
  every approach and algorithm.
* Many selection settings pick the same sensors (the point-by-point common set has
  ``selection.pointwise_common`` sensors whatever the cluster count).  An evaluation depends on the selection
  only through the sensors its model uses, so within a batch the metrics of an
  identical (fold, approach, algorithm, degree, sensors) evaluation are reused.
* Linear evaluations (mlr, ridge and pls at fixed strengths) are not fitted one by one:
  every point set of a (fold, approach, algorithm, degree) is solved at once from the
  fold's Gram matrices (:mod:`thermaxis.method.batched`, the same numbers to 1e-9).

scikit-learn is imported only when a batch evaluates, so the collecting and plotting
jobs do not pay for it.
"""

from __future__ import annotations

import logging
import math
import sys
import time
from collections.abc import Callable, Iterable

import numpy as np
import pandas as pd

from thermaxis.config import ModelSettings, SelectionSettings
from thermaxis.method.metrics import METRIC_COLUMNS
from thermaxis.sweep.plan import Unit
from thermaxis.sweep_grid import FACTORS, LEVEL_ORDER, Configuration, SelectionSpec, SweepGrid
from thermaxis.tables import read_table as read_labelled

__all__ = [
    "SUMMARY_COLUMNS",
    "RANKING_COLUMNS",
    "Progress",
    "run_batch",
    "read_sweep_table",
    "collect_summary",
    "rank_configurations",
    "factor_effects",
    "factor_levels",
    "heatmap_table",
    "main_configuration_mask",
]

log = logging.getLogger("thermaxis")

SUMMARY_COLUMNS = ("config_id", *FACTORS, "fold", "target", *METRIC_COLUMNS, "sensors", "status")
RANKING_COLUMNS = (
    "rank",
    "config_id",
    *FACTORS,
    "mean_max_abs",
    "mean_rmse",
    "worst_max_abs",
    "n_folds",
    "main_config",
)
_INTEGER_FACTORS = ("n_clusters", "degree")


class Progress:
    """A tqdm-like progress line on stderr, at most every ``every_s`` seconds and at the end.

    Whole lines, not carriage returns: batches run side by side and Snakemake
    interleaves their output.
    """

    def __init__(
        self,
        total: int,
        label: str,
        stream=None,
        every_s: float = 2.0,
        clock: Callable[[], float] = time.monotonic,
    ):
        self.total, self.label, self.every_s, self.clock = int(total), label, every_s, clock
        self.stream = stream if stream is not None else sys.stderr
        self.done = 0
        self.start = self._last = clock()

    def line(self) -> str:
        elapsed = self.clock() - self.start
        fraction = self.done / self.total if self.total else 1.0
        bar = "#" * int(20 * fraction)
        rate = self.done / elapsed if elapsed > 0 else float("nan")
        left = (self.total - self.done) / rate if rate and rate > 0 else float("nan")
        return (
            f"{self.label}: {100 * fraction:3.0f}%|{bar:<20}| {self.done}/{self.total} "
            f"[{_clock_text(elapsed)}<{_clock_text(left)}, {rate:.1f} config/s]"
        )

    def update(self, n: int = 1) -> None:
        self.done += n
        now = self.clock()
        if self.done >= self.total or now - self._last >= self.every_s:
            self._last = now
            print(self.line(), file=self.stream, flush=True)


def _clock_text(seconds: float) -> str:
    if not math.isfinite(seconds):
        return "?"
    minutes, secs = divmod(int(round(seconds)), 60)
    return f"{minutes:02d}:{secs:02d}"


# --------------------------------------------------------------------------- evaluation


def _model_inputs_of(selection, approach: str) -> tuple:
    """The sensors the model of ``approach`` reads: what makes two evaluations equal.

    Must follow thermaxis.method.folds.build_model: decoupled models read the k and b
    points, pointwise models the common set.
    """
    if approach == "decoupled":
        return ("k", selection.k_sensors, "b", selection.b_sensors)
    return ("error", selection.pointwise)


def _sensors_text(inputs: tuple) -> str:
    return ";".join(f"{inputs[i]}={'+'.join(inputs[i + 1])}" for i in range(0, len(inputs), 2))


def _unit_selections(
    X, Y, unit: Unit, grid: SweepGrid, base: SelectionSettings, decoupled: bool, relative
) -> dict:
    """The unit's selections: {degree: FoldSelection} for decoupled, {None: ...} for pointwise.

    A selection the data cannot support is kept as its one-line error message, so
    only the configurations that need it fail.  ``relative``: X's relative temperatures,
    computed once per batch (an exhaustive subset search selects thousands of times).
    """
    from thermaxis.method.folds import select_for_fold

    pairs = grid.approach_degrees(decoupled)
    degrees = sorted({d for _, d in pairs if d is not None})
    wants_pointwise = any(d is None for _, d in pairs)
    out: dict = {}
    for degree in degrees:
        # The point-by-point points do not depend on the degree: selected once, with
        # the first degree whose selection succeeds.
        with_pointwise = wants_pointwise and None not in out
        settings = unit.selection.settings(base, grid.fixed)
        try:
            out[degree] = select_for_fold(
                X,
                Y,
                unit.fold,
                settings,
                degree,
                decoupled=True,
                pointwise=with_pointwise,
                relative=relative,
                cap_clusters=False,
            )
        except ValueError as exc:
            out[degree] = f"selection failed: {str(exc).splitlines()[0]}"
            continue
        if with_pointwise:
            out[None] = out[degree]
    if wants_pointwise and None not in out:
        settings = unit.selection.settings(base, grid.fixed)
        try:
            out[None] = select_for_fold(
                X, Y, unit.fold, settings, None, decoupled=False, relative=relative,
                cap_clusters=False,
            )  # fmt: skip
        except ValueError as exc:
            out[None] = f"selection failed: {str(exc).splitlines()[0]}"
    return out


def _evaluate(
    X, Y, fold: str, config: Configuration, selection, model: ModelSettings
) -> pd.DataFrame | str:
    """The metrics of one evaluation, or its one-line error message."""
    from thermaxis.method.folds import fold_metrics

    try:
        return fold_metrics(
            X, Y, fold, config.approach, config.algorithm, selection, model, config.degree
        )
    except ValueError as exc:
        return str(exc).splitlines()[0]


def _evaluate_batched(X, Y, deferred: dict, model: ModelSettings) -> dict:
    """The deferred linear evaluations, every point set of a (fold, approach, algorithm,
    degree) in one call of the numpy core; one-by-one where the data stops a group."""
    from thermaxis.method.batched import decoupled_metrics, pointwise_metrics

    groups: dict[tuple, list] = {}
    for key in deferred:
        groups.setdefault(key[:4], []).append(key)
    out = {}
    for (fold, approach, algorithm, degree), keys in groups.items():
        try:
            if approach == "decoupled":
                pairs = [(key[4][1], key[4][3]) for key in keys]
                frames = decoupled_metrics(X, Y, fold, algorithm, model, degree, pairs)
            else:
                frames = pointwise_metrics(X, Y, fold, algorithm, model, [k[4][1] for k in keys])
            out.update(zip(keys, frames, strict=True))
        except ValueError:
            # The one-by-one path says which evaluation failed and why, as it always has.
            out.update({key: _evaluate(X, Y, fold, *deferred[key], model) for key in keys})
    return out


def _config_rows(
    config: Configuration,
    fold: str,
    inputs: tuple,
    outcome,
    how: str = "fitted",
    seconds: float = 0.0,
) -> list[dict]:
    """Summary rows of one configuration on one fold, and its log line."""
    label = {"config_id": config.config_id, **config.factors(), "fold": fold}
    if isinstance(outcome, str):
        log.warning("%s fold %s: failed: %s", config.config_id, fold, outcome)
        return [{**label, "target": "error", "sensors": "", "status": outcome}]
    error = outcome.loc[outcome["target"] == "error", "max_abs"].iloc[0]
    log.info(
        "%s fold %s: max|residual| %.4g um (%s, %.2f s)",
        config.config_id, fold, error, how, seconds,
    )  # fmt: skip
    sensors = _sensors_text(inputs)
    # Column by column (Python values, as DataFrame.to_dict gives them): a subset search
    # makes thousands of these rows, and to_dict's per-row boxing was a quarter of its time.
    columns = ("target", *METRIC_COLUMNS)
    return [
        {**label, **dict(zip(columns, values, strict=True)), "sensors": sensors, "status": "ok"}
        for values in zip(*(outcome[c].tolist() for c in columns), strict=True)
    ]


def run_batch(
    X: pd.DataFrame,
    Y: pd.DataFrame,
    units: Iterable[Unit],
    grid: SweepGrid,
    base_selection: SelectionSettings,
    model: ModelSettings,
    decoupled: bool = True,
    progress: Progress | None = None,
) -> pd.DataFrame:
    """Evaluate every configuration of ``units`` on its fold; one row per target.

    Parameters
    ----------
    X, Y : DataFrame
        :func:`thermaxis.cleaning.run.model_inputs` of the assembled tables.
    units : iterable of Unit
    grid : SweepGrid
        Approaches, degrees and algorithms evaluated for every unit.
    base_selection : thermaxis.config.SelectionSettings
        Settings the sweep does not vary (scope, rho, normalisation, pointwise_common,
        and ``fixed`` for method "fixed").
    model : thermaxis.config.ModelSettings
        With the sweep's SVR grid (:meth:`thermaxis.config.SweepSettings.models`).
    decoupled : bool
        False for a dataset with a single target position (pointwise only).
    progress : Progress, optional
        Advanced once per configuration and fold.

    Returns
    -------
    DataFrame
        :data:`SUMMARY_COLUMNS`, metrics unrounded.  A configuration that cannot be
        evaluated on a fold (e.g. a selection the data cannot support) gives one row
        with NaN metrics and the reason in ``status``, instead of stopping the sweep.

    Linear evaluations (:func:`thermaxis.method.batched.batchable`) are deferred and
    made at the end, all point sets of a fold and model at once
    (:mod:`thermaxis.method.batched`, equal to the one-by-one fits to 1e-9).
    """
    from thermaxis.method.batched import batchable
    from thermaxis.method.features import relative_temperatures

    relative = relative_temperatures(X)
    # Whether an algorithm is batched depends on the data and the settings only: asked once.
    batched = {algorithm: batchable(algorithm, model, Y) for algorithm in grid.algorithms}
    planned: list[tuple] = []
    done: dict[tuple, pd.DataFrame | str] = {}
    deferred: dict[tuple, tuple] = {}
    seconds: dict[tuple, float] = {}
    for unit in units:
        selections = _unit_selections(X, Y, unit, grid, base_selection, decoupled, relative)
        for config in grid.unit_configurations(unit.selection, decoupled):
            selection = selections[config.degree]
            planned.append(_planned(config, unit.fold, selection))
            key = planned[-1][3]
            # Each fit is made once: a key seen again (same fold, model and inputs) is reused.
            new = key is not None and key not in done and key not in deferred
            if new and batched[config.algorithm]:
                deferred[key] = (config, selection)
            elif new:
                started = time.perf_counter()
                done[key] = _evaluate(X, Y, unit.fold, config, selection, model)
                seconds[key] = time.perf_counter() - started
            if progress is not None:
                progress.update()
    done.update(_evaluate_batched(X, Y, deferred, model))
    return _as_summary_frame(_planned_rows(planned, done, deferred, seconds))


def _planned(config, fold: str, selection) -> tuple:
    """(config, fold, inputs, key of its fit, failure): a selection that failed has no fit."""
    if isinstance(selection, str):
        return (config, fold, (), None, selection)
    inputs = _model_inputs_of(selection, config.approach)
    return (
        config,
        fold,
        inputs,
        (fold, config.approach, config.algorithm, config.degree, inputs),
        None,
    )


def _planned_rows(planned: list[tuple], done: dict, deferred: dict, seconds: dict) -> list[dict]:
    """The summary rows in the planned order, each saying how its fit was made."""
    rows: list[dict] = []
    seen: set[tuple] = set()
    for config, fold, inputs, key, failure in planned:
        if key is None:
            rows += _config_rows(config, fold, inputs, failure)
            continue
        how = "reused" if key in seen else "batched" if key in deferred else "fitted"
        rows += _config_rows(config, fold, inputs, done[key], how, seconds.get(key, 0.0))
        seen.add(key)
    return rows


def _as_summary_frame(rows: list[dict]) -> pd.DataFrame:
    frame = pd.DataFrame(rows, columns=list(SUMMARY_COLUMNS))
    for name in _INTEGER_FACTORS:
        frame[name] = frame[name].astype("Int64")
    for name in METRIC_COLUMNS:
        frame[name] = frame[name].astype(float)
    return frame


# --------------------------------------------------------------------------- summary and ranking


def read_sweep_table(path) -> pd.DataFrame:
    """summary.csv or ranking.csv with the integer factors as nullable integers (empty = n/a)."""
    return read_labelled(path, dtype={name: "Int64" for name in _INTEGER_FACTORS})


def collect_summary(frames: Iterable[pd.DataFrame]) -> pd.DataFrame:
    """All batches' rows in one table, sorted by configuration, fold and target."""
    frames = [f for f in frames if len(f)]
    if not frames:
        raise ValueError("sweep: the batches hold no rows; expected at least one configuration")
    summary = pd.concat(frames, ignore_index=True)
    summary = _as_summary_frame(summary.to_dict("records"))
    duplicated = summary.duplicated(["config_id", "fold", "target"])
    if duplicated.any():
        row = summary.loc[duplicated].iloc[0]
        raise ValueError(
            f"sweep: configuration {row['config_id']} fold {row['fold']} appears in two batches"
        )
    return summary.sort_values(["config_id", "fold", "target"], kind="stable", ignore_index=True)


def main_configuration_mask(
    frame: pd.DataFrame, selection: SelectionSettings, degree: int
) -> pd.Series:
    """Rows of the main workflow's configuration (config ``selection`` and ``decoupling``).

    The selection method's own factors must match; the degree matters for the decoupled
    approach only.  Every algorithm and approach of the main configuration is marked.
    """
    spec = SelectionSpec.of(selection)
    same = frame["method"] == spec.method
    for name in ("n_clusters", "similarity", "grade"):
        value = getattr(spec, name)
        same &= frame[name].isna() if value is None else (frame[name] == value).fillna(False)
    same_degree = (frame["approach"] == "pointwise") | (frame["degree"] == degree).fillna(False)
    return (same & same_degree).astype(bool)


def rank_configurations(
    summary: pd.DataFrame, main_selection: SelectionSettings, main_degree: int
) -> pd.DataFrame:
    """Configurations ranked by their mean held-out max |residual| of the error curves.

    The mean is over folds; a configuration that failed on any fold is ranked after
    all complete ones (its mean is over fewer folds and would flatter it).  Means that
    agree to 9 significant digits are ties: two models that are the same fit (PLS with as
    many components as sensors is MLR) differ only by rounding, which the order must
    not depend on.  Ties are broken by the configuration id, so the order is deterministic.
    """
    errors = summary[summary["target"] == "error"]
    n_folds = errors["fold"].nunique()
    grouped = errors.groupby("config_id", sort=True)
    table = grouped[list(FACTORS)].first()
    table["mean_max_abs"] = grouped["max_abs"].mean()
    table["mean_rmse"] = grouped["rmse"].mean()
    table["worst_max_abs"] = grouped["max_abs"].max()
    table["n_folds"] = grouped["max_abs"].count().astype(int)
    table = table.reset_index()
    complete = table["n_folds"] == n_folds
    table = (
        table.assign(
            _incomplete=~complete, _mean=table["mean_max_abs"].map(lambda v: float(f"{v:.9g}"))
        )
        .sort_values(["_incomplete", "_mean", "config_id"], kind="stable", na_position="last")
        .drop(columns=["_incomplete", "_mean"])
        .reset_index(drop=True)
    )
    table.insert(0, "rank", np.arange(1, len(table) + 1))
    table["main_config"] = main_configuration_mask(table, main_selection, main_degree)
    for name in _INTEGER_FACTORS:
        table[name] = table[name].astype("Int64")
    return table[list(RANKING_COLUMNS)]


def factor_effects(ranking: pd.DataFrame) -> pd.DataFrame:
    """Per factor and level: how many configurations, and their mean max |residual| spread.

    Only configurations where the factor applies (non-empty) and that are complete
    over all folds are counted.  Columns: factor, level, n_configurations, best,
    median, mean, worst (of the configurations' fold-mean max |residual|, um).
    """
    complete = ranking[ranking["n_folds"] == ranking["n_folds"].max()]
    rows = []
    for factor in FACTORS:
        values = complete[[factor, "mean_max_abs"]].dropna(subset=[factor])
        for level in factor_levels(values[factor], factor):
            v = values.loc[values[factor] == level, "mean_max_abs"].to_numpy(dtype=float)
            rows.append(
                {"factor": factor, "level": str(level), "n_configurations": len(v), "best": v.min(),
                 "median": float(np.median(v)), "mean": v.mean(), "worst": v.max()}
            )  # fmt: skip
    return pd.DataFrame(
        rows, columns=["factor", "level", "n_configurations", "best", "median", "mean", "worst"]
    )


def factor_levels(values: pd.Series, factor: str) -> list:
    """The levels present, in the order of :data:`LEVEL_ORDER` (integers ascending)."""
    present = list(dict.fromkeys(values.tolist()))
    if factor in LEVEL_ORDER:
        order = {level: i for i, level in enumerate(LEVEL_ORDER[factor])}
        return sorted(present, key=lambda v: (order.get(v, len(order)), str(v)))
    return sorted(present)


def heatmap_table(
    ranking: pd.DataFrame, approach: str, selection: SelectionSettings, degree: int
) -> pd.DataFrame:
    """Mean held-out max |residual| over n_clusters (rows) x algorithm (columns) for one approach.

    The cluster count is swept by fuzzy_grey (else correlation) selection; the other
    selection factors are held at the main configuration's values where the grid has
    them (else at the grid's first level), as is the degree of the decoupled approach.
    ``attrs["held"]`` says what was held, e.g. ``"fuzzy_grey, pearson, deng, degree 1"``.
    """
    rows = ranking[ranking["approach"] == approach]
    method = "fuzzy_grey" if (rows["method"] == "fuzzy_grey").any() else "correlation"
    rows = rows[rows["method"] == method]
    held = [method]
    names = ("similarity", "grade") if method == "fuzzy_grey" else ()
    if approach == "decoupled":
        names += ("degree",)
    wanted_values = {"similarity": selection.similarity, "grade": selection.grade, "degree": degree}
    for name in names:
        present = factor_levels(rows[name].dropna(), name)
        if not present:
            continue
        wanted = wanted_values.get(name) if wanted_values.get(name) in present else present[0]
        rows = rows[(rows[name] == wanted).fillna(False)]
        held.append(f"degree {wanted}" if name == "degree" else str(wanted))
    table = rows.pivot_table(
        index="n_clusters", columns="algorithm", values="mean_max_abs", aggfunc="first", sort=True
    )
    table = table[factor_levels(pd.Series(table.columns), "algorithm")]
    table.index = table.index.astype(int)
    table.attrs["held"] = ", ".join(held)
    return table
