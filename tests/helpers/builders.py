"""Tiny datasets in the documented raw layout, written from known truth, and table edits."""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pandas as pd
import yaml

from helpers.truth import SENSORS
from thermaxis.config import FallbackSettings


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
    log_interval_s=10.0,
    log_start_s=-300.0,
    log_end_margin_s=300.0,
) -> Path:
    """Write a small, fault-free dataset.

    ``n_measurements`` is one count for every run, or one count per run (runs of
    unequal length).  ``curve(run_index, measurement_index, positions) -> errors`` gives
    the error of each measurement; ``temperature(run_index, sensor_index, minutes) -> degC``
    the sensor logs, sampled every ``log_interval_s`` from ``log_start_s`` (seconds from
    the first measurement) to the last sample before ``log_end_margin_s`` after the last
    measurement's start + 10 min. Defaults: exact lines and smooth ramps.
    """
    root = Path(root)
    root.mkdir(parents=True, exist_ok=True)
    positions = np.asarray(positions, dtype=float)
    if curve is None:

        def curve(r, m, x):
            return (-10.0 + 0.5 * m + r) * (x - x[0]) / 1000.0 + (-0.7 * m - 0.1 * r)

    if temperature is None:

        def temperature(r, s, minutes):
            rise = (1.0 + 0.3 * s) * (1.0 - np.exp(-minutes / (60.0 + 10 * s)))
            return 20.0 + r + 0.5 * s + rise

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
    for r, (run, n_run) in enumerate(zip(runs, counts, strict=True)):
        total = interval_min * (n_run - 1) + 10
        (root / run / "temperatures").mkdir(parents=True, exist_ok=True)
        (root / run / "errors").mkdir(parents=True, exist_ok=True)
        seconds = np.arange(log_start_s, total * 60 + log_end_margin_s, log_interval_s)
        times = t0 + pd.to_timedelta(seconds, unit="s")
        frame = pd.DataFrame({"time": times.strftime("%Y-%m-%dT%H:%M:%S")})
        for s, sensor in enumerate(sensors):
            frame[sensor] = temperature(r, s, seconds / 60.0)
        frame.to_csv(root / run / "temperatures" / "box.csv", index=False, float_format="%.6f")
        for m in range(n_run):
            start = t0 + pd.Timedelta(minutes=interval_min * m)
            err = curve(r, m, positions)
            passes = [("+", positions, err)]
            if two_passes:
                passes.append(("-", positions[::-1], err[::-1]))
            rows = []
            k = 0
            for direction, xs, es in passes:
                for x, e in zip(xs, es, strict=True):
                    when = (start + pd.Timedelta(seconds=5 * k)).strftime("%Y-%m-%dT%H:%M:%S")
                    rows.append((when, x, e, direction))
                    k += 1
            table = pd.DataFrame(rows, columns=["time", "position_mm", "error_um", "direction"])
            table.to_csv(
                root / run / "errors" / f"M{m + 1:02d}.csv", index=False, float_format="%.12g"
            )
    return root


def set_csv_cell(path: Path, line: int, field: int, value: str) -> None:
    """Overwrite one cell of a CSV file (``line`` is the 0-based line index, header = 0)."""
    lines = Path(path).read_text().splitlines()
    fields = lines[line].split(",")
    fields[field] = value
    lines[line] = ",".join(fields)
    Path(path).write_text("\n".join(lines) + "\n")


def synthetic_temperatures(
    runs=("E1", "E2", "E3", "E4"), n_measurements=8, seed=20220510
) -> pd.DataFrame:
    """Smooth warming curves plus a slow random walk per sensor, so sensors are not collinear.

    The columns are the paper's sensors (``helpers.truth.SENSORS``), one row per measurement.
    """
    rng = np.random.default_rng(seed)
    t = np.arange(n_measurements) / (n_measurements - 1)
    rows = []
    for run in runs:
        base = rng.uniform(26.0, 32.0) + rng.normal(0.0, 1.0, len(SENSORS))
        rise = rng.uniform(0.5, 6.0, len(SENSORS))
        tau = rng.uniform(0.2, 1.0, len(SENSORS))
        walk = np.cumsum(rng.normal(0.0, 0.15, (n_measurements, len(SENSORS))), axis=0)
        temps = base + rise * (1.0 - np.exp(-t[:, None] / tau)) + walk
        for m in range(n_measurements):
            rows.append(
                {"run": run, "measurement": m + 1, **dict(zip(SENSORS, temps[m], strict=True))}
            )
    return pd.DataFrame(rows)


# --------------------------------------------------------------------------- a model.json by hand

TARGETS = [185.0 + 20.0 * i for i in range(14)]  # the paper's stroke; shifted origin 185 mm
HOLD = FallbackSettings(
    range_margin_c=2.0,
    plausible_c=(-20.0, 120.0),
    max_rate_c_per_min=0.5,
    max_sensor_age_s=60.0,
    policy="hold",
    ramp_to_zero_min=30.0,
)


def hand_model(fallback=HOLD, positions=TARGETS) -> dict:
    """A ``model.json`` record written by hand (tests/unit/test_compensation.py works its
    controller values out from it; tests/packaging/test_wheel.py validates it):
    k = -300 + 13 T1 [um/m] (absolute T1), b = -0.5 - 11 dT2 [um] (T2 relative to homing).
    """
    s = [(x - positions[0]) / 1000.0 for x in positions]
    return {
        "schema": "thermaxis-compensation-model",
        "schema_version": 1,
        "convention": "e = actual - target",
        "approach": "decoupled",
        "algorithm": "mlr",
        "degree": 1,
        "sensors": ["T1", "T2"],
        "inputs": [
            {
                "sensor": "T1",
                "temperature": "absolute",
                "training_min_c": 28.0,
                "training_max_c": 34.0,
            },
            {
                "sensor": "T2",
                "temperature": "relative",
                "training_min_c": 0.0,
                "training_max_c": 3.0,
            },
        ],
        "reference": {
            "temperatures": "at homing",
            "static_pitch_table": "at homing",
            "reference_position_mm": positions[0],
        },
        "positions_mm": list(positions),
        "units": {},
        "regressions": [
            {
                "target": "k",
                "position_mm": None,
                "inputs": [0],
                "form": "affine",
                "constant": -300.0,
                "coefficients": [13.0],
            },
            {
                "target": "b",
                "position_mm": None,
                "inputs": [1],
                "form": "affine",
                "constant": -0.5,
                "coefficients": [-11.0],
            },
        ],
        # b row, k row: the line through k*s + b is that line.
        "line_weights": [[0.0, 1.0], [1.0, 0.0]],
        "curve_basis": [[si, 1.0] for si in s],
        "fallback": {**fallback.__dict__, "plausible_c": list(fallback.plausible_c)},
    }


def lagged_model() -> dict:
    """The hand model with b on a 30 min lag of T2 (relative to homing) instead of T2."""
    model = copy.deepcopy(hand_model())
    model["inputs"][1]["sensor"] = "T2@lag30min"
    model["inputs"][1]["training_max_c"] = 10.0
    return model


def logged_run(n=240, seed=4):
    """A logged run at irregular 5-15 s cycles: times [s], the samples a controller reads,
    and T2, which rises 0.002 C/s."""
    rng = np.random.default_rng(seed)
    t = np.cumsum(rng.uniform(5.0, 15.0, n))  # irregular cycles, seconds
    t1 = 30.0 + np.cumsum(rng.normal(0.0, 0.005, n))
    t2 = 25.0 + 0.002 * t + rng.normal(0.0, 0.01, n)
    return t, [{"T1": a, "T2": b} for a, b in zip(t1, t2, strict=True)], t2


# --------------------------------------------------------------------------- a real record's shape

REAL_RUNS = ("R1", "R2", "R3", "R4", "R5")
REAL_SENSORS = tuple(f"T{i}" for i in range(1, 23))
# True spikes of the real-record dataset: (run index, sensor index, minute, degC). Whole
# multiples of its 5-minute logging, in the middle of a run.
REAL_SPIKES = ((0, 3, 60.0, +2.5), (2, 17, 125.0, -3.0), (4, 9, 95.0, +1.5))


def real_record_temperature(r, s, minutes):
    """Slow warming, then a ramp that sets in 15 to 30 minutes before the record's last
    sample and steepens up to it, at 0.1 C resolution, plus the spikes of :data:`REAL_SPIKES`.

    On 5-minute logging the ramp's first readings are 0.1 C steps off a flat stretch
    (8.0, 8.0, 8.0, 8.0, 8.1, 8.2, 8.3 in the report that found the old filter's fault).
    """
    minutes = np.asarray(minutes, dtype=float)
    late = np.clip(minutes - (minutes[-1] - 5.0 * (3 + s % 4)), 0.0, None)
    values = 18.0 + 0.3 * s + 0.5 * r + 0.001 * minutes + 0.02 * late + 0.0004 * late**2
    for run, sensor, minute, delta in REAL_SPIKES:
        if (run, sensor) == (r, s):
            values[np.argmin(np.abs(minutes - minute))] += delta
    return np.round(values, 1)


def write_real_record(root: Path) -> Path:
    """Records shaped like a machine builder's logger export that the old spike filter refused.

    5 runs, 22 temperature channels logged every 5 minutes at 0.1 C resolution, each
    rising to its last sample; true spikes at :data:`REAL_SPIKES`. 12 measurements every
    20 minutes; the log's samples fall 2 minutes before each measurement's start, and its
    last sample 30 s after the last measurement ends, the only one after it: without
    that sample the last measurement has no reading within max_gap_s / 2.
    """
    return write_dataset(
        root,
        runs=REAL_RUNS,
        sensors=REAL_SENSORS,
        positions=tuple(np.arange(0.0, 701.0, 50.0)),
        n_measurements=12,
        temperature=real_record_temperature,
        name="real",
        log_interval_s=300.0,
        log_start_s=-120.0,
        log_end_margin_s=-300.0,
    )


def held_out_summary(rows) -> pd.DataFrame:
    """A held-out summary table (compensation/summary.csv, the verdict's input) from rows of
    (run, measurement, largest |deviation| before, after, E before, after)."""
    columns = ["run", "measurement", "largest_abs_uncompensated_um", "largest_abs_compensated_um",
               "E_uncompensated_um", "E_compensated_um"]  # fmt: skip
    return pd.DataFrame(rows, columns=columns)
