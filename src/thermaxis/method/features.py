"""The models' inputs and targets without the models: relative temperatures, decoupled rows.

Apart from :mod:`thermaxis.method.estimators` so that the sensitive-point selection, the
statistics and the controller side compute them without importing scikit-learn, which
costs every Snakemake job that imports it a second or more at start.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd

from thermaxis.method.decouple import decouple_curves

__all__ = ["ID_COLUMNS", "KB_COLUMNS", "relative_temperatures", "decouple_rows"]

ID_COLUMNS = ("run", "measurement")
# The decoupled coefficients' columns: slope k, intercept b, and the curvature terms.
KB_COLUMNS = {
    "k": "k_um_per_m",
    "b": "b_um",
    "c2": "c2_um_per_m2",
    "c3": "c3_um_per_m3",
}


def relative_temperatures(X: pd.DataFrame, sensors: Sequence[str] | None = None) -> pd.DataFrame:
    """Temperatures relative to the same run's first measurement.

    Parameters
    ----------
    X : DataFrame
        Columns ``run``, ``measurement`` and sensor columns in absolute degrees C.
    sensors : sequence of str, optional
        Which sensor columns; default every numeric column other than run and measurement.

    Returns
    -------
    DataFrame
        Same index as X, one column per sensor: value minus the run's value at its lowest
        ``measurement`` among the rows of X, so a run's first row is all zeros.  A run's
        reference comes from its own rows only, whatever other runs X holds.
    """
    if sensors is None:
        sensors = [
            c
            for c in X.columns
            if c not in ID_COLUMNS and pd.api.types.is_numeric_dtype(X[c].dtype)
        ]
    sensors = list(sensors)
    missing = [c for c in (*ID_COLUMNS, *sensors) if c not in X.columns]
    if missing:
        raise ValueError(
            f"X lacks column(s) {missing}; expected run, measurement and sensor columns"
        )
    # In numpy, not a pandas sort and group-by: the sweep calls this thousands of times.
    runs, _ = pd.factorize(X["run"])
    # A stable sort by measurement puts each run's lowest measurement (the earlier row on a tie) first.
    order = np.argsort(X["measurement"].to_numpy(), kind="stable")
    _, first = np.unique(runs[order], return_index=True)
    absolute = X[sensors].to_numpy(dtype=float)
    values = absolute - absolute[order[first]][runs]
    return pd.DataFrame(values, index=X.index, columns=sensors)


def decouple_rows(X: pd.DataFrame, Y: pd.DataFrame, degree: int) -> pd.DataFrame:
    """Decoupling of every row of Y (Eq. 6): run, measurement, k_um_per_m, b_um (c2, c3), r2, rms_um.

    The origin is Y's first position, so b means the same for every measurement.
    """
    positions = np.asarray(Y.columns, dtype=float)
    labels = [
        f"run {run} measurement {measurement}"
        for run, measurement in zip(X["run"], X["measurement"], strict=False)
    ]
    fits = decouple_curves(
        positions, Y.to_numpy(dtype=float), degree, origin_mm=float(positions[0]), labels=labels
    )
    rows = []
    for run, measurement, fit in zip(X["run"], X["measurement"], fits, strict=False):
        row = {
            "run": run,
            "measurement": measurement,
            "k_um_per_m": fit.k_um_per_m,
            "b_um": fit.b_um,
        }
        for p in range(2, degree + 1):
            row[KB_COLUMNS[f"c{p}"]] = fit.coefficients[p]
        row.update(r2=fit.r2, rms_um=fit.rms_um)
        rows.append(row)
    return pd.DataFrame(rows, index=X.index)
