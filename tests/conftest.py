"""Shared test helpers: tiny datasets in the documented raw layout, written from known truth."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml

REPO = Path(__file__).resolve().parents[1]
SNAKEMAKE = str(Path(sys.executable).with_name("snakemake"))
# 2023-11-14T22:13:20Z: pins the run time recorded in provenance and reports, the one
# field that is otherwise meant to differ between runs.
FIXED_EPOCH = "1700000000"


def workflow_workdir(tmp_path: Path) -> Path:
    """A scratch copy of the workflow's entry points (symlinks), so results stay in tmp."""
    work = tmp_path / "work"
    (work / "data").mkdir(parents=True)
    for name in ("Snakefile", "config", "workflow", "notebooks"):
        os.symlink(REPO / name, work / name)
    os.symlink(REPO / "data" / "paper", work / "data" / "paper")
    return work


def snakemake_env() -> dict:
    env = {**os.environ, "MPLBACKEND": "Agg", "PYTHONHASHSEED": "0", "SOURCE_DATE_EPOCH": FIXED_EPOCH}
    env["PATH"] = f"{Path(sys.executable).parent}:{env['PATH']}"
    return env


def run_snakemake(work: Path, *args, check=True, env=None, timeout=900) -> subprocess.CompletedProcess:
    proc = subprocess.run(
        [SNAKEMAKE, "--cores", "2", "--nolock", *args],
        cwd=work,
        capture_output=True,
        text=True,
        env=env or snakemake_env(),
        timeout=timeout,
    )
    if check and proc.returncode != 0:
        raise AssertionError(f"snakemake failed:\n{proc.stdout[-3000:]}\n{proc.stderr[-5000:]}")
    return proc


def set_csv_cell(path: Path, line: int, field: int, value: str) -> None:
    """Overwrite one cell of a CSV file (``line`` is the 0-based line index, header = 0)."""
    lines = Path(path).read_text().splitlines()
    fields = lines[line].split(",")
    fields[field] = value
    lines[line] = ",".join(fields)
    Path(path).write_text("\n".join(lines) + "\n")


def write_dataset(
    root: Path,
    *,
    runs=("R1", "R2"),
    sensors=("S1", "S2", "S3"),
    positions=(0.0, 50.0, 100.0, 150.0),
    n_measurements=4,
    interval_min=20.0,
    curve=None,
    temperature=None,
    name="tiny",
    kind="simulated",
    two_passes=True,
    reproduces=None,
) -> Path:
    """Write a small, fault-free dataset.

    ``n_measurements`` is one count for every run, or one count per run (runs of
    unequal length).  ``curve(run_index, measurement_index, positions) -> errors`` gives the error of
    each measurement; ``temperature(run_index, sensor_index, minutes) -> degC`` the
    sensor logs (sampled every 10 s). Defaults: exact lines and smooth ramps.
    """
    root = Path(root)
    root.mkdir(parents=True, exist_ok=True)
    positions = np.asarray(positions, dtype=float)
    if curve is None:
        def curve(r, m, x):
            return (-10.0 + 0.5 * m + r) * (x - x[0]) / 1000.0 + (-0.7 * m - 0.1 * r)
    if temperature is None:
        def temperature(r, s, minutes):
            return 20.0 + r + 0.5 * s + (1.0 + 0.3 * s) * (1.0 - np.exp(-minutes / (60.0 + 10 * s)))
    meta = {
        "name": name,
        "description": "Tiny test dataset.",
        "provenance": {"kind": kind, "citation": "tests"},
        **({"reproduces": reproduces} if reproduces else {}),
        "axis": {"name": "X"},
        "sensors": [{"id": s, "location": f"loc {s}", "source": "box"} for s in sensors],
        "sources": [{"name": "box", "clock_note": "reference", "clock_offset_s": 0}],
    }
    (root / "dataset.yaml").write_text(yaml.safe_dump(meta, sort_keys=False))
    lines = ["run\tcondition\tfeed_mm_min\tdescription"]
    for i, run in enumerate(runs, start=1):
        lines.append(f"{run}\t{i}\t{1000 * i}\trun {run}")
    (root / "runs.tsv").write_text("\n".join(lines) + "\n")
    t0 = pd.Timestamp("2022-05-10T09:00:00")
    counts = [n_measurements] * len(runs) if np.ndim(n_measurements) == 0 else list(n_measurements)
    for r, (run, n_run) in enumerate(zip(runs, counts)):
        total = interval_min * (n_run - 1) + 10
        (root / run / "temperatures").mkdir(parents=True, exist_ok=True)
        (root / run / "errors").mkdir(parents=True, exist_ok=True)
        seconds = np.arange(-300, total * 60 + 300, 10.0)
        frame = pd.DataFrame({"time": (t0 + pd.to_timedelta(seconds, unit="s")).strftime("%Y-%m-%dT%H:%M:%S")})
        for s, sensor in enumerate(sensors):
            frame[sensor] = temperature(r, s, seconds / 60.0)
        frame.to_csv(root / run / "temperatures" / "box.csv", index=False, float_format="%.6f")
        for m in range(n_run):
            start = t0 + pd.Timedelta(minutes=interval_min * m)
            err = curve(r, m, positions)
            rows = []
            passes = [("+", positions, err), ("-", positions[::-1], err[::-1])] if two_passes else [("+", positions, err)]
            k = 0
            for direction, xs, es in passes:
                for x, e in zip(xs, es):
                    rows.append(((start + pd.Timedelta(seconds=5 * k)).strftime("%Y-%m-%dT%H:%M:%S"), x, e, direction))
                    k += 1
            pd.DataFrame(rows, columns=["time", "position_mm", "error_um", "direction"]).to_csv(
                root / run / "errors" / f"M{m + 1:02d}.csv", index=False, float_format="%.12g"
            )
    return root


@pytest.fixture
def tiny_dataset(tmp_path):
    return write_dataset(tmp_path / "tiny")
