"""Write the embedded default dataset (``data/raw/twin``) and its ground truth.

Everything is a pure function of the committed parameters and fixed seeds, and every
number is written with a fixed format, so regenerating gives byte-identical files.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from thermaxis.method.decouple import decouple_measurement

from . import conditions as cond
from . import faults
from . import model as mdl
from .network import NODES
from .observe import (
    HMI_CLOCK_OFFSET_S,
    HMI_PERIOD_S,
    INTERFEROMETER,
    SENSORS,
    WIRELESS_JITTER_S,
    WIRELESS_PERIOD_S,
    calibrated_sensors,
    interferometer_readings,
    lagged,
    sensor_signal,
)

__all__ = ["SEED", "RunRecord", "simulate_records", "write_runs", "generate_dataset"]

SEED = 20220416  # the paper's received date


@dataclass(frozen=True)
class RunRecord:
    """Everything written for one run, as arrays (times in s from M1)."""

    condition: cond.Condition
    state: mdl.RunState
    sensor_truth: dict[str, np.ndarray]  # on the box grid, lag + offset, no noise
    box: dict[str, np.ndarray]  # as logged (noise, faults), rows = box_rows
    box_rows: np.ndarray  # indices into the grid (duplicates repeated)
    wireless_time_s: np.ndarray
    wireless: np.ndarray
    hmi_stamp_s: np.ndarray  # on the HMI's own clock
    hmi: np.ndarray
    measurements: list  # list[Readings]
    kb_truth: list  # (time_min, k, b)


def _clock(condition: cond.Condition, t_s: np.ndarray, unit: str) -> np.ndarray:
    base = np.datetime64(f"{condition.date}T{condition.m1_clock}")
    ms = np.round(np.asarray(t_s, dtype=float) * 1000.0).astype("int64").astype("timedelta64[ms]")
    return np.datetime_as_string(base + ms, unit=unit)


def _run_rng(run_index: int, stream: int) -> np.random.Generator:
    return np.random.default_rng([SEED, run_index, stream])


def _wireless_times(tl: cond.Timeline, rng: np.random.Generator) -> np.ndarray:
    n = int((tl.log_end_s - tl.log_start_s) / WIRELESS_PERIOD_S) + 2
    steps = WIRELESS_PERIOD_S + rng.uniform(-WIRELESS_JITTER_S, WIRELESS_JITTER_S, n)
    t = (
        tl.log_start_s
        + rng.uniform(1.0, WIRELESS_PERIOD_S)
        + np.concatenate([[0.0], np.cumsum(steps[:-1])])
    )
    return np.round(t[t < tl.log_end_s - 1.0], 3)


def _sensor(sensor_id: str):
    return next(s for s in SENSORS if s.id == sensor_id)


def _box_log(run: str, grid: np.ndarray, truth: dict[str, np.ndarray], rng: np.random.Generator):
    """T1-T10 every 10 s with noise, then the box's seeded faults."""
    clean = {
        s.id: truth[s.id] + rng.normal(0.0, s.noise_c, grid.size)
        for s in SENSORS
        if s.source == "box"
    }
    return faults.apply_box_faults(run, grid / 60.0, clean)


def _wireless_log(run: str, tl: cond.Timeline, truth: np.ndarray, rng: np.random.Generator):
    """T11 at irregular ~30 s packets, with lost packets and the outage."""
    times = _wireless_times(tl, rng)
    values = np.interp(times, tl.grid_s, truth) + rng.normal(
        0.0, _sensor("T11").noise_c, times.size
    )
    keep = rng.uniform(size=times.size) >= faults.WIRELESS_LOSS_PROBABILITY
    out_run, first_min, last_min = faults.WIRELESS_OUTAGE
    if out_run == run:
        keep &= ~((times >= 60.0 * first_min) & (times <= 60.0 * last_min))
    return times[keep], values[keep]


def _hmi_log(tl: cond.Timeline, truth: np.ndarray, rng: np.random.Generator):
    """T12 polled every minute of the HMI's own (late) clock, quantised to 0.1 degC."""
    first_stamp = np.ceil((tl.log_start_s - HMI_CLOCK_OFFSET_S) / HMI_PERIOD_S) * HMI_PERIOD_S
    stamps = np.arange(first_stamp, tl.log_end_s - HMI_CLOCK_OFFSET_S, HMI_PERIOD_S)
    true_time = stamps + HMI_CLOCK_OFFSET_S
    noisy = np.interp(true_time, tl.grid_s, truth) + rng.normal(
        0.0, _sensor("T12").noise_c, stamps.size
    )
    return stamps, np.round(noisy, 1)


def _laser(params: mdl.TwinParams, state: mdl.RunState, rng: np.random.Generator):
    """The 8 measurements as read, and the noise-free (time_min, k, b) of each."""
    tl = state.timeline
    datum_true = float(
        mdl.positioning_error(params.values, state, cond.FIRST_TARGET_MM, cond.ZERO_S)
    )
    # Zeroing captures one noisy reading: every later reading carries its noise.
    datum_read = datum_true + rng.normal(0.0, INTERFEROMETER.reading_noise_um)
    n = cond.TARGETS_MM.size
    measurements, kb_truth = [], []
    for start, end in zip(tl.measurement_start_s, tl.measurement_end_s, strict=False):
        readings = interferometer_readings(params.values, state, start, datum_read, rng)
        true_rel = readings.true_um + datum_read - datum_true
        pass_mean = 0.5 * (true_rel[:n] + true_rel[n:][::-1])
        # The true k and b: the paper's straight line (Eq. 6) through the noise-free readings.
        fit = decouple_measurement(
            cond.TARGETS_MM, pass_mean, degree=1, origin_mm=cond.FIRST_TARGET_MM
        )
        measurements.append(readings)
        kb_truth.append((0.5 * (start + end) / 60.0, fit.k_um_per_m, fit.b_um))
    return measurements, kb_truth


def simulate_records(params: mdl.TwinParams) -> list[RunRecord]:
    """Simulate all four runs: hidden state, sensors (clean and faulty) and readings.

    Each instrument draws from its own seeded stream, so changing one never shifts
    the noise of another.
    """
    records = []
    sensors = calibrated_sensors(params.values)
    for i, condition in enumerate(cond.CONDITIONS):
        state = mdl.simulate_run(condition, params)
        tl = state.timeline
        step = float(tl.grid_s[1] - tl.grid_s[0])
        truth = {s.id: lagged(sensor_signal(s, state), step, s.lag_s) + s.offset_c for s in sensors}
        box, rows = _box_log(condition.run, tl.grid_s, truth, _run_rng(i, 1))
        w_time, w_value = _wireless_log(condition.run, tl, truth["T11"], _run_rng(i, 2))
        stamps, hmi = _hmi_log(tl, truth["T12"], _run_rng(i, 3))
        measurements, kb_truth = _laser(params, state, _run_rng(i, 4))
        records.append(
            RunRecord(
                condition=condition,
                state=state,
                sensor_truth=truth,
                box=box,
                box_rows=rows,
                wireless_time_s=w_time,
                wireless=w_value,
                hmi_stamp_s=stamps,
                hmi=hmi,
                measurements=measurements,
                kb_truth=kb_truth,
            )
        )
    return records


def _write_csv(path: Path, header: list[str], columns: list[list[str]]) -> None:
    lines = [",".join(header)] + [",".join(row) for row in zip(*columns, strict=False)]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")


def _fmt(values: np.ndarray, spec: str) -> list[str]:
    return [format(float(v), spec) for v in values]


def _write_run(root: Path, record: RunRecord) -> None:
    c = record.condition
    grid = record.state.grid_s
    temps = root / c.run / "temperatures"
    errors = root / c.run / "errors"
    temps.mkdir(parents=True, exist_ok=True)
    errors.mkdir(parents=True, exist_ok=True)
    box_ids = [s.id for s in SENSORS if s.source == "box"]
    rows = record.box_rows
    _write_csv(
        temps / "box.csv",
        ["time"] + box_ids,
        [list(_clock(c, grid[rows], "s"))] + [_fmt(record.box[s][rows], ".3f") for s in box_ids],
    )
    _write_csv(
        temps / "wireless.csv",
        ["time", "T11"],
        [list(_clock(c, record.wireless_time_s, "ms")), _fmt(record.wireless, ".2f")],
    )
    _write_csv(
        temps / "hmi.csv",
        ["time", "T12"],
        [list(_clock(c, record.hmi_stamp_s, "s")), _fmt(record.hmi, ".1f")],
    )
    miss_run, miss_meas, miss_dir, miss_pos = faults.MISSING_READING
    for m, readings in enumerate(record.measurements, start=1):
        keep = np.ones(readings.time_s.size, dtype=bool)
        if c.run == miss_run and m == miss_meas:
            keep &= ~((readings.direction == miss_dir) & (readings.position_mm == miss_pos))
        _write_csv(
            errors / f"M{m:02d}.csv",
            ["time", "position_mm", "error_um", "direction"],
            [
                list(_clock(c, readings.time_s[keep], "s")),
                _fmt(readings.position_mm[keep], ".0f"),
                _fmt(readings.error_um[keep], ".4f"),
                list(readings.direction[keep]),
            ],
        )


def _write_truth(truth_root: Path, records: list[RunRecord], params: mdl.TwinParams) -> None:
    truth_root.mkdir(parents=True, exist_ok=True)
    kb_rows = []
    for record in records:
        for m, (t_min, k, b) in enumerate(record.kb_truth, start=1):
            kb_rows.append(
                (
                    record.condition.run,
                    str(m),
                    format(t_min, ".3f"),
                    format(k, ".4f"),
                    format(b, ".4f"),
                )
            )
    _write_csv(
        truth_root / "kb_truth.csv",
        ["run", "measurement", "time_min", "k_um_per_m", "b_um"],
        [list(col) for col in zip(*kb_rows, strict=False)],
    )
    sensor_ids = [s.id for s in SENSORS]
    for record in records:
        c = record.condition
        state = record.state
        grid = state.grid_s
        time = list(_clock(c, grid, "s"))
        _write_csv(
            truth_root / f"{c.run}_sensors.csv",
            ["time"] + sensor_ids,
            [time] + [_fmt(record.sensor_truth[s], ".4f") for s in sensor_ids],
        )
        k_geo, b_geo = _geometric_line(params.values)
        k_inst = mdl.thermal_slope(params.values, state, grid) + k_geo
        datum = mdl.positioning_error(params.values, state, cond.FIRST_TARGET_MM, cond.ZERO_S)
        lever = (cond.FIRST_TARGET_MM - mdl.X_FIXED_MM) / 1000.0
        b_inst = (
            b_geo
            + mdl.thermal_slope(params.values, state, grid) * lever
            + mdl.drift(params.values, state, grid)
        )
        b_inst = b_inst + mdl.geometric_error(params.values, cond.FIRST_TARGET_MM) - datum
        _write_csv(
            truth_root / f"{c.run}_hidden.csv",
            ["time", "minute"] + list(NODES) + ["ambient", "k_instant_um_per_m", "b_instant_um"],
            [time, _fmt(grid / 60.0, ".3f")]
            + [_fmt(state.nodes[:, j], ".4f") for j in range(len(NODES))]
            + [_fmt(state.ambient, ".4f"), _fmt(k_inst, ".4f"), _fmt(b_inst, ".4f")],
        )
    (truth_root / "README.md").write_text(TRUTH_README, encoding="utf-8")


def _geometric_line(values: dict[str, float]) -> tuple[float, float]:
    """k and b of the geometric error alone (relative to the first target)."""
    g = mdl.geometric_error(values, cond.TARGETS_MM) - mdl.geometric_error(
        values, cond.FIRST_TARGET_MM
    )
    fit = decouple_measurement(cond.TARGETS_MM, g, degree=1, origin_mm=cond.FIRST_TARGET_MM)
    return fit.k_um_per_m, fit.b_um


TRUTH_README = """\
# Ground truth of the thermal twin (for tests only)

Written by `python -m thermaxis.twin generate` next to `data/raw/twin/`. The modelling
code never reads these files (a test greps for their folder name); they exist so that
tests can check the cleaning and decoupling stages against what the twin really did.

| file | content |
|---|---|
| `kb_truth.csv` | run, measurement, time_min (middle of the measurement, minutes from the start of M1), k_um_per_m, b_um: the least-squares line (origin 185 mm) of the pass-mean error curve without reversal error, noise, datum noise and the interferometer's scale error. The missing capture of E3 M06 is included here. |
| `<run>_sensors.csv` | fault-free sensor temperatures T1-T12 on the box's 10 s grid and the reference clock: each sensor's mounting mix, lag and calibration offset, WITHOUT noise, spikes, gaps, quantisation or clock offset. The raw logs add white noise (box 0.008-0.010 degC, wireless 0.03 degC, HMI 0.04 degC before 0.1 degC quantisation). |
| `<run>_hidden.csv` | the network's node temperatures (degC; `screw_core` drives the expansion and has no sensor), the workshop air, and the instantaneous noise-free slope and intercept the interferometer would see if it could read the whole stroke at that moment (`k_instant_um_per_m`, `b_instant_um`, same datum as the raw files). |

Times are ISO 8601 without zone (the runs' fictitious dates), `minute` is minutes from
the start of M1.
"""


def write_runs(out_dir: Path, records: list[RunRecord]) -> None:
    """The raw files of every run and the dataset's description (no ground truth)."""
    from .documents import write_dataset_docs

    for record in records:
        _write_run(out_dir, record)
    write_dataset_docs(out_dir)


def generate_dataset(
    out_dir: Path | str, truth_dir: Path | str, params_path: Path | str = mdl.PARAMS_PATH
) -> list[RunRecord]:
    """Write the raw dataset and the ground truth from a parameter file; returns the records."""
    from .report import write_calibration_report

    params = mdl.load_params(params_path)
    out_dir, truth_dir = Path(out_dir), Path(truth_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    records = simulate_records(params)
    write_runs(out_dir, records)
    _write_truth(truth_dir, records, params)
    write_calibration_report(out_dir, params, mdl.load_fit(params_path))
    return records
