"""Tests of thermaxis.sweep.run (the `sweep` target end to end:
tests/workflow/test_sweep_workflow.py).

Counts, partitions, rankings and factor effects are checked against numbers worked
out by hand in the comments; the sweep's metrics are checked against the library
function the main workflow calls and, end to end, against the main workflow's
metrics.csv for the same configuration.
"""

from __future__ import annotations

import io
import sys
from dataclasses import replace

import numpy as np
import pandas as pd
import pytest
from threadpoolctl import threadpool_limits

from helpers import DEFAULTS
from thermaxis import sweep_grid
from thermaxis.config import Settings, load_config
from thermaxis.errors import SelectionWarning
from thermaxis.method import batched, folds
from thermaxis.method.folds import evaluate_configuration, select_for_fold
from thermaxis.method.metrics import METRIC_COLUMNS
from thermaxis.schemas import schema_path
from thermaxis.sweep import plan as sweep_plan
from thermaxis.sweep import run as sweep_run

PAPER_FIXED = (
    ("b", ("T2", "T7", "T11")),
    ("k", ("T1", "T6", "T12")),
    ("pointwise", ("T1", "T11", "T12")),
)
TWELVE = [f"T{i}" for i in range(1, 13)]


@pytest.fixture(autouse=True, scope="module")
def _single_blas_thread():
    with threadpool_limits(limits=1):
        yield


# --------------------------------------------------------------------------- the grid


def test_default_grid_counts_by_hand():
    # fuzzy_grey: 5 cluster counts x 2 similarities x 2 grades = 20; correlation: 5;
    # all: 1; fixed: 1 -> 27 selection settings. Approaches: decoupled at degrees 1-3
    # plus pointwise = 4. Algorithms: 5. 27 x 4 x 5 = 540.
    grid = replace(DEFAULTS.sweep.grid, fixed=PAPER_FIXED)
    specs, notes = grid.selection_specs(TWELVE)
    assert (len(specs), notes) == (27, [])
    configs = grid.configurations(TWELVE)
    assert len(configs) == 540
    assert len({c.config_id for c in configs}) == 540
    # Without a decoupled branch only pointwise remains: 27 x 1 x 5.
    assert len(grid.configurations(TWELVE, decoupled=False)) == 135


def test_config_yaml_sweep_is_the_issue_grid():
    grid = Settings.from_config(load_config()).sweep.grid
    assert grid.n_clusters == (2, 3, 4, 5, 6) and grid.degrees == (1, 2, 3)
    assert len(grid.configurations(TWELVE)) >= 200


def test_schema_fills_defaults_and_rejects_bad_levels():
    from snakemake.utils import validate

    schema = str(schema_path("config"))
    config = {"dataset": "x"}
    validate(config, schema, set_default=True)
    assert config["sweep"]["methods"] == ["fuzzy_grey", "correlation", "all", "fixed"]
    assert config["sweep"]["batches"] == 0
    assert Settings.from_config(config).sweep.svr_grid == (
        ("C", (1.0, 10.0)),
        ("epsilon", (0.1,)),
        ("gamma", ("scale",)),
    )
    settings = Settings.from_config({"sweep": {"svr_grid": "models"}})
    assert settings.sweep.svr_grid == settings.models.svr_grid
    for bad in (
        {"degrees": [4]},
        {"methods": ["lasso"]},
        {"svr_grid": "mine"},
        {"batches": -1},
        {"colour": 1},
    ):
        with pytest.raises(Exception, match="sweep|valid"):
            validate({"dataset": "x", "sweep": bad}, schema, set_default=True)


def test_settings_the_dataset_cannot_support_are_left_out_with_a_note():
    # Three sensors: only 2 and 3 clusters fit -> fuzzy 2 x 2 x 2 = 8, correlation 2,
    # all 1; fixed names T1.. which the dataset lacks.
    grid = replace(DEFAULTS.sweep.grid, fixed=PAPER_FIXED)
    specs, notes = grid.selection_specs(["S1", "S2", "S3"])
    assert len(specs) == 11
    assert len(notes) == 3 * 2 + 1
    assert any("T1, T11, T12, T2, T6, T7" in n for n in notes)


def test_spec_settings_apply_only_the_factors_of_the_method():
    base = replace(DEFAULTS.selection, n_clusters=3, similarity="pearson", grade="deng")
    s = sweep_grid.SelectionSpec("correlation", 5).settings(base, ())
    assert (s.method, s.n_clusters, s.similarity, s.grade) == ("correlation", 5, "pearson", "deng")
    f = sweep_grid.SelectionSpec("fixed").settings(base, PAPER_FIXED)
    assert f.fixed_for("k") == ("T1", "T6", "T12")


# --------------------------------------------------------------------------- batches


def test_batches_cover_every_unit_once_in_contiguous_near_equal_shares():
    units = [sweep_plan.Unit(f"F{i}", sweep_grid.SelectionSpec("all")) for i in range(10)]
    shares = [sweep_plan.batch_units(units, 4, b) for b in range(4)]
    # 10 units in 4 shares: boundaries round(0, 2.5, 5, 7.5, 10) = 0, 2, 5, 8, 10.
    assert [len(s) for s in shares] == [2, 3, 3, 2]
    assert [u for s in shares for u in s] == units
    with pytest.raises(ValueError, match="batch 4 does not exist"):
        sweep_plan.batch_units(units, 4, 4)


def test_batch_count_follows_the_cores_unless_set():
    assert sweep_plan.batch_count(0, 2, 108) == 2
    assert sweep_plan.batch_count(0, 64, 10) == 10
    assert sweep_plan.batch_count(3, 2, 108) == 3
    assert sweep_plan.batch_count(0, None, 5) == 1
    with pytest.raises(ValueError, match="sweep.batches"):
        sweep_plan.batch_count(-1, 2, 5)


def test_progress_prints_whole_tqdm_like_lines():
    ticks = iter([0.0, 1.0, 2.0, 3.0, 4.0, 4.0])
    out = io.StringIO()
    progress = sweep_run.Progress(
        4, "sweep batch 1/2", stream=out, every_s=10.0, clock=lambda: next(ticks)
    )
    for _ in range(4):
        progress.update()
    # Only the last update is printed (10 s never pass); 4 configurations in 4 s.
    lines = out.getvalue().splitlines()
    assert lines == ["sweep batch 1/2: 100%|####################| 4/4 [00:04<00:00, 1.0 config/s]"]


# --------------------------------------------------------------------------- evaluation


def _inputs(n_runs=3, n_measurements=6, seed=0):
    """X, Y like model_inputs: four sensors, errors driven by two of them plus noise."""
    rng = np.random.default_rng(seed)
    rows, errors = [], []
    positions = np.array([0.0, 50.0, 100.0, 150.0])
    for r in range(n_runs):
        for m in range(n_measurements):
            t = 20.0 * m
            temps = {
                "S1": 20 + r + 2.0 * (1 - np.exp(-t / 60)) + rng.normal(0, 0.05),
                "S2": 21 + 0.5 * r + 1.0 * (1 - np.exp(-t / 90)) + rng.normal(0, 0.05),
                "S3": 22 - 0.3 * r + 0.2 * t / 100 + rng.normal(0, 0.05),
                "S4": 20 + 0.8 * r + 1.5 * (1 - np.exp(-t / 30)) + rng.normal(0, 0.05),
            }
            rows.append({"run": f"R{r + 1}", "measurement": m + 1, "time_min": t, **temps})
            k = -10 + 3 * (temps["S1"] - 20) - (temps["S3"] - 22)
            b = -1.5 * (temps["S2"] - 21 - 0.5 * r)
            errors.append(
                k * positions / 1000
                + b
                + 0.02 * (positions / 100) ** 2
                + rng.normal(0, 0.05, positions.size)
            )
    return pd.DataFrame(rows), pd.DataFrame(np.array(errors), columns=positions)


def test_batch_rows_are_the_library_functions_metrics():
    X, Y = _inputs()
    grid = replace(
        DEFAULTS.sweep.grid,
        methods=("fuzzy_grey",),
        n_clusters=(2,),
        similarities=("pearson",),
        grades=("deng",),
        degrees=(1,),
        algorithms=("mlr", "ridge"),
    )
    units, _ = sweep_plan.plan_units(grid, ["R2"], ["S1", "S2", "S3", "S4"])
    base = replace(DEFAULTS.selection, pointwise_common=2)
    rows = sweep_run.run_batch(X, Y, units, grid, base, DEFAULTS.models)
    # 1 unit x (decoupled d1 + pointwise) x 2 algorithms; decoupled has k, b, error rows.
    assert len(rows) == 2 * 3 + 2 * 1
    assert (rows["status"] == "ok").all()
    selection = select_for_fold(
        X, Y, "R2", replace(DEFAULTS.selection, n_clusters=2, pointwise_common=2), 1
    )
    for approach in ("decoupled", "pointwise"):
        expected = evaluate_configuration(
            X, Y, "R2", approach, "ridge", selection, DEFAULTS.models, 1
        ).metrics
        got = rows[(rows["approach"] == approach) & (rows["algorithm"] == "ridge")]
        pd.testing.assert_frame_equal(
            got[["target", *METRIC_COLUMNS]].reset_index(drop=True),
            expected[["target", *METRIC_COLUMNS]].reset_index(drop=True),
        )
    # The MLR rows by hand, with numpy least squares on the fold's sensitive points.
    mlr = rows[rows["algorithm"] == "mlr"].set_index(["approach", "target"])
    for (approach, target), residual in _mlr_residuals_by_hand(X, Y, "R2", selection).items():
        assert mlr.loc[(approach, target), "rmse"] == pytest.approx(
            np.sqrt(np.mean(residual**2)), rel=1e-9
        )
        assert mlr.loc[(approach, target), "max_abs"] == pytest.approx(
            np.abs(residual).max(), rel=1e-9
        )


def _mlr_residuals_by_hand(X, Y, fold, selection) -> dict[tuple[str, str], np.ndarray]:
    """Residuals of the held-out run: pointwise, one line per position on the rises of the
    common points; decoupled, k on absolute and b on relative temperatures (the paper's
    Eq. 9 form), from each measurement's least-squares line (x from the first target)."""
    test = (X["run"] == fold).to_numpy()
    rise = X.drop(columns=["run", "measurement", "time_min"]) - X.groupby("run")[
        ["S1", "S2", "S3", "S4"]
    ].transform("first")

    def fit_predict(inputs, target):
        design = np.column_stack([np.ones(len(inputs)), inputs.to_numpy()])
        coef, *_ = np.linalg.lstsq(design[~test], target[~test], rcond=None)
        return design[test] @ coef

    y = Y.to_numpy()
    x_m = (Y.columns.to_numpy(float) - float(Y.columns[0])) / 1000.0
    k, b = np.polyfit(x_m, y.T, 1)
    k_hat = fit_predict(X[list(selection.k_sensors)], k)
    b_hat = fit_predict(rise[list(selection.b_sensors)], b)
    pointwise = fit_predict(rise[list(selection.pointwise)], y)
    return {
        ("pointwise", "error"): (y[test] - pointwise).ravel(),
        ("decoupled", "k"): k[test] - k_hat,
        ("decoupled", "b"): b[test] - b_hat,
        ("decoupled", "error"): (y[test] - (np.outer(k_hat, x_m) + b_hat[:, None])).ravel(),
    }


@pytest.mark.parametrize("algorithm", ["svr", "mlr"])
def test_identical_model_inputs_are_evaluated_once(monkeypatch, algorithm):
    X, Y = _inputs()
    calls = []
    original = folds.fold_metrics

    def counting(*args, **kwargs):
        calls.append(args[2:5])
        return original(*args, **kwargs)

    def counting_sets(function):
        # The batched path's point sets (its last argument): one per distinct evaluation.
        def counted(*args, **kwargs):
            calls.extend(args[-1])
            return function(*args, **kwargs)

        return counted

    monkeypatch.setattr(folds, "fold_metrics", counting)
    for name in ("decoupled_metrics", "pointwise_metrics"):
        monkeypatch.setattr(batched, name, counting_sets(getattr(batched, name)))
    # "all" puts every sensor in k and b, and its pointwise common set is the first
    # pointwise_common (here 4 = all) sensors; "fixed" lists exactly the same sensors.
    # So 2 settings x (decoupled d1 + pointwise) x 1 algorithm = 4 configurations,
    # but only 2 distinct evaluations (svr one by one, mlr batched).
    every = ("S1", "S2", "S3", "S4")
    grid = replace(DEFAULTS.sweep.grid, methods=("all", "fixed"), degrees=(1,), algorithms=(algorithm,),
                           fixed=(("b", every), ("k", every), ("pointwise", every)))  # fmt: skip
    units, _ = sweep_plan.plan_units(grid, ["R1"], list(every))
    rows = sweep_run.run_batch(
        X, Y, units, grid, replace(DEFAULTS.selection, pointwise_common=4), DEFAULTS.models
    )
    assert len(calls) == 2
    assert rows["config_id"].nunique() == 4
    a = rows[rows["method"] == "all"][list(METRIC_COLUMNS)].to_numpy()
    f = rows[rows["method"] == "fixed"][list(METRIC_COLUMNS)].to_numpy()
    np.testing.assert_array_equal(a, f)


def test_summary_does_not_depend_on_the_batch_count():
    X, Y = _inputs()
    grid = replace(
        DEFAULTS.sweep.grid,
        methods=("fuzzy_grey", "correlation"),
        n_clusters=(2, 3),
        similarities=("pearson",),
        grades=("deng", "absolute"),
        degrees=(1, 2),
        algorithms=("mlr",),
    )
    units, _ = sweep_plan.plan_units(grid, ["R1", "R2", "R3"], ["S1", "S2", "S3", "S4"])
    base = replace(DEFAULTS.selection, pointwise_common=2)
    one = sweep_run.collect_summary([sweep_run.run_batch(X, Y, units, grid, base, DEFAULTS.models)])
    parts = [
        sweep_run.run_batch(X, Y, sweep_plan.batch_units(units, 3, b), grid, base, DEFAULTS.models)
        for b in range(3)
    ]
    pd.testing.assert_frame_equal(sweep_run.collect_summary(parts[::-1]), one)
    # 3 folds x (2 fuzzy x 2 grades + 2 correlation) settings x (2 degrees + pointwise)
    # x 1 algorithm.
    assert one.groupby("config_id")["fold"].nunique().eq(3).all()
    assert one["config_id"].nunique() == 6 * 3


def test_a_configuration_the_data_cannot_support_is_recorded_not_fatal():
    X, Y = _inputs()
    # Degree 3 needs four targets per measurement: there are four, so make one NaN in
    # every row of run R1 -> its decoupling fails for degree 3 only.
    Y.loc[X["run"] == "R1", 50.0] = np.nan
    grid = replace(
        DEFAULTS.sweep.grid,
        methods=("all",),
        approaches=("decoupled",),
        degrees=(1, 3),
        algorithms=("mlr",),
    )
    units, _ = sweep_plan.plan_units(grid, ["R2"], ["S1", "S2", "S3", "S4"])
    rows = sweep_run.run_batch(X, Y, units, grid, DEFAULTS.selection, DEFAULTS.models)
    by_degree = rows.groupby("degree")["status"].first()
    assert by_degree.loc[1] == "ok"
    assert by_degree.loc[3] != "ok" and rows.loc[rows["degree"] == 3, "max_abs"].isna().all()


# --------------------------------------------------------------------------- ranking and effects


def _summary_rows():
    def row(config_id, method, algorithm, fold, max_abs, rmse):
        return {
            "config_id": config_id,
            "method": method,
            "n_clusters": 3 if method == "fuzzy_grey" else None,
            "similarity": "pearson" if method == "fuzzy_grey" else None,
            "grade": "deng" if method == "fuzzy_grey" else None,
            "approach": "decoupled",
            "degree": 1,
            "algorithm": algorithm,
            "fold": fold,
            "target": "error",
            "rmse": rmse,
            "max_abs": max_abs,
            "mae": rmse,
            "residual_min": -max_abs,
            "residual_max": max_abs,
            "sensors": "",
            "status": "ok",
        }

    rows = [
        row("A", "fuzzy_grey", "mlr", "E1", 1.0, 0.5),
        row("A", "fuzzy_grey", "mlr", "E2", 3.0, 1.5),
        row("B", "all", "mlr", "E1", 2.0, 1.0),
        row("B", "all", "mlr", "E2", 2.0, 1.0),
        row("C", "all", "svr", "E1", 0.5, 0.2),
        row("D", "all", "svr", "E1", 4.0, 2.0),
        row("D", "all", "svr", "E2", 6.0, 3.0),
    ]
    # A k row must not count: only the error curves rank configurations.
    rows.append({**rows[0], "target": "k", "max_abs": 100.0})
    frame = sweep_run._as_summary_frame(rows)
    frame.loc[len(frame)] = {
        **rows[4],
        "fold": "E2",
        "status": "failed",
        "rmse": np.nan,
        "max_abs": np.nan,
    }
    return frame


def test_ranking_by_mean_max_residual_incomplete_last_ties_by_id():
    main = replace(
        DEFAULTS.selection, method="fuzzy_grey", n_clusters=3, similarity="pearson", grade="deng"
    )
    ranking = sweep_run.rank_configurations(_summary_rows(), main, 1)
    # A: (1 + 3) / 2 = 2, B: (2 + 2) / 2 = 2 (tie -> id order), D: 5, C: one fold only -> last.
    assert ranking["config_id"].tolist() == ["A", "B", "D", "C"]
    assert ranking["rank"].tolist() == [1, 2, 3, 4]
    assert ranking["mean_max_abs"].tolist()[:3] == [2.0, 2.0, 5.0]
    assert ranking["worst_max_abs"].tolist()[:3] == [3.0, 2.0, 6.0]
    assert ranking["mean_rmse"].tolist()[:3] == [1.0, 1.0, 2.5]
    assert ranking["n_folds"].tolist() == [2, 2, 2, 1]
    assert ranking["main_config"].tolist() == [True, False, False, False]


def test_means_equal_to_rounding_tie_and_go_by_id():
    # B's mean is A's plus one part in 1e12 (the same fit computed two ways): a tie, so
    # id order (A, B) holds, although B's mean is numerically the smaller when it is A's minus that.
    main = replace(DEFAULTS.selection, method="fixed")
    frame = _summary_rows()
    frame.loc[(frame["config_id"] == "B") & (frame["target"] == "error"), "max_abs"] = [
        2.0 * (1 - 1e-12),
        2.0 * (1 - 1e-12),
    ]
    ranking = sweep_run.rank_configurations(frame, main, 1)
    assert ranking["config_id"].tolist()[:2] == ["A", "B"]
    # A real difference (one part in 1e6) still ranks B first.
    frame.loc[(frame["config_id"] == "B") & (frame["target"] == "error"), "max_abs"] = [
        2.0 * (1 - 1e-6),
        2.0 * (1 - 1e-6),
    ]
    assert sweep_run.rank_configurations(frame, main, 1)["config_id"].tolist()[:2] == ["B", "A"]


def test_factor_effects_by_hand():
    main = replace(DEFAULTS.selection, method="fixed")
    ranking = sweep_run.rank_configurations(_summary_rows(), main, 1)
    effects = sweep_run.factor_effects(ranking).set_index(["factor", "level"])
    # Complete configurations: A (fuzzy_grey, mlr, 2), B (all, mlr, 2), D (all, svr, 5).
    assert effects.loc[
        ("method", "all"), ["n_configurations", "best", "median", "worst"]
    ].tolist() == [2, 2.0, 3.5, 5.0]
    assert effects.loc[("algorithm", "mlr"), "mean"] == 2.0
    assert effects.loc[("algorithm", "svr"), "n_configurations"] == 1
    # n_clusters applies to A only.
    assert effects.loc["n_clusters"].index.tolist() == ["3"]
    assert not ranking["main_config"].any()


def test_heatmap_holds_the_other_factors_at_the_main_configuration():
    rows = []
    for n in (2, 3):
        for similarity in ("pearson", "printed"):
            for degree in (1, 2):
                for algorithm in ("svr", "mlr"):
                    value = (
                        n * 10
                        + (0 if similarity == "pearson" else 100)
                        + degree
                        + (0.5 if algorithm == "svr" else 0)
                    )
                    rows.append(
                        {
                            "method": "fuzzy_grey",
                            "n_clusters": n,
                            "similarity": similarity,
                            "grade": "deng",
                            "approach": "decoupled",
                            "degree": degree,
                            "algorithm": algorithm,
                            "mean_max_abs": value,
                        }
                    )
    ranking = pd.DataFrame(rows)
    main = replace(
        DEFAULTS.selection, method="fuzzy_grey", n_clusters=3, similarity="printed", grade="deng"
    )
    table = sweep_run.heatmap_table(ranking, "decoupled", main, 2)
    assert table.columns.tolist() == ["mlr", "svr"] and table.index.tolist() == [2, 3]
    # printed (+100), degree 2 (+2): n=2 -> 122, n=3 -> 132; svr adds 0.5.
    np.testing.assert_array_equal(table.to_numpy(), [[122.0, 122.5], [132.0, 132.5]])
    assert table.attrs["held"] == "fuzzy_grey, printed, deng, degree 2"


# --------------------------------------------------------------------------- bench


def test_scaling_fit_by_hand():
    from tools.bench import fit_scaling

    # 5 s + 2 s per run exactly: slope 2, intercept 5, marginal 2 and 2, no quadratic term.
    fit = fit_scaling([10, 5, 20], [25.0, 15.0, 45.0])
    assert (round(fit.slope_s_per_run, 9), round(fit.intercept_s, 9), round(fit.r2, 9)) == (
        2.0,
        5.0,
        1.0,
    )
    assert fit.marginal_s_per_run == [2.0, 2.0] and abs(fit.quadratic_share) < 1e-9
    assert "grows linearly" in fit.statement
    # Pure n^2: the parabola is n^2 itself, so its quadratic term is all of the cost at
    # n = 8; marginal costs (4-1)/1 = 3, (16-4)/2 = 6, (64-16)/4 = 12.
    quadratic = fit_scaling([1, 2, 4, 8], [1.0, 4.0, 16.0, 64.0])
    assert round(quadratic.quadratic_share, 9) == 1.0 and quadratic.marginal_s_per_run == [
        3.0,
        6.0,
        12.0,
    ]
    assert "about quadratically" in quadratic.statement
    # 10 s + n + 0.1 n^2 at n = 10: the quadratic term is 10 of 30 s -> share 1/3.
    some = fit_scaling([2, 5, 10], [10 + n + 0.1 * n * n for n in (2, 5, 10)])
    assert round(some.quadratic_share, 9) == round(1 / 3, 9) and "somewhat faster" in some.statement
    assert "not judged" in fit_scaling([2, 3], [19.0, 24.5]).statement
    with pytest.raises(ValueError, match="two distinct run counts"):
        fit_scaling([5, 5], [1.0, 2.0])


def test_measure_counts_the_whole_process_tree(tmp_path):
    from tools.bench import measure

    # A grandchild (python under sh) holds 300 MiB for a second, so that the tree sampler
    # sees it; no time is asserted (a test never does).
    script = (
        "import time; b = bytearray(300 * 2**20); b[::4096] = b'x' * len(b[::4096]); time.sleep(1)"
    )
    command = ["sh", "-c", f'"{sys.executable}" -c "$0"; exit 3', script]
    m = measure("probe", command, tmp_path, tmp_path / "logs" / "probe.log")
    assert m.returncode == 3 and not m.ok
    assert 300 <= m.peak_rss_mib < 600
    assert m.peak_tree_rss_mib is None or m.peak_tree_rss_mib >= 250


def test_bench_markdown_names_the_cores_and_the_targets():
    from tools.bench import bench_markdown

    doc = {
        "machine": {
            "usable_cores": 2,
            "cpu_count": 2,
            "memory_gib": 8.0,
            "platform": "Linux",
            "python": "3.11",
            "load_average_at_start": [0.1, 0.1, 0.1],
            "load_average_at_end": [0.2, 0.1, 0.1],
        },
        "settings": {"cores": 2},
        "measurements": [
            {
                "name": "results_noop",
                "wall_s": 1.5,
                "cpu_s": 1.2,
                "peak_rss_mib": 200.0,
                "peak_tree_rss_mib": 210.0,
                "extra": {"jobs": 0},
                "ok": True,
                "description": "again",
            }
        ],
        "targets": [{"target": "no-op rerun <= 2 s", "measured": "1.5 s", "met": True}],
    }
    text = bench_markdown(doc)
    assert "2 usable cores" in text and "--cores 2" in text
    assert "| results_noop | 1.5 | 1.2 | 200 | 210 | 0 | yes | again |" in text
    assert "| no-op rerun <= 2 s | 1.5 s | yes |" in text


def test_a_cluster_count_above_the_sensors_that_vary_fails_that_unit_not_the_sweep():
    X, Y = _inputs()
    X["S4"] = 25.0  # constant: three sensors vary
    grid = replace(
        DEFAULTS.sweep.grid,
        methods=("correlation",),
        n_clusters=(3, 4),
        similarities=("pearson",),
        grades=("deng",),
        degrees=(1,),
        algorithms=("mlr",),
    )
    units, _ = sweep_plan.plan_units(grid, ["R2"], ["S1", "S2", "S3", "S4"])
    with pytest.warns(SelectionWarning, match="fold R2: sensor S4 is constant"):
        rows = sweep_run.run_batch(X, Y, units, grid, DEFAULTS.selection, DEFAULTS.models)
    by_count = rows.groupby("n_clusters")["status"].agg(set)
    # A swept count is the count used: 4 is not quietly evaluated as 3.
    assert by_count[3] == {"ok"}
    assert by_count[4] == {
        "selection failed: fold R2: 4 clusters (selection.n_clusters) but only 3 sensors vary "
        "over its training measurements; expected at most 3"
    }
