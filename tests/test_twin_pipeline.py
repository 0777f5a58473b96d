"""The first half of the chain on the simulated twin, checked against the twin's truth.

Tests may read data/twin_truth/ (the modelling code never does): cleaning must recover
the fault-free sensor temperatures, and decoupling the noise-free k and b.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from conftest import REPO
from thermaxis.assemble import clean_and_assemble_run, model_inputs
from thermaxis.config import load_config
from thermaxis.decouple import decouple_table
from thermaxis.io import load_dataset, read_run
from thermaxis.models import DecoupledAxisModel

TWIN = REPO / "data" / "raw" / "twin"
TRUTH = REPO / "data" / "twin_truth"

pytestmark = pytest.mark.skipif(not (TWIN / "dataset.yaml").is_file(), reason="data/raw/twin not generated")


@pytest.fixture(scope="module")
def twin_tables():
    config = load_config()
    dataset = load_dataset(TWIN)
    return dataset, {run: clean_and_assemble_run(dataset, read_run(dataset, run), config) for run in dataset.run_ids}


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
    kb, _ = decouple_table(errors)
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
    kb, _ = decouple_table(errors)
    assert (kb["rms_um"] > 0.01).all()
    assert kb["r2"].median() > 0.9


def test_papers_mlr_does_not_reproduce_the_twin_exactly(twin_tables):
    _, tables = twin_tables
    errors = pd.concat([t.errors for t in tables.values()], ignore_index=True)
    temperatures = pd.concat([t.temperatures for t in tables.values()], ignore_index=True)
    X, Y = model_inputs(errors, temperatures)
    train = (X["run"] != "E4").to_numpy()
    model = DecoupledAxisModel(k_sensors=("T1", "T6", "T12"), b_sensors=("T2", "T7", "T11"), algorithm="mlr")
    model.fit(X.loc[train], Y.loc[train])
    residual = Y.loc[~train].to_numpy() - model.predict(X.loc[~train])
    rmse = float(np.sqrt(np.nanmean(residual**2)))
    # Hidden drivers, lagging noisy sensors: the held-out condition is predicted, not reproduced.
    assert rmse > 0.05
