"""Datasets of other shapes than the paper's: unequal runs, one position, many positions, two
and many runs.

Each test writes a small dataset in the documented layout, runs the library's own
chain (read -> clean -> assemble -> model inputs -> a leave-one-run-out fit) and
checks the numbers against an independent computation (plain numpy least squares,
or counts worked out by hand).
"""

from __future__ import annotations

import re
from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from helpers import DEFAULTS
from helpers.builders import write_dataset
from thermaxis.cleaning.run import clean_and_assemble_run, model_inputs
from thermaxis.config import Settings, load_config
from thermaxis.dataset.plausibility import check_same_targets
from thermaxis.dataset.reader import load_dataset, read_run
from thermaxis.errors import DataError
from thermaxis.method.folds import evaluate_configuration, select_for_fold

CLEANING = Settings.from_config(load_config()).cleaning


def assembled(root):
    dataset = load_dataset(root)
    tables = [
        clean_and_assemble_run(dataset, read_run(dataset, run), CLEANING) for run in dataset.run_ids
    ]
    errors = pd.concat([t.errors for t in tables], ignore_index=True)
    temperatures = pd.concat([t.temperatures for t in tables], ignore_index=True)
    return errors, temperatures


def relative(X, sensors):
    """Temperatures minus each run's first measurement, computed directly."""
    first = (
        X.sort_values("measurement").groupby("run")[list(sensors)].transform("first").loc[X.index]
    )
    return X[list(sensors)].to_numpy(float) - first.to_numpy(float)


def numpy_pointwise(X, Y, fold, sensors):
    """Point-by-point MLR by plain least squares, fitted on every run but ``fold``."""
    train = (X["run"] != fold).to_numpy()
    T = relative(X, sensors)
    A = np.column_stack([np.ones(train.sum()), T[train]])
    out = np.empty((int((~train).sum()), Y.shape[1]))
    for j in range(Y.shape[1]):
        coef, *_ = np.linalg.lstsq(A, Y.to_numpy(float)[train, j], rcond=None)
        out[:, j] = np.column_stack([np.ones(out.shape[0]), T[~train]]) @ coef
    return out


@pytest.mark.parametrize(
    "runs, counts, positions",
    [
        (("A", "B"), (5, 3), (0.0, 50.0, 100.0)),  # two runs of unequal length
        (("R1", "R2", "R3"), (4, 7, 2), (0.0,)),  # one position, unequal runs
        (
            tuple(f"run_{i:02d}" for i in range(1, 8)),
            (3, 4, 5, 3, 6, 4, 3),
            (0.0, 100.0),
        ),  # many runs
        (("A", "B", "C"), (3, 3, 4), tuple(np.linspace(0.0, 900.0, 46))),  # many positions
    ],
)
def test_shapes_assemble_and_predict_like_numpy(tmp_path, runs, counts, positions):
    root = write_dataset(
        tmp_path / "ds", runs=runs, n_measurements=counts, positions=positions, two_passes=False
    )
    errors, temperatures = assembled(root)
    X, Y = model_inputs(errors, temperatures)
    # One row per measurement that exists: no padding to the longest run.
    assert len(X) == sum(counts)
    assert X.groupby("run").size().to_dict() == dict(zip(runs, counts, strict=True))
    assert Y.shape == (sum(counts), len(positions))
    sensors = ("S1", "S2")
    selection = select_for_fold(
        X,
        Y,
        runs[-1],
        replace(
            DEFAULTS.selection,
            method="fixed",
            fixed=(("pointwise", sensors), ("k", sensors), ("b", sensors)),
        ),
        1,
        decoupled=False,
    )
    result = evaluate_configuration(
        X, Y, runs[-1], "pointwise", "mlr", selection, DEFAULTS.models, 1
    )
    predicted = result.error_predictions["predicted"].to_numpy().reshape(counts[-1], len(positions))
    np.testing.assert_allclose(predicted, numpy_pointwise(X, Y, runs[-1], sensors), atol=1e-6)


def test_runs_with_different_targets_are_refused_naming_the_run(tmp_path):
    a = write_dataset(tmp_path / "a", runs=("A",), positions=(0.0, 50.0, 100.0))
    b = write_dataset(tmp_path / "b", runs=("B",), positions=(0.0, 50.0, 120.0))
    errors = pd.concat([assembled(a)[0], assembled(b)[0]], ignore_index=True)
    with pytest.raises(
        DataError,
        match=r"^data/B/errors: run B reads 3 target positions, run A 3 "
        r"\(120 mm is not a target of run A\)",
    ):
        check_same_targets(errors, "data")


def test_single_position_common_set_follows_the_ranking_not_the_names(tmp_path):
    """One position, five sensors; the error follows Z9 best, then Z1: the common set must be
    (Z9, Z1)."""

    def temperature(r, s, minutes):
        # Z9 (s=4) is the error's driver, Z1 (s=0) a noisy copy, the rest unrelated wiggles.
        base = (1.0 + r) * (1.0 - np.exp(-minutes / 40.0))
        return (
            20.0
            + np.where(s == 4, base, 0.0)
            + np.where(s == 0, base + 0.05 * np.sin(minutes), 0.0)
            + (0.0 if s in (0, 4) else 0.3 * np.sin(minutes / (7.0 + s)))
        )

    def curve(r, m, x):
        return np.full(x.shape, -2.0 * (1.0 + r) * (1.0 - np.exp(-20.0 * m / 40.0)))

    root = write_dataset(
        tmp_path / "one",
        runs=("R1", "R2", "R3"),
        sensors=("Z1", "A2", "B3", "C4", "Z9"),
        positions=(0.0,),
        n_measurements=6,
        curve=curve,
        temperature=temperature,
        two_passes=False,
    )
    X, Y = model_inputs(*assembled(root))
    settings = replace(DEFAULTS.selection, method="correlation", n_clusters=4, pointwise_common=2)
    selection = select_for_fold(X, Y, "R3", settings, 1, decoupled=False)
    assert selection.pointwise == ("Z9", "Z1")


def _into_one_errors_file(root, run, edit=lambda frame: frame):
    """Move a run's measurement files into one ``<run>/errors.csv`` (the fl_thermal layout);
    ``edit`` may change its rows."""
    frames = []
    for f in sorted((root / run / "errors").glob("*.csv")):
        frames.append(pd.read_csv(f, dtype=str).assign(measurement=f.stem))
        f.unlink()
    (root / run / "errors").rmdir()
    edit(pd.concat(frames, ignore_index=True)).to_csv(root / run / "errors.csv", index=False)
    return root / run / "errors.csv"


def test_errors_in_one_file_per_run_read_like_one_file_per_measurement(tmp_path):
    root = write_dataset(tmp_path / "ds", runs=("A", "B"), n_measurements=(3, 2))
    dataset = load_dataset(root)
    before = read_run(dataset, "A").measurements
    _into_one_errors_file(root, "A")
    after = read_run(dataset, "A").measurements
    assert list(after) == list(before) == ["M01", "M02", "M03"]
    for name in before:
        pd.testing.assert_frame_equal(after[name], before[name])


def _one_file_run(tmp_path, edit=lambda frame: frame):
    """Runs A (one file per measurement) and B (one errors.csv, rows changed by ``edit``)."""
    root = write_dataset(
        tmp_path / "ds", runs=("A", "B"), n_measurements=3, positions=(0.0, 50.0, 100.0, 150.0)
    )
    return load_dataset(root), _into_one_errors_file(root, "B", edit)


def test_cleaning_messages_of_a_run_in_one_errors_file_name_that_file(tmp_path):
    def edit(f):
        # M02 loses its backward reading at 50 mm, M03 every reading but those at 0 mm.
        position = f["position_mm"].astype(float)
        m02_gap = (f["measurement"] == "M02") & (f["direction"] == "-") & (position == 50.0)
        return f[~(m02_gap | ((f["measurement"] == "M03") & (position != 0.0)))]

    dataset, one_file = _one_file_run(tmp_path, edit)
    raw = read_run(dataset, "B")
    assert raw.error_files == dict.fromkeys(["M01", "M02", "M03"], one_file)
    with pytest.raises(
        ValueError,
        match=re.escape(f"measurement M03 in {one_file}: 3 of 4 targets have no reading"),
    ):
        clean_and_assemble_run(dataset, raw, CLEANING)
    relaxed = replace(CLEANING, errors=replace(CLEANING.errors, max_missing_fraction=1.0))
    notes = clean_and_assemble_run(dataset, raw, relaxed).notes
    assert (
        f"measurement M02 in {one_file}: position 50 mm has no - reading; using the + reading alone"
        in notes
    )
    # A measurement in its own file is named by that file.
    (dataset.root / "A" / "errors" / "M02.csv").write_text(
        "time,position_mm,error_um\n2022-05-10T09:20:00,0,0\n"
    )
    own = dataset.root / "A" / "errors" / "M02.csv"
    with pytest.raises(
        ValueError, match=re.escape(f"measurement {own}: 3 of 4 targets have no reading")
    ):
        clean_and_assemble_run(dataset, read_run(dataset, "A"), CLEANING)


def test_checks_of_a_run_in_one_errors_file_name_that_file_and_the_line(tmp_path):
    from thermaxis.dataset.plausibility import check_run_plausibility, check_same_targets

    def edit(f):
        f.loc[f.index[-2], "error_um"] = "5000"  # M03's last-but-one reading
        return f

    dataset, one_file = _one_file_run(tmp_path, edit)
    lines = one_file.read_text().splitlines()
    line = next(i for i, row in enumerate(lines, start=1) if ",5000," in row)
    assert line == len(lines) - 1
    with pytest.raises(
        DataError, match=re.escape(f"{one_file}: line {line}, column 'error_um': 5000 um is beyond")
    ):
        check_run_plausibility(dataset, read_run(dataset, "B"), CLEANING)
    errors = pd.DataFrame({"run": ["A", "A", "B"], "position_mm": [0.0, 50.0, 0.0]})
    with pytest.raises(
        DataError, match=re.escape(f"{one_file}: run B reads 1 target positions, run A 2")
    ):
        check_same_targets(errors, dataset.root)


def test_condition_is_a_label_and_feed_optional(tmp_path):
    root = write_dataset(tmp_path / "ds", runs=("A", "B"))
    (root / "runs.tsv").write_text(
        "run\tcondition\tspindle_rpm\tdescription\nA\tcold start\t1500\tx\nB\twarm\t\ty\n"
    )
    dataset = load_dataset(root)
    assert dataset.condition_of("A") == "cold start"
    assert dataset.descriptors == ("spindle_rpm",)
    assert dataset.runs["spindle_rpm"].tolist()[0] == 1500.0 and np.isnan(
        dataset.runs["spindle_rpm"].tolist()[1]
    )
