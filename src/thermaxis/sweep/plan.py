"""Planning a sweep: its units and batches, and what it will cost.

The grid of configurations is :mod:`thermaxis.sweep_grid`; :mod:`thermaxis.sweep.run`
evaluates them.

Work is grouped in *units* (one fold x one selection setting): a unit's sensitive
points are selected once per decoupling degree and shared by every approach and
algorithm, and a unit lives in exactly one batch (one process), so no selection is
computed twice. Units are cut into batches in fold order, which keeps a fold's units
together.

Exhaustive subsets (method ``subset``): every subset of ``n`` sensors (``n`` from the
``n_clusters`` levels) is used as it stands for k, b and the point-by-point models, as
method ``fixed`` uses the paper's lists.  C(12, 3) = 220 subsets per size and fold is
why it wants a cluster: :func:`thermaxis.sweep_grid.subset_count` caps it and
:func:`cost_estimate` says what it will cost before it starts.

This module imports neither scikit-learn nor pandas, so the workflow can plan a sweep
while it parses the Snakefile.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from thermaxis.sweep_grid import SelectionSpec, SweepGrid

__all__ = [
    "Unit",
    "plan_units",
    "batch_count",
    "cluster_batch_count",
    "cost_estimate",
    "cost_note",
    "batch_units",
]


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
