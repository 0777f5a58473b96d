"""How stable the sensitive points are: stability selection over leave-one-run-out subsets.

For each fold the sensitive points are chosen again on every subset of the runs the fold's
selection sees (its training runs, or every run with ``selection.scope: all``) that leaves
one of them out; a sensor's frequency is the share of those subsets that choose it
(Meinshausen & Bühlmann 2010 resample halves of the samples; here the unit is the run,
because a run's measurements are not independent draws and the choice must not hinge on
one condition). A bootstrap of whole runs would repeat runs: with the paper's three training
runs it has only ten distinct resamples, most holding a run twice, so leaving one out is
the resampling that exists. Above ``statistics.stability_subsets.max_loco_runs`` runs a
subset leaves out a group of them instead, so that a record of many runs costs a fixed
number of selections per fold. With a single run to choose from nothing can be left out:
frequencies are then empty (not resolved).
"""

from __future__ import annotations

import warnings

import numpy as np
import pandas as pd

from thermaxis.config import SelectionSettings
from thermaxis.labels import natural_key
from thermaxis.method.folds import FoldSelection, run_groups, select_for_fold, sensor_columns

__all__ = ["STABILITY_COLUMNS", "selection_stability"]

STABILITY_COLUMNS = (
    "fold",
    "target",
    "sensor",
    "chosen",
    "n_subsets",
    "times_chosen",
    "frequency",
)


def _chosen(selection: FoldSelection) -> dict[str, tuple[str, ...]]:
    targets = {}
    if selection.k is not None:
        targets["k"] = selection.k_sensors
        targets["b"] = selection.b_sensors
    targets["pointwise"] = selection.pointwise
    return targets


def _seen_runs(X: pd.DataFrame, fold: str, settings: SelectionSettings) -> list[str]:
    runs = list(dict.fromkeys(X["run"].tolist()))
    return [r for r in runs if r != fold] if settings.scope == "training" else runs


def selection_stability(
    X: pd.DataFrame,
    Y: pd.DataFrame,
    folds,
    settings: SelectionSettings,
    degree: int | None,
    decoupled: bool,
    subsets: tuple[int, int],
) -> pd.DataFrame:
    """:data:`STABILITY_COLUMNS`: per fold, target (k, b, pointwise) and sensor, how often it is chosen.

    ``subsets`` is ``(max_loco_runs, group_folds)`` (config ``statistics.stability_subsets``):
    above ``max_loco_runs`` seen runs each subset leaves out one of ``group_folds`` groups
    of them (:func:`~thermaxis.method.folds.run_groups`) instead of one run.
    """
    sensors = sorted(sensor_columns(X), key=natural_key)
    rows = []
    for fold in folds:
        full = _chosen(select_for_fold(X, Y, fold, settings, degree, decoupled=decoupled))
        seen = _seen_runs(X, fold, settings)
        subsets_of_fold = (
            [[r for r in seen if r not in left] for left in run_groups(seen, *subsets)]
            if len(seen) >= 2
            else []
        )
        counts = {target: dict.fromkeys(sensors, 0) for target in full}
        for subset in subsets_of_fold:
            keep = X["run"].isin(subset).to_numpy()
            with warnings.catch_warnings():
                # The fold's own selection has warned about its data; a subset's repeats are noise.
                warnings.simplefilter("ignore")
                picked = _chosen(
                    select_for_fold(
                        X.loc[keep].reset_index(drop=True),
                        Y.loc[keep].reset_index(drop=True),
                        fold,
                        settings,
                        degree,
                        decoupled=decoupled,
                    )
                )
            for target, names in picked.items():
                for name in names:
                    counts[target][name] += 1
        for target, names in full.items():
            for sensor in sensors:
                n = len(subsets_of_fold)
                rows.append(
                    {
                        "fold": fold,
                        "target": target,
                        "sensor": sensor,
                        "chosen": sensor in names,
                        "n_subsets": n,
                        "times_chosen": counts[target][sensor],
                        "frequency": counts[target][sensor] / n if n else np.nan,
                    }
                )
    return pd.DataFrame(rows, columns=list(STABILITY_COLUMNS))
