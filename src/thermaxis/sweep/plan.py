"""Planning a sweep: the grid of configurations, its units and batches, and what it will cost.

A *configuration* is one choice of sensitive-point selection (method, number of
clusters, similarity, grey grade), approach (decoupled or point-by-point), decoupling
degree and algorithm; :mod:`thermaxis.sweep.run` evaluates them.

Work is grouped in *units* (one fold x one selection setting): a unit's sensitive
points are selected once per decoupling degree and shared by every approach and
algorithm, and a unit lives in exactly one batch (one process), so no selection is
computed twice. Units are cut into batches in fold order, which keeps a fold's units
together.

Exhaustive subsets (method ``subset``): every subset of ``n`` sensors (``n`` from the
``n_clusters`` levels) is used as it stands for k, b and the point-by-point models, as
method ``fixed`` uses the paper's lists.  C(12, 3) = 220 subsets per size and fold is
why it wants a cluster: :func:`subset_count` caps it and :func:`cost_estimate` says
what it will cost before it starts.

Factors that do not apply to a configuration are left empty (None): n_clusters for
``all`` and ``fixed``; similarity and grade for every method but ``fuzzy_grey``; the
degree for the point-by-point approach, which never decouples.

This module imports neither scikit-learn nor pandas, so the workflow can plan a sweep
while it parses the Snakefile.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, replace

import numpy as np

from thermaxis.vocabulary import ALGORITHMS, APPROACHES

__all__ = [
    "FACTORS",
    "LEVEL_ORDER",
    "SelectionSpec",
    "Configuration",
    "SweepGrid",
    "Unit",
    "plan_units",
    "batch_count",
    "cluster_batch_count",
    "batch_minutes",
    "subset_count",
    "cost_estimate",
    "cost_note",
    "batch_units",
]

FACTORS = ("method", "n_clusters", "similarity", "grade", "approach", "degree", "algorithm")
METHODS = ("fuzzy_grey", "correlation", "all", "fixed", "subset")
# Order of the levels in tables and figures: the paper's choice first.
LEVEL_ORDER = {
    "method": METHODS,
    "similarity": ("pearson", "printed"),
    "grade": ("deng", "absolute"),
    "approach": APPROACHES,
    "algorithm": ALGORITHMS,
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

    @classmethod
    def of(cls, selection) -> SelectionSpec:
        """The spec of a :class:`thermaxis.config.SelectionSettings` (the main configuration's)."""
        if selection.method == "fuzzy_grey":
            return cls(
                selection.method, selection.n_clusters, selection.similarity, selection.grade
            )
        if selection.method == "correlation":
            return cls(selection.method, selection.n_clusters)
        return cls(selection.method)

    def settings(self, base, fixed: tuple):
        """``base`` (a :class:`thermaxis.config.SelectionSettings`) with this spec applied.

        Factors that do not apply keep the base value: they are unused by the method.
        ``fixed`` (the grid's sensor lists) replaces the base's for method "fixed".
        """
        changes = {"method": self.method}
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
    """The levels of every factor (config ``sweep``, built by :class:`thermaxis.config.SweepSettings`)."""

    methods: tuple[str, ...]
    n_clusters: tuple[int, ...]
    similarities: tuple[str, ...]
    grades: tuple[str, ...]
    approaches: tuple[str, ...]
    degrees: tuple[int, ...]
    algorithms: tuple[str, ...]
    fixed: tuple  # ((target, (sensor, ...)), ...) for method "fixed"
    max_subsets: int  # method "subset": more subsets than this stop the plan

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
                        notes.append(
                            f"fuzzy_grey with {n} clusters: the dataset has only {n_sensors} sensors"
                        )
                        continue
                    specs += [
                        SelectionSpec(method, n, s, g)
                        for s in self.similarities
                        for g in self.grades
                    ]
            elif method == "correlation":
                for n in self.n_clusters:
                    if n > n_sensors:
                        notes.append(
                            f"correlation ranking of {n} sensors: the dataset has only {n_sensors} sensors"
                        )
                        continue
                    specs.append(SelectionSpec(method, n))
            elif method == "subset":
                self._check_subset_cap(n_sensors)
                for n in self.n_clusters:
                    if n > n_sensors:
                        notes.append(
                            f"subsets of {n} sensors: the dataset has only {n_sensors} sensors"
                        )
                        continue
                    specs += [
                        SelectionSpec(method, n, sensors=c)
                        for c in itertools.combinations(sensors, n)
                    ]
            elif method == "fixed":
                note = self._fixed_note(sensors)
                if note:
                    notes.append(note)
                else:
                    specs.append(SelectionSpec(method))
            else:
                specs.append(SelectionSpec(method))
        return specs, notes

    def _check_subset_cap(self, n_sensors: int) -> None:
        """Refuse a subset sweep larger than sweep.max_subsets before any fit."""
        count = subset_count(n_sensors, self.n_clusters)
        if count > self.max_subsets:
            raise ValueError(
                f"config sweep: method subset would evaluate {count} subsets of "
                f"{'/'.join(map(str, self.n_clusters))} of {n_sensors} sensors; "
                f"the cap sweep.max_subsets is {self.max_subsets}"
            )

    def _fixed_note(self, sensors: Sequence[str]) -> str | None:
        """Why the fixed selection cannot be swept on the dataset, or None."""
        wanted = sorted({s for _, chosen in self.fixed for s in chosen})
        missing = [s for s in wanted if s not in sensors]
        if not self.fixed:
            return "fixed: config sweep.fixed lists no sensors"
        if missing:
            return f"fixed: sensor(s) {', '.join(missing)} of sweep.fixed are not in the dataset"
        return None

    def approach_degrees(self, decoupled: bool = True) -> list[tuple[str, int | None]]:
        """(approach, degree) pairs; without a decoupled branch only the pointwise one."""
        pairs = []
        for approach in self.approaches:
            if approach == "decoupled" and decoupled:
                pairs += [("decoupled", d) for d in self.degrees]
            elif approach == "pointwise":
                pairs.append(("pointwise", None))
        return pairs

    def unit_configurations(
        self, spec: SelectionSpec, decoupled: bool = True
    ) -> list[Configuration]:
        return [
            Configuration(spec, approach, degree, algorithm)
            for approach, degree in self.approach_degrees(decoupled)
            for algorithm in self.algorithms
        ]

    def configurations(self, sensors: Sequence[str], decoupled: bool = True) -> list[Configuration]:
        """Every configuration of the grid the dataset allows, in sweep order."""
        specs, _ = self.selection_specs(sensors)
        return [c for spec in specs for c in self.unit_configurations(spec, decoupled)]


# --------------------------------------------------------------------------- batches


@dataclass(frozen=True)
class Unit:
    """One fold x one selection setting: the work that shares one set of selections."""

    fold: str
    selection: SelectionSpec


def plan_units(
    grid: SweepGrid, folds: Sequence[str], sensors: Sequence[str]
) -> tuple[list[Unit], list[str]]:
    """Units in fold order, then grid order, and the notes of settings left out."""
    specs, notes = grid.selection_specs(sensors)
    return [Unit(fold, spec) for fold in folds for spec in specs], notes


def batch_count(requested: int, cores: int | None, n_units: int) -> int:
    """How many batches: ``requested`` if positive, else one per core; never more than units."""
    if requested < 0:
        raise ValueError(
            f"config sweep.batches: expected 0 (one per core) or a positive count, got {requested}"
        )
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
    grid: SweepGrid,
    units: Sequence[Unit],
    n_batches: int,
    batch: int,
    seconds_per_evaluation: float,
    decoupled: bool = True,
) -> int:
    """Time limit (minutes) of one batch job: its evaluations at the given cost, with the
    headroom :func:`thermaxis.pipeline.resources.request` gives every rule."""
    from thermaxis.pipeline.resources import request

    evaluations = sum(
        len(grid.unit_configurations(u.selection, decoupled))
        for u in batch_units(units, n_batches, batch)
    )
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


def cost_note(n_units: int, n_evaluations: int, batches: int, seconds_per_evaluation: float) -> str:
    """The line printed before a sweep's first batch starts: its size and :func:`cost_estimate`."""
    cost = cost_estimate(n_evaluations, seconds_per_evaluation, batches)
    return (
        f"thermaxis: sweep of {n_units} fold x selection units, "
        f"{cost['evaluations']} evaluations in {batches} batches; estimated "
        f"{cost['cpu_hours']:.2f} CPU-hours at {cost['seconds_per_evaluation']:g} s each "
        "(config sweep.seconds_per_evaluation), "
        f">= {cost['wall_minutes']:.1f} min wall with every batch running at once"
    )


def batch_units(units: Sequence[Unit], n_batches: int, batch: int) -> list[Unit]:
    """The units of batch ``batch`` (0-based): contiguous, near-equal shares in unit order.

    Contiguous shares keep a fold's units together, so that evaluations repeated
    across selection settings are found within one batch.
    """
    if not 0 <= batch < n_batches:
        raise ValueError(f"batch {batch} does not exist; expected 0 to {n_batches - 1}")
    bounds = np.linspace(0, len(units), n_batches + 1).round().astype(int)
    return list(units[bounds[batch] : bounds[batch + 1]])
