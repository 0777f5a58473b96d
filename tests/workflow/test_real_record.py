"""Issue 24's acceptance: records shaped like a machine builder's logger export run through.

5 runs, 22 channels logged every 5 minutes at 0.1 °C, every channel rising to its last
sample (``helpers.builders.write_real_record``): the old spike filter took each record's
last sample for a spike and refused every run. The default configuration (the schema's
defaults, config/config.yaml) runs through cleaning, assembly, decoupling, selection and
every algorithm's held-out fit (target ``tables/metrics.csv``; the figures and reports of
``all`` add nothing to what is checked here and would multiply the run time), and the
only samples flagged are the spikes the generator put in.
"""

from __future__ import annotations

import pandas as pd
import yaml

from helpers.builders import REAL_RUNS, REAL_SENSORS, REAL_SPIKES, write_real_record
from helpers.workflow import run_snakemake, workflow_workdir


def test_the_default_workflow_runs_on_a_real_records_shape_flagging_only_true_spikes(tmp_path):
    dataset = write_real_record(tmp_path / "real")
    work = workflow_workdir(tmp_path)
    config = work / "real.yaml"
    config.write_text(yaml.safe_dump({"dataset": str(dataset), "ambient_sensor": "T1"}))
    run_snakemake(
        work, "--configfile", str(config), "--", "results/real/tables/metrics.csv",
        "results/real/tables/cleaning_qc.csv",
    )  # fmt: skip
    out = work / "results" / "real" / "tables"
    qc = pd.read_csv(out / "cleaning_qc.csv")
    sensors = qc[qc["sensor"] != "error_um"]
    flagged = sorted(
        (row.run, row.sensor) for row in sensors.itertuples() for _ in range(row.n_spikes)
    )
    truth = sorted((REAL_RUNS[r], REAL_SENSORS[s]) for r, s, _, _ in REAL_SPIKES)
    assert flagged == truth
    assert len(sensors) == len(REAL_RUNS) * len(REAL_SENSORS)
    assert (qc["sensor"] == "error_um").sum() == 0  # the displacements are fault-free too
    metrics = pd.read_csv(out / "metrics.csv")
    assert sorted(metrics["fold"].unique()) == list(REAL_RUNS)
