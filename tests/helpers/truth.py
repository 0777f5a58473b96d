"""Truth worked out independently of the library: what the builders write and the tests expect."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd

# ------------------------------------------------------------------ Eq. 8 and Eq. 9 by construction

POSITIONS = np.arange(185.0, 446.0, 20.0)  # the paper's 14 targets
SENSORS = [f"T{i}" for i in range(1, 13)]

# Eq. 9 as printed: k [um/m] on absolute, b [um] on relative temperatures.
EQ9_K = {"const": -306.494, "T1": 13.247, "T6": -6.629, "T12": 3.326}
EQ9_B = {"const": -0.576, "T2": -11.058, "T7": 0.974, "T11": -1.915}

# Eq. 8 prints rows 1-3 and 14; rows 4-13 are interpolated linearly between row 3 and row 14.
_EQ8_PRINTED = {
    0: (-0.421, -7.417, -2.961, 1.180),
    1: (-0.708, -7.288, -2.706, 1.066),
    2: (-1.131, -7.237, -2.548, 1.001),
    13: (-4.544, -4.908, 2.436, -1.032),
}
EQ8 = np.array(
    [
        (
            _EQ8_PRINTED[j]
            if j in _EQ8_PRINTED
            else tuple(
                np.array(_EQ8_PRINTED[2])
                + (j - 2) / 11 * (np.array(_EQ8_PRINTED[13]) - np.array(_EQ8_PRINTED[2]))
            )
        )
        for j in range(14)
    ]
)  # columns const, T1, T11, T12


def eq9_truth(X: pd.DataFrame) -> tuple[np.ndarray, np.ndarray]:
    """k and b straight from Eq. 9, relative temperatures computed here by hand."""
    k = EQ9_K["const"] + sum(c * X[s].to_numpy() for s, c in EQ9_K.items() if s != "const")
    b = np.full(len(X), EQ9_B["const"])
    for s, c in EQ9_B.items():
        if s == "const":
            continue
        first = X.loc[X["measurement"] == 1].set_index("run")[s]
        b = b + c * (X[s].to_numpy() - first.loc[X["run"]].to_numpy())
    return k, b


def eq9_errors(X: pd.DataFrame, c2=None) -> pd.DataFrame:
    k, b = eq9_truth(X)
    shifted_m = (POSITIONS - POSITIONS[0]) / 1000.0
    errors = k[:, None] * shifted_m + b[:, None]
    if c2 is not None:
        errors = errors + c2[:, None] * shifted_m**2
    return pd.DataFrame(errors, columns=POSITIONS, index=X.index)


def eq8_errors(X: pd.DataFrame) -> pd.DataFrame:
    first = X.loc[X["measurement"] == 1].set_index("run")
    rel = np.column_stack(
        [X[s].to_numpy() - first.loc[X["run"], s].to_numpy() for s in ("T1", "T11", "T12")]
    )
    design = np.column_stack([np.ones(len(X)), rel])
    return pd.DataFrame(design @ EQ8.T, columns=POSITIONS, index=X.index)


# --------------------------------------------------------------------------- the `lines` dataset


# The `lines` dataset's targets (helpers.builders.write_dataset's default stroke, mm).
LINES_POSITIONS = np.array([0.0, 50.0, 100.0, 150.0])


# k and b of each (run, measurement) of the `lines` dataset: exact lines the pipeline must recover.
def k_true(r, m):
    return -10.0 + 0.5 * m + r + 0.1 * m * m


def b_true(r, m):
    return -0.7 * m - 0.1 * r + 0.05 * r * m


def exact_line(r, m, x):
    return k_true(r, m) * (x - x[0]) / 1000.0 + b_true(r, m)


def lines_mlr_by_hand(temperatures: pd.DataFrame, inputs: dict[str, tuple], fold: str, runs):
    """The held-out run's k, b and error of the ``lines`` dataset predicted by MLR with numpy
    least squares on the other runs' exact lines: k on absolute temperatures, b and the
    point-by-point errors on the rises since each run's first measurement (the paper's forms).

    ``temperatures``: assembled (run, measurement, sensor, absolute_c); ``inputs``: the
    sensors of ``k``, ``b`` and ``pointwise``. Returns (truth, predictions) with keys ``k``,
    ``b`` (per measurement), ``decoupled`` and ``pointwise`` (measurements x LINES_POSITIONS).
    """
    wide = temperatures.pivot(index=["run", "measurement"], columns="sensor", values="absolute_c")
    rise = wide - wide.groupby(level="run").transform("first")
    run_of = wide.index.get_level_values("run")
    r = np.array([list(runs).index(run) for run in run_of])
    m = wide.index.get_level_values("measurement").to_numpy() - 1
    test = np.asarray(run_of == fold)
    x = LINES_POSITIONS
    errors = np.array([exact_line(ri, mi, x) for ri, mi in zip(r, m, strict=True)])

    def fit_predict(table, target):
        design = np.column_stack([np.ones(len(table)), table.to_numpy()])
        coef, *_ = np.linalg.lstsq(design[~test], target[~test], rcond=None)
        return design[test] @ coef

    k = fit_predict(wide[list(inputs["k"])], k_true(r, m))
    b = fit_predict(rise[list(inputs["b"])], b_true(r, m))
    truth = {"k": k_true(r, m)[test], "b": b_true(r, m)[test], "error": errors[test]}
    predicted = {
        "k": k,
        "b": b,
        "decoupled": k[:, None] * (x - x[0]) / 1000.0 + b[:, None],
        "pointwise": fit_predict(rise[list(inputs["pointwise"])], errors),
    }
    return truth, predicted


def lines_mlr_residuals(out) -> dict[str, dict[tuple[str, str], np.ndarray]]:
    """Each fold's MLR residuals (k, b, decoupled and point-by-point error) of the ``lines``
    run in ``out``: :func:`lines_mlr_by_hand` on the sensitive points the run chose."""
    temperatures = pd.read_parquet(out / "assembled" / "temperatures.parquet")
    runs = sorted(temperatures["run"].unique())
    residuals = {}
    for fold in runs:
        chosen = json.loads((out / "selection" / f"{fold}.json").read_text())
        inputs = {"k": chosen["k"]["selected"], "b": chosen["b"]["selected"],
                  "pointwise": chosen["pointwise"]}  # fmt: skip
        truth, predicted = lines_mlr_by_hand(temperatures, inputs, fold, runs)
        residuals[fold] = {
            ("decoupled", "k"): truth["k"] - predicted["k"],
            ("decoupled", "b"): truth["b"] - predicted["b"],
            ("decoupled", "error"): truth["error"] - predicted["decoupled"],
            ("pointwise", "error"): truth["error"] - predicted["pointwise"],
        }
    return residuals
