"""A large synthetic dataset in the same layout, for benchmarks (never committed).

Same physics and error model as the embedded twin (the calibrated parameters), but
any number of runs, sensors, targets, hours and sampling rate.  Data are clean-ish:
sensor noise and lag only, one source (``box``), no seeded faults.  Runs cycle through
the paper's four feeds; each run gets its own random workshop-air profile and initial
temperatures.  Memory stays at one run's table; CSVs are written with pyarrow.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.csv as pacsv

from ..dataset.safety import check_name
from . import conditions as cond
from . import model as mdl
from .network import NODES
from .observe import INTERFEROMETER, lagged

__all__ = ["ScaleSpec", "generate_scale"]

MEASUREMENT_PERIOD_S = 1800.0
FIRST_MEASUREMENT_S = 300.0  # after the log start
STROKE_MM = (185.0, 445.0)
_SURFACES = NODES + ("ambient",)


@dataclass(frozen=True)
class ScaleSpec:
    """Shape of a benchmark dataset."""

    runs: int
    sensors: int
    positions: int
    hours: float
    rate_hz: float
    seed: int = 0
    measurement_period_s: float = MEASUREMENT_PERIOD_S
    # The dataset's name, so its results folder: results/<name>/.
    name: str = "twin_scale"

    def validate(self) -> None:
        check_name(self.name, "dataset name", "thermaxis.twin scale")
        if self.runs < 1 or self.sensors < 1 or self.positions < 1:
            raise ValueError(
                f"runs, sensors and positions must be >= 1, got runs={self.runs}, "
                f"sensors={self.sensors}, positions={self.positions}"
            )
        if not (self.hours > 0 and self.rate_hz > 0 and self.measurement_period_s > 0):
            raise ValueError(
                f"hours, rate_hz and measurement_period_s must be positive, got hours={self.hours}, "
                f"rate_hz={self.rate_hz}, measurement_period_s={self.measurement_period_s}"
            )
        if (
            self.hours * 3600.0
            < FIRST_MEASUREMENT_S + 2 * self.positions * self.reading_interval_s + 60.0
        ):
            raise ValueError(
                f"hours={self.hours} is too short for one measurement of {self.positions} targets "
                f"(needs about {(FIRST_MEASUREMENT_S + 60.0) / 3600.0 + 2 * self.positions * self.reading_interval_s / 3600.0:.2f} h)"
            )

    @property
    def reading_interval_s(self) -> float:
        # Both passes fit in half the measurement period, at most one capture every 6 s.
        return min(6.0, 0.5 * self.measurement_period_s / (2 * self.positions))

    @property
    def positions_mm(self) -> np.ndarray:
        return np.round(np.linspace(*STROKE_MM, self.positions), 3)


def _timeline(spec: ScaleSpec) -> cond.Timeline:
    total = spec.hours * 3600.0
    duration = 2 * spec.positions * spec.reading_interval_s
    starts = (
        np.arange(FIRST_MEASUREMENT_S, total - duration - 60.0, spec.measurement_period_s)
        - FIRST_MEASUREMENT_S
    )
    # Times are relative to the first measurement, as in the paper's runs.
    log_start = -FIRST_MEASUREMENT_S
    n_steps = int(np.ceil(total / cond.STEP_S))
    grid = log_start + cond.STEP_S * np.arange(n_steps + 1)
    return cond.Timeline(
        log_start_s=log_start,
        log_end_s=float(grid[-1]),
        measurement_start_s=starts,
        measurement_end_s=starts + duration - spec.reading_interval_s,
        grid_s=grid,
    )


def _ambient_profile(rng: np.random.Generator, tl: cond.Timeline):
    knots_s = np.arange(tl.log_start_s, tl.log_end_s + 1800.0, 1800.0)
    values = rng.uniform(20.0, 30.0) + np.cumsum(rng.normal(0.0, 0.3, knots_s.size))
    return lambda t: np.interp(t, knots_s, values)


def _sensor_mix(rng: np.random.Generator, n: int) -> list[tuple[dict[str, float], float, float]]:
    """Per sensor: surface weights, lag (s), calibration offset (degC)."""
    out = []
    for i in range(n):
        primary = _SURFACES[i % len(_SURFACES)]
        secondary = _SURFACES[rng.integers(len(_SURFACES))]
        w = rng.uniform(0.7, 1.0)
        weights = {primary: w}
        weights[secondary] = weights.get(secondary, 0.0) + 1.0 - w
        out.append((weights, float(rng.uniform(20.0, 120.0)), float(rng.normal(0.0, 0.1))))
    return out


def _clock(t_s: np.ndarray, day: int, unit: str) -> np.ndarray:
    base = np.datetime64("2023-01-02T08:00:00") + np.timedelta64(day, "D")
    ms = np.round(t_s * 1000.0).astype("int64").astype("timedelta64[ms]")
    return np.datetime_as_string(base + ms, unit=unit)


def _write_table(path: Path, header: list[str], columns: dict[str, np.ndarray | list]) -> None:
    table = pa.table({name: pa.array(col) for name, col in columns.items()})
    with open(path, "wb") as fh:
        fh.write((",".join(header) + "\n").encode())
        pacsv.write_csv(table, fh, pacsv.WriteOptions(include_header=False, quoting_style="none"))


def _run(
    spec: ScaleSpec, index: int, params: mdl.TwinParams, mixes, root: Path
) -> tuple[str, int, float]:
    rng = np.random.default_rng([spec.seed, index])
    base = cond.CONDITIONS[index % len(cond.CONDITIONS)]
    run = f"S{index + 1:03d}"
    tl = _timeline(spec)
    ambient = _ambient_profile(rng, tl)
    initial = np.full(len(NODES), float(ambient(tl.grid_s[:1])[0])) + rng.normal(
        0.0, 0.5, len(NODES)
    )
    state = mdl.simulate_timeline(params.values, tl, ambient, base.feed_mm_min, initial)

    temps = root / run / "temperatures"
    errors = root / run / "errors"
    temps.mkdir(parents=True, exist_ok=True)
    errors.mkdir(parents=True, exist_ok=True)

    dt = 1.0 / spec.rate_hz
    n_rows = int(round(spec.hours * 3600.0 * spec.rate_hz))
    t = tl.log_start_s + dt * np.arange(n_rows)
    unit = "s" if float(dt).is_integer() else "ms"
    columns: dict[str, np.ndarray | list] = {"time": _clock(t, index, unit)}
    for i, (weights, lag_s, offset) in enumerate(mixes):
        surface = sum(
            w * (state.ambient if name == "ambient" else state.nodes[:, NODES.index(name)])
            for name, w in weights.items()
        )
        slow = lagged(surface, cond.STEP_S, lag_s)
        values = np.interp(t, tl.grid_s, slow) + offset + rng.normal(0.0, 0.01, n_rows)
        columns[f"T{i + 1}"] = np.round(values, 3)
    _write_table(temps / "box.csv", list(columns), columns)

    x = spec.positions_mm
    lever_dir = np.concatenate([x, x[::-1]])
    direction = np.array(["+"] * x.size + ["-"] * x.size)
    datum = float(mdl.positioning_error(params.values, state, x[0], -30.0))
    for m, start in enumerate(tl.measurement_start_s, start=1):
        times = start + spec.reading_interval_s * np.arange(2 * x.size)
        true = mdl.positioning_error(params.values, state, lever_dir, times) - datum
        scale = np.clip(rng.normal(0.0, INTERFEROMETER.scale_error_um_per_m), -0.5, 0.5)
        read = (
            true
            + scale * (lever_dir - x[0]) / 1000.0
            + rng.normal(0.0, INTERFEROMETER.reading_noise_um, times.size)
            + np.where(direction == "-", INTERFEROMETER.reversal_um, 0.0)
        )
        _write_table(
            errors / f"M{m:02d}.csv",
            ["time", "position_mm", "error_um", "direction"],
            {
                "time": _clock(
                    times, index, "s" if float(spec.reading_interval_s).is_integer() else "ms"
                ),
                "position_mm": lever_dir,
                "error_um": np.round(read, 4),
                "direction": direction,
            },
        )
    return run, base.condition, base.feed_mm_min


def generate_scale(
    out_dir: Path | str, spec: ScaleSpec, params: mdl.TwinParams | None = None
) -> None:
    """Write a benchmark dataset of ``spec`` to ``out_dir`` (one run at a time)."""
    spec.validate()
    params = params or mdl.load_params()
    root = Path(out_dir)
    root.mkdir(parents=True, exist_ok=True)
    mixes = _sensor_mix(np.random.default_rng([spec.seed, 10**6]), spec.sensors)
    rows = [_run(spec, i, params, mixes, root) for i in range(spec.runs)]
    runs_tsv = ["run\tcondition\tfeed_mm_min\tdescription"] + [
        f"{run}\t{c}\t{feed:.0f}\tbenchmark run, {feed:.0f} mm/min reciprocating, random workshop air"
        for run, c, feed in rows
    ]
    (root / "runs.tsv").write_text("\n".join(runs_tsv) + "\n", encoding="utf-8")
    sensors = "\n".join(
        f'  - {{id: T{i + 1}, location: "simulated surface mixing {", ".join(sorted(w))}", source: box}}'
        for i, (w, _, _) in enumerate(mixes)
    )
    (root / "dataset.yaml").write_text(
        f"""# Written by `python -m thermaxis.twin scale` -- a benchmark dataset, not for analysis.
name: {spec.name}
description: >-
  Benchmark dataset from thermaxis.twin scale: {spec.runs} runs, {spec.sensors} sensors,
  {spec.positions} targets, {spec.hours:g} h at {spec.rate_hz:g} Hz, measurements every {spec.measurement_period_s / 60:g} min.
provenance:
  kind: simulated
  citation: "thermaxis.twin scale (seed {spec.seed}); physics calibrated to Xu et al., DOI 10.19650/j.cnki.cjsi.J2209628"
axis:
  name: X
sensors:
{sensors}
sources:
  - name: box
    clock_note: "reference clock"
    clock_offset_s: 0
""",
        encoding="utf-8",
    )
