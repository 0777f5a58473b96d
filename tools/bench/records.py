"""The recommendation against two plain references and the paper's, on every record at hand.

Issue 61's figures: on every embedded dataset, and on the public FL_THERMAL record's five
displacement channels (``data/sources/fl_thermal``, imported with the embedded
mapping ``data/import/fl_thermal.yaml``, channel swapped, 6 runs cut by speed step, the
spindle-speed signal dropped after the cut; the embedded ``fl_thermal`` is channel 1 with
it), the recommendation's mean held-out RMSE against the two plain references
(``baseline-ridge+lags``: a ridge over every sensor's rise and its causal lags at
20/60/180 min, strength by inner leave-one-condition-out; ``evidence-ridge``: the
evidence-maximising ridge over every sensor and the declared signals) and against the
paper's configuration, each on the same outer folds. Every figure is read from the
workflow's own tables (``tables/recommendation.csv``, ``recommend/candidates.csv``).
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pandas as pd
import yaml

from thermaxis.method.candidates import BASELINE, EVIDENCE
from thermaxis.pipeline import paths
from tools.bench.scaling import generate_command

__all__ = [
    "CHANNELS",
    "DEV_RECORDS",
    "channel_mapping",
    "meets_targets",
    "dev_records",
    "record_quality",
    "RECORD_TARGETS",
    "without_signals",
]

CHANNELS = (1, 2, 3, 4, 5)
# Issue 61's bounds: at most 1.10 x the better plain reference, at most the paper's configuration.
RECORD_TARGETS = {"references": 1.10, "paper": 1.0}

# Simulated development records (runs, sensors, positions, seed): what a change of the
# combination rule is judged on before it meets a scored record. Shapes of a logger record
# (5 h at 0.1 Hz, a measurement every 10 min), 5 to 12 runs, seeds apart from the twin's.
DEV_RECORDS = ((5, 8, 1, 11), (6, 24, 1, 12), (6, 12, 5, 13), (8, 24, 1, 14),
               (10, 16, 3, 15), (7, 10, 1, 16), (12, 24, 1, 17), (6, 6, 1, 18))  # fmt: skip
DEV_LOGGER = {"hours": 5.0, "rate_hz": 0.1, "measurement_min": 10.0}


def meets_targets(vs_references: float, vs_paper: float) -> bool:
    """Whether a recommendation's ratios to the better reference and to the paper's
    configuration are within :data:`RECORD_TARGETS`."""
    return vs_references <= RECORD_TARGETS["references"] and vs_paper <= RECORD_TARGETS["paper"]


def channel_mapping(mapping: Path, channel: int) -> dict:
    """The embedded FL_THERMAL import mapping with displacement channel ``channel`` as the error.

    Paths of the mapping are relative to its file; they are made absolute so the mapping
    can be written anywhere.
    """
    spec = yaml.safe_load(mapping.read_text(encoding="utf-8"))
    for key in ("source", "licence_file"):
        spec[key] = str((mapping.parent / spec[key]).resolve())
    spec["name"] = f"{spec['name']}_ch{channel}"
    (column,) = spec["errors"]["columns"]
    column["column"] = column["column"].replace("ch1", f"ch{channel}")
    spec["axis"]["interferometer"] = f"none; displacement sensor channel ch{channel} at the tool"
    spec["description"] += f" (bench copy: displacement channel ch{channel} imported as the error.)"
    return spec


def without_signals(dataset: Path) -> None:
    """Drop a dataset's operating signals (its declaration and every run's logs), in place.

    The runs were cut by the signal at import; without it the candidates see temperatures
    alone, as on a machine that logs no speed.
    """
    spec_path = dataset / "dataset.yaml"
    spec = yaml.safe_load(spec_path.read_text(encoding="utf-8"))
    spec.pop("signals", None)
    spec_path.write_text(
        yaml.safe_dump(spec, sort_keys=False, allow_unicode=True), encoding="utf-8"
    )
    for logs in dataset.glob("*/signals"):
        shutil.rmtree(logs)


def record_quality(results: Path) -> dict:
    """Mean held-out RMSE (µm) of the recommendation, the two plain references and the
    paper's, and the deployment verdict of the compensation (``compensation/model.json``)."""
    folds = pd.read_csv(results / paths.RECOMMENDATION)
    candidates = pd.read_csv(results / paths.CANDIDATES).set_index("candidate")
    recommended = float(folds["rmse_um"].mean())
    baseline = float(candidates.loc[BASELINE, "loco_rmse_um"])
    evidence = float(candidates.loc[EVIDENCE, "loco_rmse_um"])
    paper = float(folds["paper_rmse_um"].mean())
    better = min(baseline, evidence)
    verdict = json.loads((results / paths.DEPLOYED_MODEL).read_text(encoding="utf-8"))[
        "deployment"
    ]["verdict"]
    return {
        "record": results.name,
        "folds": int(len(folds)),
        "recommended_rmse_um": recommended,
        "baseline_rmse_um": baseline,
        "evidence_rmse_um": evidence,
        "paper_rmse_um": paper,
        "vs_references": recommended / better,
        "vs_paper": recommended / paper,
        "met": meets_targets(recommended / better, recommended / paper),
        "verdict": verdict["outcome"],
        "improved_runs": int(verdict["improved_runs"]),
        "worsened_runs": int(verdict["worsened_runs"]),
        "held_out_runs": int(verdict["held_out_runs"]),
        "untested_runs": int(verdict["untested_runs"]),
        "sign_test_p": float(verdict["sign_test_p"]),
    }


def import_channels(repo: Path, scratch: Path, env: dict, timeout_s: float) -> list[Path]:
    """FL_THERMAL channels 1-5 without the speed signal as datasets under ``scratch``, from
    the record in data/sources."""
    mapping = repo / "data" / "import" / "fl_thermal.yaml"
    out = []
    for channel in CHANNELS:
        spec = channel_mapping(mapping, channel)
        path = scratch / "mappings" / f"{spec['name']}.yaml"
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(yaml.safe_dump(spec, sort_keys=False, allow_unicode=True), encoding="utf-8")
        target = scratch / "data" / spec["name"]
        subprocess.run(
            [sys.executable, "-m", "thermaxis.cli", "import", str(path), "--out", str(target)],
            env=env, check=True, capture_output=True, timeout=timeout_s,
        )  # fmt: skip
        without_signals(target)
        out.append(target)
    return out


def dev_records(scratch: Path, env: dict, timeout_s: float) -> list[Path]:
    """The :data:`DEV_RECORDS` as datasets under ``scratch``, SIMULATED by ``thermaxis.twin
    scale`` and named ``dev_r<runs>_s<sensors>_p<positions>_seed<seed>``."""
    out = []
    for runs, sensors, positions, seed in DEV_RECORDS:
        name = f"dev_r{runs}_s{sensors}_p{positions}_seed{seed}"
        target = scratch / name
        shutil.rmtree(target, ignore_errors=True)
        shape = {"sensors": sensors, "positions": positions, "seed": seed, **DEV_LOGGER}
        subprocess.run(generate_command(target, runs, shape), env=env, check=True,
                       capture_output=True, timeout=timeout_s)  # fmt: skip
        spec_path = target / "dataset.yaml"
        spec = yaml.safe_load(spec_path.read_text(encoding="utf-8"))
        spec["name"] = name
        spec["description"] = "SIMULATED development record. " + spec["description"]
        spec_path.write_text(
            yaml.safe_dump(spec, sort_keys=False, allow_unicode=True), encoding="utf-8"
        )
        out.append(target)
    return out


def run_records(
    datasets: list[Path],
    work: Path,
    snakemake: Callable[..., list[str]],
    measure: Callable,
    logs: Path,
    env: dict,
    timeout_s: float,
) -> list[tuple]:
    """Run each dataset's recommendation in ``work``: (measurement, quality or None) per dataset."""
    rows = []
    for dataset in datasets:
        name = yaml.safe_load((dataset / "dataset.yaml").read_text(encoding="utf-8"))["name"]
        targets = [
            paths.under(f"results/{name}", path)
            for path in (paths.RECOMMENDATION, paths.CANDIDATES, paths.DEPLOYED_MODEL)
        ]
        m = measure(
            f"records_{name}",
            snakemake("--config", f"dataset={dataset}", "--", *targets),
            work,
            logs / f"records_{name}.log",
            f"the recommendation of {name}, from its raw files to its compensation verdict",
            env,
            timeout_s,
        )
        rows.append((m, record_quality(work / "results" / name) if m.ok else None))
    return rows
