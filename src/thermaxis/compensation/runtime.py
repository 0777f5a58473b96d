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
        self.positions_mm = np.asarray(model["positions_mm"], dtype=float)
        self.p0_mm = float(model["reference"]["reference_position_mm"])
        self.offset_only = self.positions_mm.size == 1
        self.weights = np.asarray(model["line_weights"], dtype=float)
        self.basis = np.asarray(model["curve_basis"], dtype=float)
        f = model["fallback"]
        self.fallback = fallback or FallbackSettings(
            **{**f, "plausible_c": tuple(f["plausible_c"])}
        )

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

        Each lag or rate starts with the first sample, steady, as the offline inputs of
        :mod:`thermaxis.method.inputs` start with the run; a missing or non-finite
        reading feeds the last good one, so a fault does not break the filter's history.
        """
        states = {
            name: (LagState(seconds) if kind == "lag" else RateState(seconds), base)
            for name, (base, kind, seconds) in self.derived.items()
        }
        last: dict[str, float] = {}
        out = []
        for time_s, sample in zip(times_s, temperatures, strict=True):
            values = {}
            for name, (state, base) in states.items():
                value = sample.get(base, math.nan)
                if math.isfinite(value):
                    last[base] = value
                values[name] = state.update(float(time_s), last[base]) if base in last else math.nan
            out.append(values)
        return out

    def _input_row(
        self, temperatures: Mapping[str, float], reference: Mapping[str, float]
    ) -> np.ndarray:
        return np.array(
            [
                temperatures[s] - reference[s] if kind == "relative" else temperatures[s]
                for s, kind in self.inputs
            ],
            dtype=float,
        )

    def regression_changes(
        self, temperatures: Mapping[str, float], reference: Mapping[str, float]
    ) -> np.ndarray:
        """Each regression's prediction at the current state minus at the reference state."""
        now = self._input_row(temperatures, reference)
        then = self._input_row(reference, reference)
        changes = []
        for record in self.model["regressions"]:
            chosen = record["inputs"]
            pair = evaluate_regression(record, np.vstack([now[chosen], then[chosen]]))
            changes.append(pair[0] - pair[1])
        return np.asarray(changes, dtype=float)

    def predicted_change(
        self, temperatures: Mapping[str, float], reference: Mapping[str, float]
    ) -> np.ndarray:
        """Predicted change of the error curve since the reference state, um at each target."""
        return self.basis @ self.regression_changes(temperatures, reference)

    def parameters(
        self, temperatures: Mapping[str, float], reference: Mapping[str, float]
    ) -> ControllerParameters:
        """K0 [mm], tan(beta) [-], P0 [mm] of the compensation (= -predicted change) in one state."""
        changes = self.regression_changes(temperatures, reference)
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
        if reasons:
            return tuple(reasons)
        row = self._input_row(temperatures, reference)
        for (sensor, kind), spec, value in zip(
            self.inputs, self.model["inputs"], row, strict=False
        ):
            if base_of(sensor) in self.signals:
                # A speed beyond the training range is an extrapolation the held-out verdict
                # measures; a degC margin says nothing about it. (The channel decides, as
                # SENSOR_SIGNAL[INPUT_SENSOR[j]] does in the Structured Text block.)
                continue
            low = spec["training_min_c"] - f.range_margin_c
            high = spec["training_max_c"] + f.range_margin_c
            if not low <= value <= high:
                reasons.append(
                    f"{sensor} ({kind}): {value:.3g} C outside the training range "
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
            rate = abs(value - last[sensor][1]) / (time_s - last[sensor][0]) * 60.0
            if rate > f.max_rate_c_per_min:
                return [
                    f"{sensor}: changes {rate:.3g} C/min (limit {f.max_rate_c_per_min:g} C/min)"
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
    ) -> list[Step]:
        """The compensation cycle by cycle, with the fallback policy applied."""
        f = self.fallback
        if self.derived:
            # The reference of a derived input is its value at homing: the first cycle's,
            # unless ``reference`` holds it (homed after the filters started).
            derived = self.derived_inputs(times_s, temperatures)
            temperatures = [{**s, **d} for s, d in zip(temperatures, derived, strict=True)]
            reference = {**derived[0], **reference}
        good = _zero_parameters(self.p0_mm, self.offset_only, self.positions_mm.size)
        fault_since = None
        last: dict[str, tuple[float, float]] = {}
        steps = []
        for i, (time_s, sample) in enumerate(zip(times_s, temperatures, strict=False)):
            ages = ages_s[i] if ages_s is not None else {}
            reasons = self.faults(sample, reference, float(time_s), last, ages)
            last.update(self._plausible_readings(float(time_s), sample, ages))
            if not reasons:
                good = self.parameters(sample, reference)
                fault_since = None
                steps.append(Step(float(time_s), good, "ok"))
                continue
            fault_since = float(time_s) if fault_since is None else fault_since
            if f.policy == "hold":
                steps.append(Step(float(time_s), good, "hold", reasons))
                continue
            elapsed_min = (float(time_s) - fault_since) / 60.0
            scale = (
                max(0.0, 1.0 - elapsed_min / f.ramp_to_zero_min) if f.ramp_to_zero_min > 0 else 0.0
            )
            ramped = replace(
                good,
                k0_mm=good.k0_mm * scale,
                tan_beta=good.tan_beta * scale,
                curve_um=tuple(v * scale for v in good.curve_um),
            )
            steps.append(Step(float(time_s), ramped, "ramp", reasons))
        return steps
