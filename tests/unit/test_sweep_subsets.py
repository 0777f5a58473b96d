"""Exhaustive sensor subsets, cluster batch counts and the sweep's cost estimate."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pandas as pd
import pytest
from threadpoolctl import threadpool_limits

from helpers import DEFAULTS
from thermaxis import sweep_grid
from thermaxis.pipeline import tuning
from thermaxis.sweep import plan as sweep_plan
from thermaxis.sweep import run as sweep_run

TWELVE = [f"T{i}" for i in range(1, 13)]


def subset_grid(sizes=(3,), cap=1000, **kw):
    return replace(
        DEFAULTS.sweep.grid, methods=("subset",), n_clusters=tuple(sizes), max_subsets=cap, **kw
    )


def test_every_subset_once_counted_by_hand():
    # C(12, 3) = 12 * 11 * 10 / 6 = 220; C(12, 2) = 66.
    specs, notes = subset_grid((3,)).selection_specs(TWELVE)
    assert (len(specs), notes) == (220, [])
    assert len({s.sensors for s in specs}) == 220
    assert all(len(s.sensors) == 3 and s.n_clusters == 3 for s in specs)
    assert specs[0].sensors == ("T1", "T2", "T3") and specs[-1].sensors == ("T10", "T11", "T12")
    assert sweep_grid.subset_count(12, (2, 3)) == 66 + 220
    # 220 subsets x (decoupled d1-3 + pointwise) x 5 algorithms.
    assert len(subset_grid((3,)).configurations(TWELVE)) == 220 * 4 * 5
    # A size above the sensor count is left out with a note, as for cluster counts.
    specs, notes = subset_grid((2, 5)).selection_specs(["S1", "S2", "S3"])
    assert len(specs) == 3 and notes == ["subsets of 5 sensors: the dataset has only 3 sensors"]


def test_more_subsets_than_the_cap_stop_the_plan_with_the_count():
    with pytest.raises(
        ValueError,
        match="would evaluate 220 subsets of 3 of 12 sensors; the cap sweep.max_subsets is 219",
    ):
        sweep_plan.plan_units(subset_grid((3,), cap=219), ["E1"], TWELVE)
    units, _ = sweep_plan.plan_units(subset_grid((3,), cap=220), ["E1", "E2"], TWELVE)
    assert len(units) == 440


def test_a_subset_is_the_fixed_choice_for_k_b_and_pointwise():
    spec = sweep_grid.SelectionSpec("subset", 2, sensors=("T4", "T9"))
    settings = spec.settings(DEFAULTS.selection, ())
    assert settings.method == "fixed"
    assert [settings.fixed_for(t) for t in ("k", "b", "pointwise")] == [("T4", "T9")] * 3
    assert (
        sweep_grid.Configuration(spec, "pointwise", None, "mlr").config_id
        == "subset:n2:T4+T9/pointwise/mlr"
    )


def test_cluster_batches_follow_the_evaluation_count():
    # 27 units of 20 evaluations = 540; 200 per batch -> ceil(2.7) = 3.
    assert sweep_plan.cluster_batch_count(0, [20] * 27, 200) == 3
    assert sweep_plan.cluster_batch_count(0, [20] * 27, 1) == 27  # never more batches than units
    assert sweep_plan.cluster_batch_count(0, [20] * 3, 10_000) == 1
    assert sweep_plan.cluster_batch_count(5, [20] * 27, 200) == 5  # sweep.batches wins


def test_cost_estimate_by_hand():
    # 880 evaluations x 0.5 s = 440 s = 0.1222 h; on 100 workers 4.4 s = 0.0733 min.
    cost = sweep_plan.cost_estimate(880, 0.5, 100)
    assert cost["cpu_hours"] == pytest.approx(440 / 3600)
    assert cost["wall_minutes"] == pytest.approx(4.4 / 60)


def _lines(n_runs=3, n_measurements=5, seed=1):
    """X, Y as model_inputs gives them; the error at each position is linear in S1 and S2 rises."""
    rng = np.random.default_rng(seed)
    positions = np.array([0.0, 100.0])
    rows, errors = [], []
    for r in range(n_runs):
        for m in range(n_measurements):
            temps = {
                "S1": 20 + r + 0.7 * m + 0.1 * m * m,
                "S2": 21 + 0.4 * m + 0.3 * r * m,
                "S3": 22 + rng.normal(0, 0.2),
            }
            rows.append({"run": f"R{r + 1}", "measurement": m + 1, "time_min": 20.0 * m, **temps})
            errors.append(rng.normal(0, 0.1, positions.size))
    X = pd.DataFrame(rows)
    rel = X[["S1", "S2"]] - X.groupby("run")[["S1", "S2"]].transform("first")
    Y = pd.DataFrame(np.array(errors), columns=positions)
    Y[0.0] += -2.0 * rel["S1"] + 1.0 * rel["S2"]
    Y[100.0] += -1.0 * rel["S1"] - 0.5 * rel["S2"]
    return X, Y


def test_pointwise_mlr_of_a_subset_matches_plain_least_squares():
    X, Y = _lines()
    grid = subset_grid((2,), approaches=("pointwise",), algorithms=("mlr",))
    units, _ = sweep_plan.plan_units(grid, ["R3"], ["S1", "S2", "S3"])
    with threadpool_limits(limits=1):
        rows = sweep_run.run_batch(X, Y, units, grid, DEFAULTS.selection, DEFAULTS.models)
    assert rows["config_id"].tolist() == [
        "subset:n2:S1+S2/pointwise/mlr",
        "subset:n2:S1+S3/pointwise/mlr",
        "subset:n2:S2+S3/pointwise/mlr",
    ]
    got = rows.set_index("config_id").loc["subset:n2:S1+S2/pointwise/mlr"]
    # Plain numpy: per position, least squares on relative S1, S2 with an intercept,
    # fitted on R1-R2, residuals on R3.
    sensors = ["S1", "S2"]
    rel = X[sensors] - X.groupby("run")[sensors].transform("first")
    design = np.column_stack([np.ones(len(X)), rel.to_numpy()])
    train, test = (X["run"] != "R3").to_numpy(), (X["run"] == "R3").to_numpy()
    residuals = []
    for position in Y.columns:
        beta, *_ = np.linalg.lstsq(design[train], Y[position].to_numpy()[train], rcond=None)
        residuals.append(Y[position].to_numpy()[test] - design[test] @ beta)
    residuals = np.concatenate(residuals)
    assert got["max_abs"] == pytest.approx(np.abs(residuals).max(), rel=1e-9)
    assert got["rmse"] == pytest.approx(math.sqrt(np.mean(residuals**2)), rel=1e-9)
    assert got["sensors"] == "error=S1+S2"


def test_batch_time_limit_by_hand():
    # 27 units of 4 approach-degrees x 5 algorithms = 20 evaluations; 3 batches of 9 units
    # = 180 evaluations x 2 s = 360 s; five times that is 1800 s = 30 min.
    grid = replace(
        DEFAULTS.sweep.grid, fixed=(("b", ("T1",)), ("k", ("T1",)), ("pointwise", ("T1",)))
    )
    units, _ = sweep_plan.plan_units(grid, ["E1"], TWELVE)
    assert len(units) == 27
    assert tuning.batch_minutes(grid, units, 3, 0, 2.0) == 30
    # 180 x 0.05 s = 9 s: the 5-minute floor.
    assert tuning.batch_minutes(grid, units, 3, 2, 0.05) == 5
