"""What each fit did (fit_notes_, the model report's "How each model was fitted"), by hand."""

import json

import numpy as np
import pandas as pd

from thermaxis.method.models import DecoupledAxisModel, PointwiseAxisModel
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
    # Above max_loco_runs (2) the 3 runs are dealt into min(group_folds, 3) = 2 folds.
    model = DecoupledAxisModel(
        ("T1",), ("T2",), algorithm="svr", svr_grid=GRID, inner_search=(2, 2)
    )
    assert model.fit(X, Y).fit_notes_[0]["inner_search"] == "2 group folds of 3 training runs"


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
