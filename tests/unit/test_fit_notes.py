"""What each fit did (fit_notes_, the model report's "How each model was fitted"), by hand."""

import json

import numpy as np
import pandas as pd
from sklearn.preprocessing import StandardScaler
from sklearn.svm import SVR

from thermaxis.method.estimators import DecoupledAxisModel, PointwiseAxisModel
from thermaxis.reports.summaries import fitting_summary

POSITIONS = [0.0, 300.0, 600.0]
GRID = {"C": [1.0, 10.0], "epsilon": [0.1], "gamma": ["scale"]}


def runs(n_runs=3, n_measurements=6):
    rng = np.random.default_rng(7)
    rows, curves = [], []
    for r in range(n_runs):
        for m in range(n_measurements):
            t1, t2 = 22.0 + r + 0.7 * m, 21.0 + 0.4 * m + rng.normal(0, 0.05)
            rows.append(
                {"run": f"R{r}", "measurement": m + 1, "time_min": 20.0 * m, "T1": t1, "T2": t2}
            )
            curves.append([2.0 * (t1 - 22.0) * x / 1000.0 - 1.5 * (t2 - 21.0) for x in POSITIONS])
    return pd.DataFrame(rows), pd.DataFrame(curves, columns=POSITIONS)


def test_an_svr_says_its_inner_split_and_its_choice():
    X, Y = runs()
    model = DecoupledAxisModel(("T1",), ("T2",), algorithm="svr", svr_grid=GRID).fit(X, Y)
    notes = {n["target"]: n for n in model.fit_notes_}
    assert set(notes) == {"k", "b"}
    assert notes["k"]["inner_search"] == "leave one of 3 training runs out"
    assert json.loads(notes["k"]["chosen"])["C"] in (1.0, 10.0)
    assert (notes["b"]["training_rows"], notes["b"]["rows_fitted"]) == (18, 18)
    # Above max_loco_runs (2) the 3 runs are dealt into min(group_folds, 3) = 2 folds, of
    # which the SVR scores its grid on the first svr_search_folds.
    model = DecoupledAxisModel(
        ("T1",), ("T2",), algorithm="svr", svr_grid=GRID, inner_search=(2, 2), svr_search_folds=2
    )
    assert model.fit(X, Y).fit_notes_[0]["inner_search"] == "2 group folds of 3 training runs"
    model.set_params(svr_search_folds=1)
    note = model.fit(X, Y).fit_notes_[0]["inner_search"]
    assert note == "the first of 2 group folds of 3 training runs"


def test_an_svr_leaves_one_run_out_only_up_to_its_own_limit_and_a_ridge_up_to_the_search_limit():
    X, Y = runs(n_runs=6, n_measurements=4)
    # Six training runs, over svr_max_loco_runs 5 (under max_loco_runs 12): the SVR's grid
    # is scored on the first of min(group_folds 5, 6 runs) = 5 group folds ...
    svr = PointwiseAxisModel(("T1", "T2"), algorithm="svr", svr_grid=GRID, svr_max_loco_runs=5)
    assert svr.fit(X, Y).fit_notes_[0]["inner_search"] == (
        "the first of 5 group folds of 6 training runs"
    )
    # ... five runs are still left out one at a time ...
    five = X[X["run"] != "R5"]
    note = svr.fit(five, Y[(X["run"] != "R5").to_numpy()]).fit_notes_[0]["inner_search"]
    assert note == "leave one of 5 training runs out"
    # ... and a searched ridge, whose grid points are linear fits, leaves each of the six out.
    ridge = PointwiseAxisModel(("T1", "T2"), algorithm="ridge", search_grid={"alpha": [0.1, 1.0]})
    assert ridge.fit(X, Y).fit_notes_[0]["inner_search"] == "leave one of 6 training runs out"


def test_an_svr_beyond_its_row_limit_is_fitted_on_evenly_spaced_rows():
    X, Y = runs()
    model = PointwiseAxisModel(("T1", "T2"), algorithm="svr", svr_grid=GRID, svr_max_samples=10)
    notes = model.fit(X, Y).fit_notes_
    assert {(n["training_rows"], n["rows_fitted"]) for n in notes} == {(18, 10)}
    # np.linspace(0, 17, 10) rounded, by hand: each run keeps three or four of its six rows.
    keep = [0, 2, 4, 6, 8, 9, 11, 13, 15, 17]
    features = (X[["T1", "T2"]] - X.groupby("run")[["T1", "T2"]].transform("first")).to_numpy()
    y = Y[600.0].to_numpy()
    chosen = json.loads(notes[2]["chosen"])
    x_scale, y_scale = StandardScaler().fit(features[keep]), StandardScaler().fit(y[keep, None])
    svr = SVR(**chosen).fit(
        x_scale.transform(features[keep]), y_scale.transform(y[keep, None]).ravel()
    )
    expected = y_scale.inverse_transform(svr.predict(x_scale.transform(features))[:, None]).ravel()
    np.testing.assert_allclose(model.predict(X)[:, 2], expected, rtol=1e-9, atol=1e-9)


def test_a_gaussian_process_says_how_many_rows_it_was_fitted_on():
    X, Y = runs()
    model = PointwiseAxisModel(("T1", "T2"), algorithm="gpr", gpr_max_samples=10).fit(X, Y)
    assert [(n["position_mm"], n["training_rows"], n["rows_fitted"]) for n in model.fit_notes_] == [
        (0.0, 18, 10), (300.0, 18, 10), (600.0, 18, 10)
    ]  # fmt: skip
    summary = fitting_summary(pd.DataFrame([{"approach": "pointwise", "algorithm": "gpr", **n}
                                            for n in model.fit_notes_]))  # fmt: skip
    # The three positions were fitted alike: one row that counts them.
    assert summary[["training_rows", "rows_fitted", "regressions"]].values.tolist() == [[18, 10, 3]]


def test_a_plain_fit_has_nothing_to_say():
    X, Y = runs()
    model = PointwiseAxisModel(("T1",), algorithm="mlr").fit(X, Y)
    assert {n["inner_search"] for n in model.fit_notes_} == {""}
    frame = pd.DataFrame(
        [{"approach": "pointwise", "algorithm": "mlr", **n} for n in model.fit_notes_]
    )
    assert fitting_summary(frame).empty
