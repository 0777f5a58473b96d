"""Sweeps: many configurations x every leave-one-condition-out fold, evaluated in batches.

A *configuration* is one choice of sensitive-point selection (method, number of
clusters, similarity, grey grade), approach (decoupled or point-by-point), decoupling
degree and algorithm.  Each is evaluated on every fold by
:func:`thermaxis.experiment.evaluate_configuration`, the function the main workflow's
``fit_predict`` rule calls: the sweep has no model code of its own.

How the cost is kept down
-------------------------
* Start-up and imports are paid per *batch*, not per configuration: a batch is one
  process that reads the assembled tables once and works through its share of the
  grid.
* Work is grouped in *units* (one fold x one selection setting).  A unit's sensitive
  points are selected once per decoupling degree and shared by every approach and
  algorithm; a unit lives in exactly one batch, so no selection is computed twice.
* Many selection settings pick the same sensors (the point-by-point common set has
  ``selection.pointwise_common`` sensors whatever the cluster count).  An evaluation depends on the selection
  only through the sensors its model uses, so within a batch the metrics of an
  identical (fold, approach, algorithm, degree, sensors) evaluation are reused.
  Units are cut into batches in fold order, which keeps a fold's units together.

Exhaustive subsets (method ``subset``): every subset of ``n`` sensors (``n`` from the
``n_clusters`` levels) is used as it stands for k, b and the point-by-point models, as
method ``fixed`` uses the paper's lists.  C(12, 3) = 220 subsets per size and fold is
why it wants a cluster: :func:`subset_count` caps it and :func:`cost_estimate` says
what it will cost before it starts.

Factors that do not apply to a configuration are left empty (None): n_clusters for
``all`` and ``fixed``; similarity and grade for every method but ``fuzzy_grey``; the
degree for the point-by-point approach, which never decouples.

This module imports no scikit-learn at import time, so the workflow can plan a sweep
while it parses the Snakefile.
"""

from __future__ import annotations

import itertools
import logging
import math
import sys
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np
import pandas as pd

__all__ = [
    "FACTORS",
    "METRICS",
    "SUMMARY_COLUMNS",
    "RANKING_COLUMNS",
    "SelectionSpec",
    "Configuration",
    "SweepGrid",
    "Unit",
    "grid_from_config",
    "svr_grid_for_sweep",
    "plan_units",
    "batch_count",
    "cluster_batch_count",
    "batch_minutes",
    "subset_count",
    "cost_estimate",
    "batch_units",
    "Progress",
    "run_batch",
    "read_table",
    "collect_summary",
    "rank_configurations",
    "factor_effects",
    "heatmap_table",
    "main_configuration_mask",
    "fig_sweep_heatmap",
    "fig_factor_effects",
]

log = logging.getLogger("thermaxis")

FACTORS = ("method", "n_clusters", "similarity", "grade", "approach", "degree", "algorithm")
# The same names and order as thermaxis.evaluate.METRIC_COLUMNS (not imported: that
# module pulls in scikit-learn, and this one is imported while the workflow parses).
METRICS = ("rmse", "max_abs", "mae", "residual_min", "residual_max")
SUMMARY_COLUMNS = ("config_id", *FACTORS, "fold", "target", *METRICS, "sensors", "status")
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
# "subset" (exhaustive) is asked for by name; a grid without methods sweeps the others.
DEFAULT_METHODS = ("fuzzy_grey", "correlation", "all", "fixed")
METHODS = (*DEFAULT_METHODS, "subset")
APPROACHES = ("decoupled", "pointwise")
_INTEGER_FACTORS = ("n_clusters", "degree")
# Order of the levels in tables and figures: the paper's choice first.
LEVEL_ORDER = {
    "method": METHODS,
    "similarity": ("pearson", "printed"),
    "grade": ("deng", "absolute"),
    "approach": APPROACHES,
    "algorithm": ("mlr", "svr", "ridge", "pls", "gpr"),
}


# --------------------------------------------------------------------------- the grid


@dataclass(frozen=True)
class SelectionSpec:
    """The selection part of a configuration; None where a factor does not apply."""

    method: str
    n_clusters: int | None = None
    similarity: str | None = None
    grade: str | None = None
    sensors: tuple[str, ...] = ()  # method "subset": the subset, for every target

    @property
    def label(self) -> str:
        parts = [self.method]
        if self.n_clusters is not None:
            parts.append(f"n{self.n_clusters}")
        parts += [p for p in (self.similarity, self.grade) if p is not None]
        if self.sensors:
            parts.append("+".join(self.sensors))
        return ":".join(parts)

    def settings(self, base, degree: int, fixed: tuple = ()):
        """``base`` (a :class:`thermaxis.experiment.SelectionSettings`) with this spec applied.

        Factors that do not apply keep the base value: they are unused by the method.
        ``fixed`` (the grid's sensor lists) replaces the base's for method "fixed".
        """
        changes = {"method": self.method, "degree": int(degree)}
        if self.method == "fixed":
            changes["fixed"] = tuple(fixed)
        if self.method == "subset":
            # A subset is a fixed choice made by the sweep: the same sensors for every target.
            changes["method"] = "fixed"
            changes["fixed"] = tuple((target, self.sensors) for target in ("b", "k", "pointwise"))
        for name in ("n_clusters", "similarity", "grade"):
            value = getattr(self, name)
            if value is not None:
                changes[name] = value
        return replace(base, **changes)


@dataclass(frozen=True)
class Configuration:
    """One point of the grid: selection, approach, degree (None for pointwise), algorithm."""

    selection: SelectionSpec
    approach: str
    degree: int | None
    algorithm: str

    @property
    def config_id(self) -> str:
        approach = self.approach if self.degree is None else f"{self.approach}:d{self.degree}"
        return f"{self.selection.label}/{approach}/{self.algorithm}"

    def factors(self) -> dict:
        s = self.selection
        return {
            "method": s.method,
            "n_clusters": s.n_clusters,
            "similarity": s.similarity,
            "grade": s.grade,
            "approach": self.approach,
            "degree": self.degree,
            "algorithm": self.algorithm,
        }


@dataclass(frozen=True)
class SweepGrid:
    """The levels of every factor (config ``sweep``), in the order they are swept."""

    methods: tuple[str, ...] = DEFAULT_METHODS
    n_clusters: tuple[int, ...] = (2, 3, 4, 5, 6)
    similarities: tuple[str, ...] = ("pearson", "printed")
    grades: tuple[str, ...] = ("deng", "absolute")
    approaches: tuple[str, ...] = APPROACHES
    degrees: tuple[int, ...] = (1, 2, 3)
    algorithms: tuple[str, ...] = ("mlr", "svr", "ridge", "pls", "gpr")
    fixed: tuple = ()  # ((target, (sensor, ...)), ...) for method "fixed"
    max_subsets: int = 1000  # method "subset": more subsets than this stop the plan

    def selection_specs(self, sensors: Sequence[str]) -> tuple[list[SelectionSpec], list[str]]:
        """Selection settings the dataset allows, and one note per setting left out.

        A cluster (or ranking) count above the number of sensors cannot be asked for;
        ``fixed`` needs every listed sensor in the dataset.
        """
        n_sensors = len(sensors)
        specs, notes = [], []
        for method in self.methods:
            if method == "fuzzy_grey":
                for n in self.n_clusters:
                    if n > n_sensors:
                        notes.append(f"fuzzy_grey with {n} clusters: the dataset has only {n_sensors} sensors")
                        continue
                    specs += [SelectionSpec(method, n, s, g) for s in self.similarities for g in self.grades]
            elif method == "correlation":
                for n in self.n_clusters:
                    if n > n_sensors:
                        notes.append(f"correlation ranking of {n} sensors: the dataset has only {n_sensors} sensors")
                        continue
                    specs.append(SelectionSpec(method, n))
            elif method == "subset":
                count = subset_count(n_sensors, self.n_clusters)
                if count > self.max_subsets:
                    raise ValueError(
                        f"config sweep: method subset would evaluate {count} subsets of "
                        f"{'/'.join(map(str, self.n_clusters))} of {n_sensors} sensors; "
                        f"the cap sweep.max_subsets is {self.max_subsets}"
                    )
                for n in self.n_clusters:
                    if n > n_sensors:
                        notes.append(f"subsets of {n} sensors: the dataset has only {n_sensors} sensors")
                        continue
                    specs += [SelectionSpec(method, n, sensors=c) for c in itertools.combinations(sensors, n)]
            elif method == "fixed":
                wanted = sorted({s for _, chosen in self.fixed for s in chosen})
                missing = [s for s in wanted if s not in sensors]
                if not self.fixed:
                    notes.append("fixed: config sweep.fixed lists no sensors")
                elif missing:
                    notes.append(f"fixed: sensor(s) {', '.join(missing)} of sweep.fixed are not in the dataset")
                else:
                    specs.append(SelectionSpec(method))
            else:
                specs.append(SelectionSpec(method))
        return specs, notes

    def approach_degrees(self, decoupled: bool = True) -> list[tuple[str, int | None]]:
        """(approach, degree) pairs; without a decoupled branch only the pointwise one."""
        pairs = []
        for approach in self.approaches:
            if approach == "decoupled" and decoupled:
                pairs += [("decoupled", d) for d in self.degrees]
            elif approach == "pointwise":
                pairs.append(("pointwise", None))
        return pairs

    def unit_configurations(self, spec: SelectionSpec, decoupled: bool = True) -> list[Configuration]:
        return [
            Configuration(spec, approach, degree, algorithm)
            for approach, degree in self.approach_degrees(decoupled)
            for algorithm in self.algorithms
        ]

    def configurations(self, sensors: Sequence[str], decoupled: bool = True) -> list[Configuration]:
        """Every configuration of the grid the dataset allows, in sweep order."""
        specs, _ = self.selection_specs(sensors)
        return [c for spec in specs for c in self.unit_configurations(spec, decoupled)]


def grid_from_config(sweep: Mapping) -> SweepGrid:
    """The grid of config ``sweep`` (validated by the workflow schema, defaults filled)."""
    fixed = sweep.get("fixed", {}) or {}
    return SweepGrid(
        methods=tuple(sweep["methods"]),
        n_clusters=tuple(int(n) for n in sweep["n_clusters"]),
        similarities=tuple(sweep["similarity"]),
        grades=tuple(sweep["grade"]),
        approaches=tuple(sweep["approaches"]),
        degrees=tuple(int(d) for d in sweep["degrees"]),
        algorithms=tuple(sweep["algorithms"]),
        fixed=tuple(sorted((k, tuple(v)) for k, v in fixed.items())),
        max_subsets=int(sweep["max_subsets"]),
    )


def svr_grid_for_sweep(sweep: Mapping, models: Mapping) -> dict:
    """The SVR search grid of the sweep: its own (``sweep.svr_grid``) or ``"models"``'s."""
    grid = sweep["svr_grid"]
    return dict(models["svr_grid"]) if grid == "models" else dict(grid)


# --------------------------------------------------------------------------- batches


@dataclass(frozen=True)
class Unit:
    """One fold x one selection setting: the work that shares one set of selections."""

    fold: str
    selection: SelectionSpec


def plan_units(grid: SweepGrid, folds: Sequence[str], sensors: Sequence[str]) -> tuple[list[Unit], list[str]]:
    """Units in fold order, then grid order, and the notes of settings left out."""
    specs, notes = grid.selection_specs(sensors)
    return [Unit(fold, spec) for fold in folds for spec in specs], notes


def batch_count(requested: int, cores: int | None, n_units: int) -> int:
    """How many batches: ``requested`` if positive, else one per core; never more than units."""
    if requested < 0:
        raise ValueError(f"config sweep.batches: expected 0 (one per core) or a positive count, got {requested}")
    wanted = requested if requested > 0 else (cores or 1)
    return max(1, min(int(wanted), max(n_units, 1)))


def cluster_batch_count(requested: int, evaluations_per_unit: Sequence[int], per_batch: int) -> int:
    """Batches on a cluster: ``requested`` if positive, else one per ``per_batch`` evaluations.

    An evaluation is one configuration on one fold.  Never more batches than units
    (a unit is not split) nor fewer than one.
    """
    if requested > 0:
        wanted = requested
    else:
        wanted = math.ceil(sum(evaluations_per_unit) / per_batch)
    return max(1, min(int(wanted), max(len(evaluations_per_unit), 1)))


def batch_minutes(
    grid: SweepGrid, units: Sequence[Unit], n_batches: int, batch: int, seconds_per_evaluation: float, decoupled: bool = True
) -> int:
    """Time limit (minutes) of one batch job: its evaluations at the given cost, with the
    headroom :func:`thermaxis.resources.request` gives every rule."""
    from .resources import request

    evaluations = sum(len(grid.unit_configurations(u.selection, decoupled)) for u in batch_units(units, n_batches, batch))
    return request(evaluations * seconds_per_evaluation, 0.0)[1]


def subset_count(n_sensors: int, sizes: Iterable[int]) -> int:
    """How many sensor subsets of the given sizes: the sum of C(n_sensors, n)."""
    return sum(math.comb(n_sensors, n) for n in set(sizes) if n <= n_sensors)


def cost_estimate(n_evaluations: int, seconds_per_evaluation: float, workers: int) -> dict:
    """CPU time of a sweep and its wall time on ``workers`` parallel single-core batches.

    The wall time assumes the evaluations split evenly and ignores start-up and
    scheduling; it is a lower bound a plan can be checked against.
    """
    cpu_s = n_evaluations * seconds_per_evaluation
    return {
        "evaluations": int(n_evaluations),
        "seconds_per_evaluation": float(seconds_per_evaluation),
        "cpu_hours": cpu_s / 3600.0,
        "workers": int(workers),
        "wall_minutes": cpu_s / max(int(workers), 1) / 60.0,
    }


def batch_units(units: Sequence[Unit], n_batches: int, batch: int) -> list[Unit]:
    """The units of batch ``batch`` (0-based): contiguous, near-equal shares in unit order.

    Contiguous shares keep a fold's units together, so that evaluations repeated
    across selection settings are found within one batch.
    """
    if not 0 <= batch < n_batches:
        raise ValueError(f"batch {batch} does not exist; expected 0 to {n_batches - 1}")
    bounds = np.linspace(0, len(units), n_batches + 1).round().astype(int)
    return list(units[bounds[batch] : bounds[batch + 1]])


class Progress:
    """A tqdm-like progress line on stderr, at most every ``every_s`` seconds and at the end.

    Whole lines, not carriage returns: batches run side by side and Snakemake
    interleaves their output.
    """

    def __init__(self, total: int, label: str, stream=None, every_s: float = 2.0, clock: Callable[[], float] = time.monotonic):
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


def _display(label) -> str:
    from .plotting import DISPLAY_NAMES

    return DISPLAY_NAMES.get(str(label), str(label))


def _clock_text(seconds: float) -> str:
    if not math.isfinite(seconds):
        return "?"
    minutes, secs = divmod(int(round(seconds)), 60)
    return f"{minutes:02d}:{secs:02d}"


# --------------------------------------------------------------------------- evaluation


def _model_inputs_of(selection, approach: str) -> tuple:
    """The sensors the model of ``approach`` reads: what makes two evaluations equal.

    Must follow thermaxis.experiment._build_model: decoupled models read the k and b
    points, pointwise models the common set.
    """
    if approach == "decoupled":
        return ("k", selection.k_sensors, "b", selection.b_sensors)
    return ("error", selection.pointwise)


def _sensors_text(inputs: tuple) -> str:
    return ";".join(f"{inputs[i]}={'+'.join(inputs[i + 1])}" for i in range(0, len(inputs), 2))


def _unit_selections(X, Y, unit: Unit, grid: SweepGrid, base, decoupled: bool) -> dict:
    """The unit's selections: {degree: FoldSelection} for decoupled, {None: ...} for pointwise.

    A selection the data cannot support is kept as its one-line error message, so
    only the configurations that need it fail.
    """
    from .experiment import select_for_fold

    pairs = grid.approach_degrees(decoupled)
    degrees = sorted({d for _, d in pairs if d is not None})
    wants_pointwise = any(d is None for _, d in pairs)
    out: dict = {}
    for degree in degrees:
        # The point-by-point points do not depend on the degree: selected once, with
        # the first degree whose selection succeeds.
        with_pointwise = wants_pointwise and None not in out
        settings = unit.selection.settings(base, degree, grid.fixed)
        try:
            out[degree] = select_for_fold(X, Y, unit.fold, settings, decoupled=True, pointwise=with_pointwise)
        except ValueError as exc:
            out[degree] = f"selection failed: {str(exc).splitlines()[0]}"
            continue
        if with_pointwise:
            out[None] = out[degree]
    if wants_pointwise and None not in out:
        settings = unit.selection.settings(base, base.degree, grid.fixed)
        try:
            out[None] = select_for_fold(X, Y, unit.fold, settings, decoupled=False)
        except ValueError as exc:
            out[None] = f"selection failed: {str(exc).splitlines()[0]}"
    return out


def _evaluate(X, Y, fold: str, config: Configuration, selection, model, degree: int) -> pd.DataFrame | str:
    """The metrics of one evaluation, or its one-line error message."""
    from .experiment import evaluate_configuration

    try:
        return evaluate_configuration(X, Y, fold, config.approach, config.algorithm, selection, model, degree=degree).metrics
    except ValueError as exc:
        return str(exc).splitlines()[0]


def _config_rows(config: Configuration, fold: str, inputs: tuple, outcome, reused: bool = False, seconds: float = 0.0) -> list[dict]:
    """Summary rows of one configuration on one fold, and its log line."""
    label = {"config_id": config.config_id, **config.factors(), "fold": fold}
    if isinstance(outcome, str):
        log.warning("%s fold %s: failed: %s", config.config_id, fold, outcome)
        return [{**label, "target": "error", "sensors": "", "status": outcome}]
    error = outcome.loc[outcome["target"] == "error", "max_abs"].iloc[0]
    log.info(
        "%s fold %s: max|residual| %.4g um (%s, %.2f s)",
        config.config_id, fold, error, "reused" if reused else "fitted", seconds,
    )  # fmt: skip
    sensors = _sensors_text(inputs)
    return [
        {**label, "target": r["target"], **{m: r[m] for m in METRICS}, "sensors": sensors, "status": "ok"}
        for r in outcome.to_dict("records")
    ]


def run_batch(
    X: pd.DataFrame,
    Y: pd.DataFrame,
    units: Iterable[Unit],
    grid: SweepGrid,
    base_selection,
    model,
    decoupled: bool = True,
    progress: Progress | None = None,
) -> pd.DataFrame:
    """Evaluate every configuration of ``units`` on its fold; one row per target.

    Parameters
    ----------
    X, Y : DataFrame
        :func:`thermaxis.assemble.model_inputs` of the assembled tables.
    units : iterable of Unit
    grid : SweepGrid
        Approaches, degrees and algorithms evaluated for every unit.
    base_selection : thermaxis.experiment.SelectionSettings
        Settings the sweep does not vary (scope, rho, normalisation, pointwise_common,
        and ``fixed`` for method "fixed").
    model : thermaxis.experiment.ModelSettings
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
    """
    rows: list[dict] = []
    done: dict[tuple, pd.DataFrame | str] = {}
    for unit in units:
        selections = _unit_selections(X, Y, unit, grid, base_selection, decoupled)
        for config in grid.unit_configurations(unit.selection, decoupled):
            selection = selections[config.degree]
            if isinstance(selection, str):
                rows += _config_rows(config, unit.fold, (), selection)
            else:
                started = time.perf_counter()
                inputs = _model_inputs_of(selection, config.approach)
                key = (unit.fold, config.approach, config.algorithm, config.degree, inputs)
                reused = key in done
                if not reused:
                    degree = config.degree if config.degree is not None else base_selection.degree
                    done[key] = _evaluate(X, Y, unit.fold, config, selection, model, degree)
                rows += _config_rows(config, unit.fold, inputs, done[key], reused, time.perf_counter() - started)
            if progress is not None:
                progress.update()
    return _as_summary_frame(rows)


def _as_summary_frame(rows: list[dict]) -> pd.DataFrame:
    frame = pd.DataFrame(rows, columns=list(SUMMARY_COLUMNS))
    for name in _INTEGER_FACTORS:
        frame[name] = frame[name].astype("Int64")
    for name in METRICS:
        frame[name] = frame[name].astype(float)
    return frame


# --------------------------------------------------------------------------- summary and ranking


def read_table(path) -> pd.DataFrame:
    """summary.csv or ranking.csv with the integer factors as nullable integers (empty = n/a)."""
    return pd.read_csv(path, dtype={name: "Int64" for name in _INTEGER_FACTORS})


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
        raise ValueError(f"sweep: configuration {row['config_id']} fold {row['fold']} appears in two batches")
    return summary.sort_values(["config_id", "fold", "target"], kind="stable", ignore_index=True)


def main_configuration_mask(frame: pd.DataFrame, selection: Mapping, degree: int) -> pd.Series:
    """Rows of the main workflow's configuration (config ``selection`` and ``decoupling``).

    The selection method's own factors must match; the degree matters for the decoupled
    approach only.  Every algorithm and approach of the main configuration is marked.
    """
    spec = _spec_of(selection)
    same = frame["method"] == spec.method
    for name in ("n_clusters", "similarity", "grade"):
        value = getattr(spec, name)
        same &= frame[name].isna() if value is None else (frame[name] == value).fillna(False)
    same_degree = (frame["approach"] == "pointwise") | (frame["degree"] == degree).fillna(False)
    return (same & same_degree).astype(bool)


def _spec_of(selection: Mapping) -> SelectionSpec:
    method = selection["method"]
    if method == "fuzzy_grey":
        return SelectionSpec(method, int(selection["n_clusters"]), selection["similarity"], selection["grade"])
    if method == "correlation":
        return SelectionSpec(method, int(selection["n_clusters"]))
    return SelectionSpec(method)


def rank_configurations(summary: pd.DataFrame, main_selection: Mapping, main_degree: int) -> pd.DataFrame:
    """Configurations ranked by their mean held-out max |residual| of the error curves.

    The mean is over folds; a configuration that failed on any fold is ranked after
    all complete ones (its mean is over fewer folds and would flatter it).  Ties are
    broken by the configuration id, so the order is deterministic.
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
        table.assign(_incomplete=~complete)
        .sort_values(["_incomplete", "mean_max_abs", "config_id"], kind="stable", na_position="last")
        .drop(columns="_incomplete")
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
        for level in _levels(values[factor], factor):
            v = values.loc[values[factor] == level, "mean_max_abs"].to_numpy(dtype=float)
            rows.append(
                {"factor": factor, "level": str(level), "n_configurations": len(v), "best": v.min(),
                 "median": float(np.median(v)), "mean": v.mean(), "worst": v.max()}
            )  # fmt: skip
    return pd.DataFrame(rows, columns=["factor", "level", "n_configurations", "best", "median", "mean", "worst"])


def _levels(values: pd.Series, factor: str) -> list:
    """The levels present, in the order of :data:`LEVEL_ORDER` (integers ascending)."""
    present = list(dict.fromkeys(values.tolist()))
    if factor in LEVEL_ORDER:
        order = {level: i for i, level in enumerate(LEVEL_ORDER[factor])}
        return sorted(present, key=lambda v: (order.get(v, len(order)), str(v)))
    return sorted(present)


def heatmap_table(ranking: pd.DataFrame, approach: str, selection: Mapping, degree: int) -> pd.DataFrame:
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
    wanted_values = {**selection, "degree": degree}
    for name in names:
        present = _levels(rows[name].dropna(), name)
        if not present:
            continue
        wanted = wanted_values.get(name) if wanted_values.get(name) in present else present[0]
        rows = rows[(rows[name] == wanted).fillna(False)]
        held.append(f"degree {wanted}" if name == "degree" else str(wanted))
    table = rows.pivot_table(index="n_clusters", columns="algorithm", values="mean_max_abs", aggfunc="first", sort=True)
    table = table[_levels(pd.Series(table.columns), "algorithm")]
    table.index = table.index.astype(int)
    table.attrs["held"] = ", ".join(held)
    return table


# --------------------------------------------------------------------------- figures


def fig_sweep_heatmap(tables: Mapping[str, pd.DataFrame], titles: Mapping[str, str] | None = None):
    """Heat maps of mean held-out max |residual| (um), one panel per approach.

    Parameters
    ----------
    tables : mapping of approach to DataFrame
        :func:`heatmap_table` results (rows n_clusters, columns algorithms).
    titles : mapping of approach to str, optional
        Panel titles; default the approach and what :func:`heatmap_table` held fixed.

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib
    from matplotlib.figure import Figure

    from . import plotting

    tables = {k: v for k, v in tables.items() if v.size}
    if not tables:
        raise ValueError("sweep heat map: no configuration sweeps n_clusters; expected fuzzy_grey or correlation in sweep.methods")
    values = np.concatenate([t.to_numpy(dtype=float).ravel() for t in tables.values()])
    values = values[np.isfinite(values)]
    with matplotlib.rc_context(plotting.STYLE):
        fig = Figure(figsize=(plotting.DOUBLE_COLUMN_IN, 2.8), layout="constrained")
        axes = np.atleast_1d(fig.subplots(1, len(tables), sharey=True))
        norm = matplotlib.colors.Normalize(vmin=values.min(), vmax=values.max()) if values.size else None
        image = None
        for ax, (approach, table) in zip(axes, tables.items()):
            data = table.to_numpy(dtype=float)
            image = ax.imshow(data, cmap=plotting.ORDERED_CMAP, norm=norm, aspect="auto", origin="lower")
            ax.set_xticks(range(table.shape[1]), [_display(a) for a in table.columns])
            ax.set_yticks(range(table.shape[0]), [str(n) for n in table.index])
            ax.grid(False)
            threshold = norm.vmin + 0.6 * (norm.vmax - norm.vmin) if norm is not None else 0.0
            for (i, j), v in np.ndenumerate(data):
                if np.isfinite(v):
                    ax.text(j, i, f"{v:.2f}", ha="center", va="center", fontsize=6.5,
                            color="black" if v > threshold else "white")  # fmt: skip
            title = (titles or {}).get(approach) or f"{_display(approach)} ({table.attrs.get('held', '')})".replace(" ()", "")
            ax.set_title(title)
            ax.set_xlabel("Algorithm")
        axes[0].set_ylabel("Number of clusters")
        if image is not None:
            fig.colorbar(image, ax=list(axes), label="Mean held-out max |residual| (µm)", shrink=0.9)
    return fig


def fig_factor_effects(ranking: pd.DataFrame):
    """One panel per factor: the configurations' mean held-out max |residual| by level.

    Box plots (median, quartiles, whiskers to 1.5 IQR) over every complete
    configuration where the factor applies; the dots are the configurations.

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib
    from matplotlib.figure import Figure

    from . import plotting

    complete = ranking[ranking["n_folds"] == ranking["n_folds"].max()]
    factors = [f for f in FACTORS if complete[f].notna().any()]
    if not factors:
        raise ValueError("factor effects: the ranking has no complete configuration")
    ncols = min(4, len(factors))
    nrows = math.ceil(len(factors) / ncols)
    with matplotlib.rc_context(plotting.STYLE):
        fig = Figure(figsize=(plotting.DOUBLE_COLUMN_IN, 2.1 * nrows + 0.4), layout="constrained")
        axes = np.atleast_1d(fig.subplots(nrows, ncols, sharey=True)).ravel()
        for ax, factor in zip(axes, factors):
            values = complete[[factor, "mean_max_abs"]].dropna()
            levels = _levels(values[factor], factor)
            groups = [values.loc[values[factor] == level, "mean_max_abs"].to_numpy(dtype=float) for level in levels]
            ax.boxplot(groups, widths=0.55, showfliers=False, medianprops={"color": plotting.CATEGORICAL_COLORS[3]})
            jitter = np.random.default_rng(0)  # fixed seed: the same figure every run
            for i, g in enumerate(groups, start=1):
                offsets = jitter.uniform(-0.18, 0.18, len(g))
                ax.plot(i + offsets, g, ".", color=plotting.CATEGORICAL_COLORS[0], alpha=0.35, markersize=2.0)
            ax.set_xticks(range(1, len(levels) + 1), [_display(v) for v in levels],
                          rotation=30 if len(levels) > 3 else 0, ha="right" if len(levels) > 3 else "center")  # fmt: skip
            ax.set_title(factor.replace("_", " "))
            ax.grid(axis="x", visible=False)
        for ax in axes[len(factors):]:
            ax.set_visible(False)
        for row in range(nrows):
            axes[row * ncols].set_ylabel("Mean max |residual| (µm)")
    return fig
