"""The compensation a controller applies, cycle by cycle: :class:`Compensator` and its fallback policy."""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from thermaxis.compensation.model import UM_PER_MM, evaluate_regression, validate_model
from thermaxis.config import FallbackSettings
from thermaxis.method.decouple import MM_PER_M
from thermaxis.method.inputs import LagState, RateState, base_of, parse_input_name

__all__ = [
    "ControllerParameters",
    "Step",
    "Compensator",
]


# --------------------------------------------------------------------------- the compensator


@dataclass(frozen=True)
class ControllerParameters:
    """One temperature state's compensation line, in the controllers' units.

    ``curve_um`` is the compensation the model asks for at each target; ``line_gap_um``
    the largest distance between it and the exported line (0 for a straight model).
    ``offset_only`` is set for single-position datasets (SD43900 alone).
    """

    k0_mm: float
    tan_beta: float
    p0_mm: float
    curve_um: tuple[float, ...]
    line_gap_um: float
    offset_only: bool

    def at(self, position_mm) -> np.ndarray:
        """Compensation in um at positions, as the controller computes it from K0, tan(beta), P0."""
        x = np.asarray(position_mm, dtype=float)
        return (self.k0_mm + self.tan_beta * (x - self.p0_mm)) * UM_PER_MM


@dataclass(frozen=True)
class Step:
    """One cycle of the compensator: the values sent to the controller and why."""

    time_s: float
    parameters: ControllerParameters
    status: str  # ok | hold | ramp
    reasons: tuple[str, ...] = field(default=())


def _zero_parameters(p0_mm: float, offset_only: bool, n_positions: int) -> ControllerParameters:
    return ControllerParameters(0.0, 0.0, p0_mm, (0.0,) * n_positions, 0.0, offset_only)


def _ramped(good: ControllerParameters, elapsed_min: float, ramp_to_zero_min: float):
    """The last good parameters scaled down linearly to zero over ``ramp_to_zero_min``
    after a fault began (at once when it is 0): the fallback policy "ramp"."""
    scale = max(0.0, 1.0 - elapsed_min / ramp_to_zero_min) if ramp_to_zero_min > 0 else 0.0
    return replace(
        good,
        k0_mm=good.k0_mm * scale,
        tan_beta=good.tan_beta * scale,
        curve_um=tuple(v * scale for v in good.curve_um),
    )


class Compensator:
    """The deployable model: predicted error curve and controller parameters from temperatures
    (and operating signals, when the model reads any).

    Build it with :meth:`from_json`. :meth:`parameters` is the pure computation for one
    temperature state; :meth:`run` applies the fallback policy to a time series, as a
    PLC would cycle by cycle.
    """

    def __init__(
        self, model: Mapping, fallback: FallbackSettings | None = None, where: str = "model.json"
    ):
        validate_model(model, where)
        self.model = model
        self.inputs = [(i["sensor"], i["temperature"]) for i in model["inputs"]]
        # Time-aware inputs (``T5@lag30min``): derived cycle by cycle from their sensor.
        self.derived = {s: parse_input_name(s) for s, _ in self.inputs if "@" in s}
        self.sensors = tuple(dict.fromkeys(base_of(s) for s in model["sensors"]))
        # Operating signals (a spindle speed) have no plausible degC range or rate.
        self.signals = frozenset(model.get("signals", ()))
        # What each sensor's log steps by in the training runs (noise, resolution): the
        # rate check allows it on top of the rate. A model without it allows nothing.
        self.noise_c = {s: float(v) for s, v in model.get("noise_c", {}).items()}
        self.positions_mm = np.asarray(model["positions_mm"], dtype=float)
        self.p0_mm = float(model["reference"]["reference_position_mm"])
        self.offset_only = self.positions_mm.size == 1
        self.weights = np.asarray(model["line_weights"], dtype=float)
        self.basis = np.asarray(model["curve_basis"], dtype=float)
        f = model["fallback"]
        self.fallback = fallback or FallbackSettings(
            **{**f, "plausible_c": tuple(f["plausible_c"])}
        )
        self._names = [s for s, _ in self.inputs]
        self._relative = np.array([kind == "relative" for _, kind in self.inputs], dtype=bool)
        self._relative_names = [s for s, kind in self.inputs if kind == "relative"]
        # The inputs whose training range bounds them: every one but a signal's (a speed
        # beyond its training range is an extrapolation the held-out verdict measures; a
        # degC margin says nothing about it; the channel decides, as
        # SENSOR_SIGNAL[INPUT_SENSOR[j]] does in the Structured Text block).
        ranged = [i for i, s in enumerate(self._names) if base_of(s) not in self.signals]
        specs = [model["inputs"][i] for i in ranged]
        margin = self.fallback.range_margin_c
        self._ranged = np.array(ranged, dtype=int)
        self._low = np.array([spec["training_min_c"] - margin for spec in specs], dtype=float)
        self._high = np.array([spec["training_max_c"] + margin for spec in specs], dtype=float)

    @classmethod
    def from_json(cls, path, fallback: FallbackSettings | None = None) -> Compensator:
        path = Path(path)
        try:
            model = json.loads(path.read_text(encoding="utf-8"))
        except OSError as exc:
            raise ValueError(f"{path}: cannot read the model ({exc.strerror})") from exc
        except json.JSONDecodeError as exc:
            raise ValueError(f"{path}: line {exc.lineno}: not valid JSON ({exc.msg})") from exc
        return cls(model, fallback, where=str(path))

    def derived_inputs(
        self, times_s: Sequence[float], temperatures: Sequence[Mapping[str, float]]
    ) -> list[dict]:
        """The time-aware inputs at every cycle, carried from one cycle to the next.

        Each lag or rate starts with its sensor's first finite reading, steady, as the
        offline inputs of :mod:`thermaxis.method.inputs` start with the run, and is NaN
        before it; a missing or non-finite reading feeds the last good one, so a fault does
        not break the filter's history.
        """
        names = list(self.derived)
        bases = list(dict.fromkeys(base for base, _, _ in self.derived.values()))
        column = {base: j for j, base in enumerate(bases)}
        readings = np.array(
            [[sample.get(base, math.nan) for base in bases] for sample in temperatures],
            dtype=float,
        ).reshape(len(temperatures), len(bases))
        good = np.isfinite(readings)
        # The last good reading at every cycle (a row index per cycle and sensor).
        rows = np.where(good, np.arange(len(readings))[:, None], 0)
        carried = readings[np.maximum.accumulate(rows, axis=0), np.arange(len(bases))]
        first = np.where(good.any(axis=0), good.argmax(axis=0), len(readings))
        # Inputs of one kind and duration whose sensors start together share one state,
        # updated with all their readings at once: the cycle's arithmetic per input is the
        # same as with a state each, and the coefficients are computed once per cycle.
        groups: dict[tuple, list[int]] = {}
        for i, name in enumerate(names):
            base, kind, seconds = self.derived[name]
            groups.setdefault((kind, seconds, int(first[column[base]])), []).append(i)
        values = np.full((len(readings), len(names)), math.nan)
        for (kind, seconds, start), members in groups.items():
            state = LagState(seconds) if kind == "lag" else RateState(seconds)
            sensors = [column[self.derived[names[i]][0]] for i in members]
            for cycle in range(start, len(readings)):
                values[cycle, members] = state.update(
                    float(times_s[cycle]), carried[cycle, sensors]
                )
        return [dict(zip(names, row, strict=True)) for row in values.tolist()]

    def _input_row(
        self, temperatures: Mapping[str, float], reference: Mapping[str, float]
    ) -> np.ndarray:
        row = np.array([temperatures[s] for s in self._names], dtype=float)
        row[self._relative] -= [reference[s] for s in self._relative_names]
        return row

    def _changes(self, now: np.ndarray, then: np.ndarray) -> np.ndarray:
        """Each regression's prediction at each input row of ``now`` (cycles, inputs) minus
        at ``then``: (cycles, regressions)."""
        changes = []
        for record in self.model["regressions"]:
            chosen = record["inputs"]
            values = evaluate_regression(record, np.vstack([now[:, chosen], then[chosen]]))
            changes.append(values[:-1] - values[-1])
        return np.column_stack(changes).astype(float, copy=False)

    def regression_changes(
        self, temperatures: Mapping[str, float], reference: Mapping[str, float]
    ) -> np.ndarray:
        """Each regression's prediction at the current state minus at the reference state."""
        return self._changes(
            self._input_row(temperatures, reference)[None, :], self._input_row(reference, reference)
        )[0]

    def predicted_change(
        self, temperatures: Mapping[str, float], reference: Mapping[str, float]
    ) -> np.ndarray:
        """Predicted change of the error curve since the reference state, um at each target."""
        return self.basis @ self.regression_changes(temperatures, reference)

    def parameters(
        self, temperatures: Mapping[str, float], reference: Mapping[str, float]
    ) -> ControllerParameters:
        """K0 [mm], tan(beta) [-], P0 [mm] of the compensation (= -predicted change) in one state."""
        return self._parameters_of(self.regression_changes(temperatures, reference))

    def _parameters_of(self, changes: np.ndarray) -> ControllerParameters:
        b_um, k_um_per_m = self.weights @ changes
        curve = -(self.basis @ changes) + 0.0
        line = -(b_um + k_um_per_m * (self.positions_mm - self.p0_mm) / MM_PER_M)
        # + 0.0 turns -0.0 (no change negated) into 0.0, which controllers and readers expect.
        return ControllerParameters(
            k0_mm=float(-b_um / UM_PER_MM) + 0.0,
            tan_beta=float(-k_um_per_m / (UM_PER_MM * MM_PER_M)) + 0.0,
            p0_mm=self.p0_mm,
            curve_um=tuple(float(v) for v in curve),
            line_gap_um=float(np.max(np.abs(curve - line))),
            offset_only=self.offset_only,
        )

    def faults(
        self,
        temperatures: Mapping[str, float],
        reference: Mapping[str, float],
        time_s: float = 0.0,
        last: Mapping[str, tuple[float, float]] | None = None,
        ages_s: Mapping[str, float] | None = None,
    ) -> tuple[str, ...]:
        """Why this sample must not be used (empty when it is good); one reason per fault.

        ``last`` holds each sensor's previous plausible reading as (time [s], value): the
        rate is measured against it, so one wild sample does not also fail the next one.
        """
        return self._faults_and_row(temperatures, reference, time_s, last, ages_s)[0]

    def _faults_and_row(self, temperatures, reference, time_s, last, ages_s):
        """:meth:`faults`, and the input row it checked (None when a sensor already failed)."""
        reasons = self._sensor_faults(temperatures, reference, time_s, last, ages_s)
        if reasons:
            return reasons, None
        row = self._input_row(temperatures, reference)
        return self._range_faults(row), row

    def _sensor_faults(self, temperatures, reference, time_s, last, ages_s) -> tuple[str, ...]:
        """The sensors' faults: missing, stale, implausible, too fast, or no reference."""
        f = self.fallback
        lo, hi = f.plausible_c
        reasons = []
        for sensor in self.sensors:
            value = temperatures.get(sensor, math.nan)
            ref = reference.get(sensor, math.nan)
            age = (ages_s or {}).get(sensor, 0.0)
            signal = sensor in self.signals
            if not math.isfinite(value):
                reasons.append(f"{sensor}: missing")
            elif age > f.max_sensor_age_s:
                reasons.append(
                    f"{sensor}: stale, last update {age:g} s ago (limit {f.max_sensor_age_s:g} s)"
                )
            elif not signal:
                reasons += self._temperature_faults(sensor, value, time_s, last)
            if signal and not math.isfinite(ref):
                reasons.append(f"{sensor}: reference value missing")
            elif not signal and not (math.isfinite(ref) and lo <= ref <= hi):
                reasons.append(f"{sensor}: reference temperature missing or implausible")
        return tuple(reasons)

    def _range_faults(self, row: np.ndarray) -> tuple[str, ...]:
        """Inputs of ``row`` outside their training range by more than the margin."""
        values = row[self._ranged]
        # NaN is outside too: no comparison holds.
        outside = np.flatnonzero(~((self._low <= values) & (values <= self._high)))
        f = self.fallback
        reasons = []
        for j in outside.tolist():
            i = int(self._ranged[j])
            sensor, kind = self.inputs[i]
            spec = self.model["inputs"][i]
            reasons.append(
                f"{sensor} ({kind}): {row[i]:.3g} C outside the training range "
                f"{spec['training_min_c']:.3g} ... {spec['training_max_c']:.3g} C by more than {f.range_margin_c:g} C"
            )
        return tuple(reasons)

    def _temperature_faults(self, sensor: str, value: float, time_s: float, last) -> list[str]:
        """A present, fresh temperature's faults: outside the plausible range, or changing too fast."""
        f = self.fallback
        lo, hi = f.plausible_c
        if not lo <= value <= hi:
            return [f"{sensor}: implausible {value:g} C (plausible {lo:g} ... {hi:g} C)"]
        if last and sensor in last and time_s > last[sensor][0]:
            noise = self.noise_c.get(sensor, 0.0)
            beyond = max(abs(value - last[sensor][1]) - noise, 0.0)
            rate = beyond / (time_s - last[sensor][0]) * 60.0
            if rate > f.max_rate_c_per_min:
                allowed = f" beyond its {noise:.3g} C log noise" if noise else ""
                return [
                    f"{sensor}: changes {rate:.3g} C/min{allowed} (limit {f.max_rate_c_per_min:g} C/min)"
                ]
        return []

    def _plausible_readings(
        self, time_s: float, sample: Mapping[str, float], ages: Mapping[str, float]
    ) -> dict:
        lo, hi = self.fallback.plausible_c
        return {
            s: (time_s, sample[s])
            for s in self.sensors
            if s not in self.signals
            and math.isfinite(sample.get(s, math.nan))
            and lo <= sample[s] <= hi
            and ages.get(s, 0.0) <= self.fallback.max_sensor_age_s
        }

    def run(
        self,
        times_s: Sequence[float],
        temperatures: Sequence[Mapping[str, float]],
        reference: Mapping[str, float],
        ages_s: Sequence[Mapping[str, float]] | None = None,
        derived: Sequence[Mapping[str, float]] | None = None,
    ) -> list[Step]:
        """The compensation cycle by cycle, with the fallback policy applied.

        ``derived``: :meth:`derived_inputs` of these cycles, when the caller has them.
        """
        f = self.fallback
        if self.derived:
            # The reference of a derived input is its value at homing: the first cycle's,
            # unless ``reference`` holds it (homed after the filters started).
            if derived is None:
                derived = self.derived_inputs(times_s, temperatures)
            temperatures = [{**s, **d} for s, d in zip(temperatures, derived, strict=True)]
            reference = {**derived[0], **reference}
        # The faults first, cycle by cycle (a rate is measured against the last plausible
        # reading); then every good cycle's regressions in one evaluation per regression,
        # each cycle's row the one its faults were checked on (as parameters() builds it).
        last: dict[str, tuple[float, float]] = {}
        checked = []
        for i, (time_s, sample) in enumerate(zip(times_s, temperatures, strict=False)):
            ages = ages_s[i] if ages_s is not None else {}
            reasons, row = self._faults_and_row(sample, reference, float(time_s), last, ages)
            last.update(self._plausible_readings(float(time_s), sample, ages))
            checked.append((float(time_s), reasons, row))
        rows = [row for _, reasons, row in checked if not reasons]
        changes = iter(
            self._changes(np.vstack(rows), self._input_row(reference, reference)) if rows else ()
        )
        good = _zero_parameters(self.p0_mm, self.offset_only, self.positions_mm.size)
        fault_since = None
        steps = []
        for time_s, reasons, _ in checked:
            if not reasons:
                good = self._parameters_of(next(changes))
                fault_since = None
                steps.append(Step(time_s, good, "ok"))
                continue
            fault_since = time_s if fault_since is None else fault_since
            if f.policy == "hold":
                steps.append(Step(time_s, good, "hold", reasons))
                continue
            ramped = _ramped(good, (time_s - fault_since) / 60.0, f.ramp_to_zero_min)
            steps.append(Step(time_s, ramped, "ramp", reasons))
        return steps
