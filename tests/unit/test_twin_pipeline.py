"""The first half of the chain on the simulated twin, checked against the twin's truth.

Tests may read data/twin_truth/ (the modelling code never does): cleaning must recover
the fault-free sensor temperatures, and decoupling the noise-free k and b. The paper's
printed models (Eq. 8, Eq. 9) are checked on the temperatures the pipeline assembles,
never on the truth files.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from helpers import REPO
from thermaxis.cleaning.run import clean_and_assemble_run, model_inputs
from thermaxis.config import Settings, load_config
from thermaxis.dataset.reader import load_dataset, read_run
from thermaxis.method.decouple import decouple_table
from thermaxis.method.estimators import DecoupledAxisModel

TWIN = REPO / "data" / "raw" / "twin"
TRUTH = REPO / "data" / "twin_truth"

pytestmark = pytest.mark.skipif(
    not (TWIN / "dataset.yaml").is_file(), reason="data/raw/twin not generated"
)


@pytest.fixture(scope="module")
def twin_tables():
    config = load_config()
    dataset = load_dataset(TWIN)
    return dataset, {
        run: clean_and_assemble_run(
            dataset, read_run(dataset, run), Settings.from_config(config).cleaning
        )
        for run in dataset.run_ids
    }


def test_twin_is_labelled_simulated(twin_tables):
    dataset, _ = twin_tables
    assert dataset.simulated
    assert dataset.run_ids == ("E1", "E2", "E3", "E4")
    assert "SIMULATED" in (TWIN / "README.md").read_text().upper()


def test_cleaned_temperatures_match_truth_at_measurement_times(twin_tables):
    dataset, tables = twin_tables
    within, total = 0, 0
    for run, t in tables.items():
        truth = pd.read_csv(TRUTH / f"{run}_sensors.csv", parse_dates=["time"])
        cleaned = t.series.set_index("time")
        for w in t.windows.itertuples():
            rows = truth[(truth["time"] >= w.start) & (truth["time"] <= w.end)]
            assert len(rows), f"{run} measurement {w.measurement}: no truth samples in its window"
            got = cleaned.reindex(rows["time"])
            for sensor in dataset.sensors:
                diff = np.abs(got[sensor].to_numpy() - rows[sensor].to_numpy())
                within += int(np.sum(diff <= 0.1))
                total += diff.size
    assert total > 0
    assert within / total >= 0.99, f"{within}/{total} samples within 0.1 degC"


def test_k_and_b_match_noise_free_truth(twin_tables):
    _, tables = twin_tables
    errors = pd.concat([t.errors for t in tables.values()], ignore_index=True)
    kb, _ = decouple_table(errors, degree=1)
    truth = pd.read_csv(TRUTH / "kb_truth.csv")
    merged = kb.merge(truth, on=["run", "measurement"], suffixes=("", "_truth"))
    assert len(merged) == 32
    dk = (merged["k_um_per_m"] - merged["k_um_per_m_truth"]).abs()
    db = (merged["b_um"] - merged["b_um_truth"]).abs()
    assert dk.max() <= 0.3, merged.loc[dk.idxmax()]
    assert db.max() <= 0.15, merged.loc[db.idxmax()]


def test_error_curves_are_strongly_but_not_perfectly_linear(twin_tables):
    _, tables = twin_tables
    errors = pd.concat([t.errors for t in tables.values()], ignore_index=True)
    kb, _ = decouple_table(errors, degree=1)
    assert (kb["rms_um"] > 0.01).all()
    assert kb["r2"].median() > 0.9


def test_papers_mlr_does_not_reproduce_the_twin_exactly(twin_tables):
    _, tables = twin_tables
    errors = pd.concat([t.errors for t in tables.values()], ignore_index=True)
    temperatures = pd.concat([t.temperatures for t in tables.values()], ignore_index=True)
    X, Y = model_inputs(errors, temperatures)
    train = (X["run"] != "E4").to_numpy()
    model = DecoupledAxisModel(
        k_sensors=("T1", "T6", "T12"), b_sensors=("T2", "T7", "T11"), algorithm="mlr"
    )
    model.fit(X.loc[train], Y.loc[train])
    residual = Y.loc[~train].to_numpy() - model.predict(X.loc[~train])
    rmse = float(np.sqrt(np.nanmean(residual**2)))
    # By hand: each measurement's numpy line (a missing reading left out), k on absolute
    # T1, T6, T12 and b on the rises of T2, T7, T11 since each run's first measurement.
    y = Y.to_numpy()
    x_m = (Y.columns.to_numpy(float) - float(Y.columns[0])) / 1000.0
    k, b = np.array([np.polyfit(x_m[~np.isnan(row)], row[~np.isnan(row)], 1) for row in y]).T
    rise = X[["T2", "T7", "T11"]] - X.groupby("run")[["T2", "T7", "T11"]].transform("first")

    def fit_predict(inputs, target):
        design = np.column_stack([np.ones(len(inputs)), inputs.to_numpy()])
        coef, *_ = np.linalg.lstsq(design[train], target[train], rcond=None)
        return design[~train] @ coef

    by_hand = np.outer(fit_predict(X[["T1", "T6", "T12"]], k), x_m) + fit_predict(rise, b)[:, None]
    assert rmse == pytest.approx(np.sqrt(np.nanmean((y[~train] - by_hand) ** 2)), rel=1e-9)
    # Hidden drivers, lagging noisy sensors: the held-out condition is predicted, not reproduced.
    assert rmse > 0.05


# The paper's Eq. 9 and the printed rows of Eq. 8, typed from the article (not from
# thermaxis/paper/values/ or the twin): constant, then coefficient per sensor.
EQ9_K = (-306.494, {"T1": 13.247, "T6": -6.629, "T12": 3.326})  # absolute degC -> um/m
EQ9_B = (-0.576, {"T2": -11.058, "T7": 0.974, "T11": -1.915})  # relative to M1 -> um
EQ8 = {
    185.0: (-0.421, {"T1": -7.417, "T11": -2.961, "T12": 1.180}),
    205.0: (-0.708, {"T1": -7.288, "T11": -2.706, "T12": 1.066}),
    225.0: (-1.131, {"T1": -7.237, "T11": -2.548, "T12": 1.001}),
    445.0: (-4.544, {"T1": -4.908, "T11": 2.436, "T12": -1.032}),
}
# The paper's held-out RMSE of its decoupled MLR (Table 7: k, b, error), the bounds of
# the checks (issue 14); each run may miss by twice as much.
TABLE7_K, TABLE7_B, TABLE7_ERROR = 2.6, 0.5, 0.6
# Eq. 8 gives way to the paper's results (issue 32 keeps Table 5, Eq. 9 and Table 1): its
# bound is the paper's own point-by-point error, Table 4's held-out RMSE.
TABLE4_ERROR = 1.6


@pytest.fixture(scope="module")
def assembled(twin_tables):
    _, tables = twin_tables
    errors = pd.concat([t.errors for t in tables.values()], ignore_index=True)
    temperatures = pd.concat([t.temperatures for t in tables.values()], ignore_index=True)
    X, Y = model_inputs(errors, temperatures)
    # k and b recomputed with numpy.polyfit on the pipeline's pass-mean curves.
    x_m = (Y.columns.to_numpy(float) - 185.0) / 1000.0
    lines = []
    for row in Y.to_numpy(float):
        ok = ~np.isnan(row)
        lines.append(np.polyfit(x_m[ok], row[ok], 1))
    X = X.assign(k=[k for k, _ in lines], b=[b for _, b in lines])
    return X, Y


def _apply(model, frame: pd.DataFrame, relative: bool) -> np.ndarray:
    const, coef = model
    out = np.full(len(frame), const)
    for sensor, c in coef.items():
        t = frame[sensor].to_numpy(float)
        out += c * (t - t[0] if relative else t)
    return out


def _rms(values) -> float:
    return float(np.sqrt(np.mean(np.square(np.concatenate([np.ravel(v) for v in values])))))


def test_papers_eq9_reproduces_the_twins_k_and_b_from_the_assembled_temperatures(assembled):
    X, _ = assembled
    dk, db = {}, {}
    for run, frame in X.groupby("run", sort=True):
        assert len(frame) == 8
        dk[run] = _apply(EQ9_K, frame, relative=False) - frame["k"].to_numpy()
        db[run] = _apply(EQ9_B, frame, relative=True) - frame["b"].to_numpy()
    assert _rms(dk.values()) <= TABLE7_K, {r: _rms([v]) for r, v in dk.items()}
    assert _rms(db.values()) <= TABLE7_B, {r: _rms([v]) for r, v in db.items()}
    for run in dk:
        assert _rms([dk[run]]) <= 2 * TABLE7_K, run
        assert _rms([db[run]]) <= 2 * TABLE7_B, run


def test_papers_eq8_reproduces_the_twins_errors_at_the_printed_positions(assembled):
    X, Y = assembled
    miss = {}
    for run, frame in X.groupby("run", sort=True):
        measured = Y.loc[frame.index]
        miss[run] = [_apply(EQ8[x], frame, relative=True) - measured[x].to_numpy() for x in EQ8]
    assert _rms([np.concatenate(v) for v in miss.values()]) <= TABLE4_ERROR, {
        r: _rms(v) for r, v in miss.items()
    }
    for run, values in miss.items():
        assert _rms(values) <= 2 * TABLE4_ERROR, run


# --------------------------------------------------------------------------- Table 6
# The paper's selection re-done in plain numpy on the committed twin: |Pearson r|
# similarity (Eq. 1), the max-min transitive closure by repeated composition (Eq. 2),
# the lambda-cut with three classes, and Deng's grade (Eq. 4, rho 0.5, min-max
# normalisation, extremes over all sensors).  Fold E4: trained on E1-E3.
PAPER_K_CLASSES = [{"T1", "T2", "T3", "T4", "T5", "T8", "T10"}, {"T6", "T9", "T11"}, {"T12"}]
PAPER_B_CLASSES = [{"T1", "T2", "T3", "T4", "T5", "T8", "T9", "T10"}, {"T6", "T11"}, {"T7", "T12"}]


def _closure(R: np.ndarray) -> np.ndarray:
    while True:
        composed = np.max(np.minimum(R[:, :, None], R[None, :, :]), axis=1)
        if np.array_equal(composed, R):
            return R
        R = composed


def _three_classes(closure: np.ndarray, names: list[str]) -> list[set[str]]:
    for level in np.unique(closure)[::-1]:
        classes: list[set[str]] = []
        for i, name in enumerate(names):
            for c in classes:
                if closure[i, names.index(next(iter(c)))] >= level:
                    c.add(name)
                    break
            else:
                classes.append({name})
        if len(classes) == 3:
            return classes
    raise AssertionError("no lambda-cut gives three classes")


def _deng(y: np.ndarray, T: np.ndarray) -> np.ndarray:
    def unit(v):
        return (v - v.min(axis=0)) / (v.max(axis=0) - v.min(axis=0))

    delta = np.abs(unit(T) - unit(y)[:, None])
    return ((delta.min() + 0.5 * delta.max()) / (delta + 0.5 * delta.max())).mean(axis=0)


def _selected(T: pd.DataFrame, y: np.ndarray) -> tuple[list[set[str]], set[str]]:
    names = list(T.columns)
    classes = _three_classes(_closure(np.abs(np.corrcoef(T.to_numpy(float).T))), names)
    grade = dict(zip(names, _deng(y, T.to_numpy(float)), strict=True))
    return classes, {max(c, key=grade.__getitem__) for c in classes}


def _restricted(classes: list[set[str]], listed: set[str]) -> list[set[str]]:
    return sorted((c & listed for c in classes), key=sorted)


def test_numpy_fuzzy_closure_and_grey_grade_select_the_papers_table6_points(assembled):
    X, _ = assembled
    train = X[X["run"] != "E4"]
    sensors = [c for c in train.columns if c.startswith("T")]
    absolute = train[sensors]
    relative = absolute - train.groupby("run")[sensors].transform("first")
    k_classes, k_points = _selected(absolute, train["k"].to_numpy())
    b_classes, b_points = _selected(relative, train["b"].to_numpy())
    # T7 is not printed in the paper's k clustering: it may join any class.
    listed = set().union(*PAPER_K_CLASSES)
    assert _restricted(k_classes, listed) == _restricted(PAPER_K_CLASSES, listed)
    assert _restricted(b_classes, set(sensors)) == _restricted(PAPER_B_CLASSES, set(sensors))
    assert k_points == {"T1", "T6", "T12"}
    assert b_points == {"T2", "T7", "T11"}


# Table 3 of the paper, typed from the article: the sensitive points of each position.
PAPER_TABLE3 = {
    185.0: {"T2", "T7", "T11"}, 205.0: {"T2", "T7", "T11"}, 225.0: {"T1", "T7", "T11"},
    245.0: {"T4", "T7", "T12"}, 265.0: {"T4", "T7", "T11"}, 285.0: {"T1", "T11", "T12"},
    305.0: {"T1", "T11", "T12"}, 325.0: {"T1", "T6", "T12"}, 345.0: {"T1", "T6", "T12"},
    365.0: {"T1", "T6", "T12"}, 385.0: {"T1", "T7", "T11"}, 405.0: {"T1", "T11", "T12"},
    425.0: {"T1", "T6", "T7"}, 445.0: {"T1", "T11", "T12"},
}  # fmt: skip


def test_numpy_fuzzy_closure_and_grey_grade_select_34_of_table3s_42_points(assembled):
    # Issue 32: at least 34 of the 42 published per-position points, each position's
    # unzeroed error graded against the relative temperatures of the training runs.
    X, Y = assembled
    train = (X["run"] != "E4").to_numpy()
    sensors = [c for c in X.columns if c.startswith("T")]
    absolute = X.loc[train, sensors]
    relative = absolute - X.loc[train].groupby("run")[sensors].transform("first")
    hits = {}
    for x, published in PAPER_TABLE3.items():
        classes, points = _selected(relative, Y.loc[train, x].to_numpy(float))
        assert _restricted(classes, set(sensors)) == _restricted(PAPER_B_CLASSES, set(sensors))
        hits[x] = len(points & published)
    assert sum(hits.values()) >= 34, hits
