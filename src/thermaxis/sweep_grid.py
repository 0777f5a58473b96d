"""The grid of a sweep: its factors, their levels, and the configurations they make.

A *configuration* is one choice of sensitive-point selection (method, number of
clusters, similarity, grey grade), approach (decoupled or point-by-point), decoupling
degree and algorithm; :mod:`thermaxis.sweep.plan` cuts them into units and batches and
:mod:`thermaxis.sweep.run` evaluates them.

Factors that do not apply to a configuration are left empty (None): n_clusters for
``all`` and ``fixed``; similarity and grade for every method but ``fuzzy_grey``; the
degree for the point-by-point approach, which never decouples.

The grid sits below both the configuration (:class:`thermaxis.config.SweepSettings`
holds one) and the sweep, so that neither imports the other's side of the data flow.
This module imports neither scikit-learn nor pandas.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, replace

from thermaxis.vocabulary import ALGORITHMS, APPROACHES

__all__ = [
    "FACTORS",
    "LEVEL_ORDER",
    "SelectionSpec",
    "Configuration",
    "SweepGrid",
    "subset_count",
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


# The methods that take a count per level of n_clusters, and how a note names that count.
_COUNTED = {
    "fuzzy_grey": "fuzzy_grey with {n} clusters",
    "correlation": "correlation ranking of {n} sensors",
    "subset": "subsets of {n} sensors",
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
        specs, notes = [], []
        for method in self.methods:
            if method in _COUNTED:
                if method == "subset":
                    self._check_subset_cap(len(sensors))
                specs += self._counted_specs(method, sensors, notes)
            elif method == "fixed":
                note = self._fixed_note(sensors)
                if note:
                    notes.append(note)
                else:
                    specs.append(SelectionSpec(method))
            else:
                specs.append(SelectionSpec(method))
        return specs, notes

    def _counted_specs(self, method: str, sensors: Sequence[str], notes: list[str]):
        """A method's specs at each count of ``n_clusters``; a count above the dataset's
        sensors cannot be asked for and becomes a note instead."""
        specs = []
        for n in self.n_clusters:
            if n > len(sensors):
                what = _COUNTED[method].format(n=n)
                notes.append(f"{what}: the dataset has only {len(sensors)} sensors")
                continue
            specs += self._specs_of_count(method, n, sensors)
        return specs

    def _specs_of_count(self, method: str, n: int, sensors: Sequence[str]):
        if method == "fuzzy_grey":
            return [SelectionSpec(method, n, s, g) for s in self.similarities for g in self.grades]
        if method == "correlation":
            return [SelectionSpec(method, n)]
        return [SelectionSpec(method, n, sensors=c) for c in itertools.combinations(sensors, n)]

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


def subset_count(n_sensors: int, sizes: Iterable[int]) -> int:
    """How many sensor subsets of the given sizes: the sum of C(n_sensors, n)."""
    return sum(math.comb(n_sensors, n) for n in set(sizes) if n <= n_sensors)
