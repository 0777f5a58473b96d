"""Issue 24's acceptance: records shaped like a machine builder's logger export run through.

5 runs, 22 channels logged every 5 minutes at 0.1 °C, every channel rising to its last
sample (``helpers.builders.write_real_record``): the old spike filter took each record's
last sample for a spike and refused every run. The default configuration (the schema's
defaults, config/config.yaml) runs through cleaning, assembly, decoupling, selection and
every algorithm's held-out fit (target ``tables/metrics.csv``; the figures and reports of
``all`` add nothing to what is checked here and would multiply the run time), and the
only samples flagged are the spikes the generator put in.

One run serves both tests: the record with issue 33's excursion and long gap added, which
must not be taken for spikes either.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest
import yaml

from helpers.builders import REAL_RUNS, REAL_SENSORS, REAL_SPIKES, write_real_record
from helpers.workflow import run_snakemake, workflow_workdir


def _shift_readings(box, first_min, last_min, change):
    """Apply ``change`` to one sensor's readings from ``first_min`` to ``last_min`` (minutes
    after the first measurement, 09:00), in the logger file ``box``."""
    frame = pd.read_csv(box, dtype={"time": str})
    minutes = (
        pd.to_datetime(frame["time"]) - pd.Timestamp("2022-05-10T09:00:00")
    ).dt.total_seconds() / 60
    inside = (minutes >= first_min) & (minutes <= last_min)
    change(frame, inside.to_numpy())
    frame.to_csv(box, index=False)
    return pd.to_datetime(frame.loc[inside, "time"])


@pytest.fixture(scope="module")
def real(tmp_path_factory):
    """Issue 33: the 5-run x 22-sensor record, with one sensor 1.5 C above its trend for
    20 minutes (four 5-minute readings) in R2 and another's readings missing for 1,200 s
    over a measurement in R4, run by default to its metrics, cleaning tables and
    recommendation."""
    tmp_path = tmp_path_factory.mktemp("real")
    dataset = write_real_record(tmp_path / "real")

    def raise_t8(frame, inside):
        frame.loc[inside, "T8"] = (frame.loc[inside, "T8"] + 1.5).round(1)

    def blank_t15(frame, inside):
        frame.loc[inside, "T15"] = np.nan

    excursion = _shift_readings(dataset / "R2" / "temperatures" / "box.csv", 100, 120, raise_t8)
    gap = _shift_readings(dataset / "R4" / "temperatures" / "box.csv", 60, 75, blank_t15)
    work = workflow_workdir(tmp_path)
    config = work / "real.yaml"
    config.write_text(yaml.safe_dump({"dataset": str(dataset), "ambient_sensor": "T1"}))
    proc = run_snakemake(
        work, "--configfile", str(config), "--", "results/real/tables/metrics.csv",
        "results/real/tables/cleaning_qc.csv", "results/real/tables/cleaning_events.csv",
        "results/real/tables/recommendation.csv",
    )  # fmt: skip
    return SimpleNamespace(out=work / "results" / "real" / "tables", proc=proc,
                           excursion=excursion, gap=gap)  # fmt: skip


def test_the_default_workflow_runs_on_a_real_records_shape_flagging_only_true_spikes(real):
    out = real.out
    qc = pd.read_csv(out / "cleaning_qc.csv")
    # The excursion and the gap are findings of their own rows (test below), not spikes.
    findings = qc[qc["finding"].notna()]
    assert sorted(zip(findings["run"], findings["sensor"], findings["finding"], strict=True)) == [
        ("R2", "T8", "excursion"), ("R4", "T15", "unusable")
    ]  # fmt: skip
    sensors = qc[(qc["sensor"] != "error_um") & qc["finding"].isna()]
    flagged = sorted(
        (row.run, row.sensor) for row in sensors.itertuples() for _ in range(int(row.n_spikes))
    )
    truth = sorted((REAL_RUNS[r], REAL_SENSORS[s]) for r, s, _, _ in REAL_SPIKES)
    assert flagged == truth
    assert len(sensors) == len(REAL_RUNS) * len(REAL_SENSORS)
    assert (qc["sensor"] == "error_um").sum() == 0  # the displacements are fault-free too
    metrics = pd.read_csv(out / "metrics.csv")
    assert sorted(metrics["fold"].unique()) == list(REAL_RUNS)


def test_an_excursion_and_a_long_gap_of_one_sensor_cost_that_sensor_only(real):
    # Both are named; the dataset runs by default.
    excursion, gap, out, proc = real.excursion, real.gap, real.out, real.proc
    assert len(excursion) == 4
    assert len(gap) == 3  # readings at 58 and 78 min remain: a 1,200 s gap over 60-70 min
    events = pd.read_csv(out / "cleaning_events.csv", parse_dates=["start", "end"])
    assert events["finding"].tolist() == ["excursion", "unusable"]
    row = events.iloc[0]
    assert (row["run"], row["sensor"]) == ("R2", "T8")
    assert (row["start"], row["end"]) == (excursion.iloc[0], excursion.iloc[-1])
    assert abs(row["size_c"] - 1.5) <= 0.15 and row["action"] == "kept as data"
    row = events.iloc[1]
    assert (row["run"], row["sensor"]) == ("R4", "T15")
    assert "1200 s gap" in row["cause"] and "max_gap_s" in row["cause"]
    warnings = [line for line in proc.stderr.splitlines() if "thermaxis warning:" in line]
    assert any("T8" in w and "excursion" in w for w in warnings)
    assert any("T15" in w and "leaves the candidate sensors" in w for w in warnings)
    # T15 is no candidate of any fold; every fold still has its sensitive points.
    points = pd.read_csv(out / "sensitive_points.csv")
    assert sorted(points["fold"].unique()) == list(REAL_RUNS)
    assert not points.astype(str).apply(lambda c: c.str.contains(r"\bT15\b")).any().any()
    assert sorted(pd.read_csv(out / "recommendation.csv")["fold"]) == list(REAL_RUNS)
