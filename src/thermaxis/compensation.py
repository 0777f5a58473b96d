"""From a fitted thermal-error model to a machine: the deployable compensation.

Direction convention (every export states it): the positional deviation is
e = actual position - target position (the interferometer's reading minus the target,
ISO 230-2), in um. The static pitch-error table is measured in the *reference state*,
the state in which the axis is homed (referenced) and the reference temperatures are
captured. The temperature compensation supplies what the pitch table cannot:

    compensation c(x) = -(e_hat(x; T) - e_hat(x; T_ref))

the negative of the model's predicted change of the error since the reference state,
so c is zero when the axis is in its reference state. A controller adds c to the
position setpoint; the deviation left is e + c.

Controllers take a straight line per temperature state:

* SINUMERIK 840D: c = K0 + tan(beta) * (Px - P0), SD43900 K0 [mm], SD43910 tan(beta)
  [dimensionless, mm per mm], SD43920 P0 [mm];
* TwinCAT CNC: P-AXIS-00272 temp_comp_position_0 [0.1 um], P-AXIS-00273
  temp_comp_offset_0 [0.1 um], P-AXIS-00274 temp_comp_coefficient [um/m] (SGN32).

P0 is the first target, the origin of the shifted stroke of the decoupling
(:mod:`thermaxis.decouple`), so for the decoupled model K0 = -delta b / 1000 and
tan(beta) = -delta k * 1e-6 exactly. For curves that are not straight (decoupling
degree 2-3, point-by-point models) the least-squares line over the targets is exported
and its largest distance from the curve is reported.

The model is stored as plain numbers (``model.json``, schema
``workflow/schemas/compensation_model.schema.json``): affine regressions as a constant
and one coefficient per degree C, kernel regressions (SVR, GPR) as an RBF expansion.
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Mapping, Sequence

import jsonschema
import numpy as np
import pandas as pd

from .config import CompensationSettings, DecouplingSettings, ErrorCleaning, FallbackSettings, ModelSettings
from .decouple import MM_PER_M
from .models import linear_terms, relative_temperatures

__all__ = [
    "SCHEMA_VERSION",
    "MODEL_SCHEMA",
    "CONVENTION",
    "UM_PER_MM",
    "ControllerParameters",
    "Step",
    "Compensator",
    "regression_record",
    "evaluate_regression",
    "model_record",
    "line_weights",
    "siemens_840d",
    "twincat",
    "validate_model",
    "fit_axis_model",
    "fit_model_record",
    "held_out_accuracy",
    "run_states",
    "pass_deviations",
    "held_out_tables",
    "file_header",
]

SCHEMA_VERSION = 1
MODEL_SCHEMA = Path(__file__).resolve().parents[2] / "workflow" / "schemas" / "compensation_model.schema.json"
UM_PER_MM = 1000.0
# 0.1 um per register count (TwinCAT P-AXIS-00272/00273).
TENTHS_UM_PER_MM = 1e4
CONVENTION = (
    "deviation e = actual - target (um, ISO 230-2); compensation c = -(predicted e at the current temperatures "
    "- predicted e at the reference temperatures captured when the axis was homed); the controller adds c to the "
    "setpoint, the deviation left is e + c; 840D: c = K0 + tan(beta) * (Px - P0)"
)


# --------------------------------------------------------------------------- regressions as numbers


def regression_record(target: str, position_mm, inputs: Sequence[int], pipeline) -> dict:
    """One fitted :func:`thermaxis.models.make_regressor` pipeline as plain numbers.

    ``inputs`` are indices into the model's input list. Affine fits (mlr, ridge, pls) keep
    the constant and one coefficient per input in physical units (target unit per degree
    C); SVR and GPR become ``offset + sum_i w_i exp(-gamma |z - z_i|^2)`` on standardised
    inputs z, scaled back to the target's unit.
    """
    record = {"target": target, "position_mm": position_mm, "inputs": [int(i) for i in inputs]}
    terms = linear_terms(pipeline, [str(i) for i in inputs])
    if terms is not None:
        return {**record, "form": "affine", "constant": terms["const"], "coefficients": [terms[str(i)] for i in inputs]}
    from sklearn.gaussian_process import GaussianProcessRegressor

    scaler = pipeline.named_steps["standardise"]
    target_scaler = pipeline.named_steps["regress"].transformer_
    regressor = pipeline.named_steps["regress"].regressor_
    if isinstance(regressor, GaussianProcessRegressor):
        # Constant * RBF + White: the white noise adds nothing off the training points.
        kernel = regressor.kernel_.k1
        gamma = 1.0 / (2.0 * float(kernel.k2.length_scale) ** 2)
        centres = regressor.X_train_
        weights = float(kernel.k1.constant_value) * np.asarray(regressor.alpha_, dtype=float).ravel()
        offset = 0.0
    else:
        if regressor.kernel != "rbf":
            raise ValueError(f"compensation: SVR kernel {regressor.kernel!r} cannot be exported; expected 'rbf'")
        gamma = float(regressor._gamma)
        centres = regressor.support_vectors_
        weights = np.asarray(regressor.dual_coef_, dtype=float).ravel()
        offset = float(regressor.intercept_[0])
    return {
        **record,
        "form": "rbf",
        "input_mean": scaler.mean_.tolist(),
        "input_scale": scaler.scale_.tolist(),
        "target_mean": float(target_scaler.mean_[0]),
        "target_scale": float(target_scaler.scale_[0]),
        "gamma": gamma,
        "centres": np.asarray(centres, dtype=float).tolist(),
        "weights": weights.tolist(),
        "offset": offset,
    }


def evaluate_regression(record: Mapping, values) -> np.ndarray:
    """A record's prediction for input rows ``values`` (n, inputs of the record)."""
    u = np.atleast_2d(np.asarray(values, dtype=float))
    if record["form"] == "affine":
        return record["constant"] + u @ np.asarray(record["coefficients"], dtype=float)
    z = (u - np.asarray(record["input_mean"])) / np.asarray(record["input_scale"])
    centres = np.asarray(record["centres"], dtype=float)
    squared = ((z[:, None, :] - centres[None, :, :]) ** 2).sum(axis=2)
    standardised = np.exp(-record["gamma"] * squared) @ np.asarray(record["weights"]) + record["offset"]
    return standardised * record["target_scale"] + record["target_mean"]


def line_weights(positions_mm: Sequence[float], origin_mm: float, basis: np.ndarray) -> np.ndarray:
    """(2, R) weights giving the least-squares line (b [um], k [um/m]) from the regressions' changes.

    ``basis`` (positions, R) maps the R regression changes to the error curve at the
    targets. With a single target there is no slope: b is the curve, k is 0.
    """
    positions = np.asarray(positions_mm, dtype=float)
    if positions.size == 1:
        return np.vstack([basis[0], np.zeros(basis.shape[1])])
    design = np.column_stack([np.ones(positions.size), (positions - origin_mm) / MM_PER_M])
    return np.linalg.pinv(design) @ basis


# --------------------------------------------------------------------------- building model.json


def _inputs_of(approach: str, estimator) -> list[tuple[str, str]]:
    if approach == "decoupled":
        return [(s, "absolute") for s in estimator.k_sensors] + [(s, "relative") for s in estimator.b_sensors]
    return [(s, "relative") for s in estimator.sensors]


def _input_values(X: pd.DataFrame, inputs: Sequence[tuple[str, str]]) -> np.ndarray:
    sensors = sorted({s for s, _ in inputs})
    relative = relative_temperatures(X, sensors)
    return np.column_stack([(X[s] if kind == "absolute" else relative[s]).to_numpy(dtype=float) for s, kind in inputs])


def model_record(estimator, approach: str, algorithm: str, X_train: pd.DataFrame, fallback: FallbackSettings, **about) -> dict:
    """The ``model.json`` content of a fitted Decoupled- or PointwiseAxisModel.

    ``about`` adds descriptive keys (dataset, provenance, held_out_accuracy, ...).
    """
    inputs = _inputs_of(approach, estimator)
    index = {item: i for i, item in enumerate(inputs)}
    positions = np.asarray(estimator.positions_mm_, dtype=float)
    origin = float(positions[0])
    regressions = []
    if approach == "decoupled":
        k_inputs = [index[(s, "absolute")] for s in estimator.k_sensors]
        b_inputs = [index[(s, "relative")] for s in estimator.b_sensors]
        for target, _, kind in estimator._targets():
            chosen = b_inputs if kind == "relative" else k_inputs
            regressions.append(regression_record(target, None, chosen, estimator.estimators_[target]))
        power = {"b": 0, "k": 1, "c2": 2, "c3": 3}
        shifted = (positions - origin) / MM_PER_M
        basis = np.column_stack([shifted ** power[r["target"]] for r in regressions])
    else:
        chosen = [index[(s, "relative")] for s in estimator.sensors]
        for position, pipeline in zip(positions, estimator.estimators_):
            regressions.append(regression_record("error", float(position), chosen, pipeline))
        basis = np.eye(positions.size)
    values = _input_values(X_train, inputs)
    return {
        "schema": "thermaxis-compensation-model",
        "schema_version": SCHEMA_VERSION,
        **about,
        "convention": CONVENTION,
        "approach": approach,
        "algorithm": algorithm,
        "degree": int(getattr(estimator, "degree", 0)),
        "sensors": list(dict.fromkeys(s for s, _ in inputs)),
        "inputs": [
            {"sensor": s, "temperature": kind, "training_min_c": float(values[:, i].min()), "training_max_c": float(values[:, i].max())}
            for i, (s, kind) in enumerate(inputs)
        ],
        "reference": {
            "temperatures": "captured when the axis is homed (referenced); relative inputs are temperature minus this reference",
            "static_pitch_table": "measured in the reference state; the temperature compensation is zero there",
            "reference_position_mm": origin,
        },
        "positions_mm": positions.tolist(),
        "units": {"k": "um/m", "b": "um", "c2": "um/m^2", "c3": "um/m^3", "error": "um", "coefficients": "target unit per degree C"},
        "regressions": regressions,
        "line_weights": line_weights(positions, origin, basis).tolist(),
        "curve_basis": basis.tolist(),
        "fallback": asdict(fallback) | {"plausible_c": list(fallback.plausible_c)},
    }


def validate_model(record: Mapping, where: str = "model.json") -> None:
    """Raise ValueError with one line when ``record`` does not follow the committed schema."""
    with open(MODEL_SCHEMA, encoding="utf-8") as fh:
        schema = json.load(fh)
    errors = sorted(jsonschema.Draft202012Validator(schema).iter_errors(record), key=lambda e: list(e.absolute_path))
    if errors:
        path = "/".join(map(str, errors[0].absolute_path)) or "top level"
        raise ValueError(f"{where}: {path}: {errors[0].message}")


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
    """The deployable model: predicted error curve and controller parameters from temperatures.

    Build it with :meth:`from_json`. :meth:`parameters` is the pure computation for one
    temperature state; :meth:`run` applies the fallback policy to a time series, as a
    PLC would cycle by cycle.
    """

    def __init__(self, model: Mapping, fallback: FallbackSettings | None = None, where: str = "model.json"):
        validate_model(model, where)
        self.model = model
        self.inputs = [(i["sensor"], i["temperature"]) for i in model["inputs"]]
        self.sensors = tuple(model["sensors"])
        self.positions_mm = np.asarray(model["positions_mm"], dtype=float)
        self.p0_mm = float(model["reference"]["reference_position_mm"])
        self.offset_only = self.positions_mm.size == 1
        self.weights = np.asarray(model["line_weights"], dtype=float)
        self.basis = np.asarray(model["curve_basis"], dtype=float)
        f = model["fallback"]
        self.fallback = fallback or FallbackSettings(**{**f, "plausible_c": tuple(f["plausible_c"])})

    @classmethod
    def from_json(cls, path, fallback: FallbackSettings | None = None) -> "Compensator":
        path = Path(path)
        try:
            model = json.loads(path.read_text(encoding="utf-8"))
        except OSError as exc:
            raise ValueError(f"{path}: cannot read the model ({exc.strerror})") from exc
        except json.JSONDecodeError as exc:
            raise ValueError(f"{path}: line {exc.lineno}: not valid JSON ({exc.msg})") from exc
        return cls(model, fallback, where=str(path))

    def _input_row(self, temperatures: Mapping[str, float], reference: Mapping[str, float]) -> np.ndarray:
        return np.array(
            [temperatures[s] if kind == "absolute" else temperatures[s] - reference[s] for s, kind in self.inputs],
            dtype=float,
        )

    def regression_changes(self, temperatures: Mapping[str, float], reference: Mapping[str, float]) -> np.ndarray:
        """Each regression's prediction at the current state minus at the reference state."""
        now = self._input_row(temperatures, reference)
        then = self._input_row(reference, reference)
        changes = []
        for record in self.model["regressions"]:
            chosen = record["inputs"]
            pair = evaluate_regression(record, np.vstack([now[chosen], then[chosen]]))
            changes.append(pair[0] - pair[1])
        return np.asarray(changes, dtype=float)

    def predicted_change(self, temperatures: Mapping[str, float], reference: Mapping[str, float]) -> np.ndarray:
        """Predicted change of the error curve since the reference state, um at each target."""
        return self.basis @ self.regression_changes(temperatures, reference)

    def parameters(self, temperatures: Mapping[str, float], reference: Mapping[str, float]) -> ControllerParameters:
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
            if not math.isfinite(value):
                reasons.append(f"{sensor}: missing")
            elif age > f.max_sensor_age_s:
                reasons.append(f"{sensor}: stale, last update {age:g} s ago (limit {f.max_sensor_age_s:g} s)")
            elif not lo <= value <= hi:
                reasons.append(f"{sensor}: implausible {value:g} C (plausible {lo:g} ... {hi:g} C)")
            elif last and sensor in last and time_s > last[sensor][0]:
                rate = abs(value - last[sensor][1]) / (time_s - last[sensor][0]) * 60.0
                if rate > f.max_rate_c_per_min:
                    reasons.append(f"{sensor}: changes {rate:.3g} C/min (limit {f.max_rate_c_per_min:g} C/min)")
            if not (math.isfinite(ref) and lo <= ref <= hi):
                reasons.append(f"{sensor}: reference temperature missing or implausible")
        if reasons:
            return tuple(reasons)
        row = self._input_row(temperatures, reference)
        for (sensor, kind), spec, value in zip(self.inputs, self.model["inputs"], row):
            low = spec["training_min_c"] - f.range_margin_c
            high = spec["training_max_c"] + f.range_margin_c
            if not low <= value <= high:
                reasons.append(
                    f"{sensor} ({kind}): {value:.3g} C outside the training range "
                    f"{spec['training_min_c']:.3g} ... {spec['training_max_c']:.3g} C by more than {f.range_margin_c:g} C"
                )
        return tuple(reasons)

    def _plausible_readings(self, time_s: float, sample: Mapping[str, float], ages: Mapping[str, float]) -> dict:
        lo, hi = self.fallback.plausible_c
        return {
            s: (time_s, sample[s])
            for s in self.sensors
            if math.isfinite(sample.get(s, math.nan))
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
        good = _zero_parameters(self.p0_mm, self.offset_only, self.positions_mm.size)
        fault_since = None
        last: dict[str, tuple[float, float]] = {}
        steps = []
        for i, (time_s, sample) in enumerate(zip(times_s, temperatures)):
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
            scale = max(0.0, 1.0 - elapsed_min / f.ramp_to_zero_min) if f.ramp_to_zero_min > 0 else 0.0
            ramped = replace(
                good,
                k0_mm=good.k0_mm * scale,
                tan_beta=good.tan_beta * scale,
                curve_um=tuple(v * scale for v in good.curve_um),
            )
            steps.append(Step(float(time_s), ramped, "ramp", reasons))
        return steps


# --------------------------------------------------------------------------- controller units


def siemens_840d(p: ControllerParameters) -> list[tuple[str, str, float, str]]:
    """(parameter, name, value, unit) rows of SINUMERIK 840D setting data; SD43900 alone when offset only."""
    rows = [("SD43900", "TEMP_COMP_ABS_VALUE", p.k0_mm, "mm")]
    if not p.offset_only:
        rows += [
            ("SD43910", "TEMP_COMP_SLOPE", p.tan_beta, "dimensionless (mm/mm)"),
            ("SD43920", "TEMP_COMP_REF_POSITION", p.p0_mm, "mm"),
        ]
    return rows


def twincat(p: ControllerParameters) -> list[tuple[str, str, float, str]]:
    """(parameter, name, value, unit) rows of TwinCAT CNC axis parameters (before rounding to SGN32)."""
    return [
        ("P-AXIS-00272", "temp_comp_position_0", p.p0_mm * TENTHS_UM_PER_MM, "0.1 um"),
        ("P-AXIS-00273", "temp_comp_offset_0", p.k0_mm * TENTHS_UM_PER_MM, "0.1 um"),
        ("P-AXIS-00274", "temp_comp_coefficient", p.tan_beta * UM_PER_MM * MM_PER_M, "um/m"),
    ]


# --------------------------------------------------------------------------- fitting and held-out evaluation


def fit_axis_model(X: pd.DataFrame, Y: pd.DataFrame, approach: str, algorithm: str, selection, model_settings, degree: int | None):
    """The configured model fitted on the rows given (all runs, or a fold's training runs)."""
    # The estimator the folds are evaluated with, so the deployed model is the one scored.
    from .experiment import _build_model

    return _build_model(approach, algorithm, selection, model_settings, degree).fit(X, Y)


def fit_model_record(
    X: pd.DataFrame,
    Y: pd.DataFrame,
    selection,
    approach: str,
    models: ModelSettings,
    decoupling: DecouplingSettings,
    settings: CompensationSettings,
    **about,
) -> dict:
    """Fit the configured model on X, Y and return its ``model.json`` record.

    ``approach`` is the workflow's (pointwise for a single-position dataset, else
    ``settings.approach``); ``about`` adds descriptive keys. The record names the runs
    it was fitted on.
    """
    estimator = fit_axis_model(X, Y, approach, settings.algorithm, selection, models, decoupling.degree)
    trained_on = sorted(X["run"].unique().tolist())
    return model_record(estimator, approach, settings.algorithm, X, settings.fallback, trained_on=trained_on, **about)


def held_out_accuracy(metrics: pd.DataFrame, approach: str, algorithm: str) -> list[dict]:
    """The folds' held-out metrics of this approach and algorithm (every target), for model.json."""
    rows = metrics[(metrics["approach"] == approach) & (metrics["algorithm"] == algorithm)]
    if rows.empty:
        raise ValueError(f"tables/metrics.csv: no rows for approach {approach!r} and algorithm {algorithm!r}")
    columns = ["fold", "target", "rmse", "max_abs", "mae", "residual_min", "residual_max"]
    return [
        {c: (str(v) if c in ("fold", "target") else float(v)) for c, v in row.items()}
        for row in rows[columns].to_dict("records")
    ]


def run_states(X_run: pd.DataFrame, sensors: Sequence[str]):
    """A run's measurement times [s], temperature samples and reference (its first measurement)."""
    ordered = X_run.sort_values("measurement", kind="stable")
    samples = [{s: float(row[s]) for s in sensors} for _, row in ordered.iterrows()]
    return (ordered["time_min"].to_numpy(dtype=float) * 60.0).tolist(), samples, samples[0]


def pass_deviations(raw_run, targets: Sequence[float], max_missing_fraction: float) -> dict[int, dict[str, np.ndarray]]:
    """Per measurement (1-based, time order) and direction ("+", "-"), the deviation at each target [um]."""
    from .clean import combine_passes

    out = {}
    for number, (name, measurement) in enumerate(raw_run.measurements.items(), start=1):
        label = f"{raw_run.run}/errors/{name}.csv"
        passes = {}
        for direction in sorted(set(measurement["direction"]), reverse=True):  # "+" before "-"
            settings = ErrorCleaning(direction=direction, max_missing_fraction=max_missing_fraction)
            curve, _ = combine_passes(measurement[measurement["direction"] == direction], targets, settings, name=label)
            passes[direction] = curve.to_numpy(dtype=float)
        out[number] = passes
    return out


def _pitch_table(first: Mapping[str, np.ndarray]) -> np.ndarray:
    """The static pitch table: the reference measurement's deviation, mean of its passes."""
    return np.nanmean(np.vstack(list(first.values())), axis=0)


def _systematic(quantities: Mapping[str, float]) -> float:
    """E, or the one direction's E when the measurement has a single pass."""
    for name in ("E", "E_up", "E_down"):
        if np.isfinite(quantities[name]):
            return quantities[name]
    return float("nan")


def _controller_rows(label: dict, rows, final_rows, status: str) -> list[dict]:
    return [
        {**label, "parameter": p, "name": n, "unit": u, "value": v, "final_model_value": fv, "status": status}
        for (p, n, v, u), (_, _, fv, _) in zip(rows, final_rows)
    ]


def held_out_tables(
    fold: str,
    steps: Sequence[Step],
    time_min: Sequence[float],
    deviations: Mapping[int, Mapping[str, np.ndarray]],
    positions_mm: Sequence[float],
    final: Sequence[ControllerParameters],
) -> dict[str, pd.DataFrame]:
    """Exports, residuals, ISO 230-2 quantities and the drift summary of one held-out run.

    ``steps`` are the fold model's values per measurement (after the fallback policy),
    ``final`` the final model's parameters for the same temperatures (reference values).
    The pitch table is the first measurement's; compensation is what the controller
    computes from the exported K0, tan(beta), P0.
    """
    from .iso230 import NEEDS_CYCLES, NOT_COMPUTED, QUANTITIES, single_pass_quantities

    positions = np.asarray(positions_mm, dtype=float)
    table = _pitch_table(deviations[1])
    siemens, tc, residuals, iso, summary = [], [], [], [], []
    for number, (step, minutes, reference) in enumerate(zip(steps, time_min, final), start=1):
        label = {"fold": fold, "run": fold, "measurement": number, "time_min": float(minutes)}
        reasons = "; ".join(step.reasons)
        siemens += _controller_rows(label, siemens_840d(step.parameters), siemens_840d(reference), step.status)
        tc_rows = _controller_rows(label, twincat(step.parameters), twincat(reference), step.status)
        for row in tc_rows:
            row["register"] = int(round(row["value"]))
        tc += tc_rows
        applied = step.parameters.at(positions)
        before, after = {}, {}
        for direction, values in deviations[number].items():
            drift = values - table
            before[direction], after[direction] = drift, drift + applied
            for x, d, c in zip(positions, drift, applied):
                residuals.append({**label, "direction": direction, "position_mm": x, "uncompensated_um": d, "compensation_um": c, "residual_um": d + c, "status": step.status})
        q_before = single_pass_quantities(before.get("+"), before.get("-"))
        q_after = single_pass_quantities(after.get("+"), after.get("-"))
        for name, description in QUANTITIES.items():
            iso.append({**label, "quantity": name, "description": description, "uncompensated_um": q_before[name], "compensated_um": q_after[name], "computed": bool(np.isfinite(q_before[name])), "note": ""})
        for name, description in NOT_COMPUTED.items():
            iso.append({**label, "quantity": name, "description": description, "uncompensated_um": np.nan, "compensated_um": np.nan, "computed": False, "note": NEEDS_CYCLES})
        all_before = np.concatenate(list(before.values()))
        all_after = np.concatenate(list(after.values()))
        summary.append(
            {
                **label,
                "status": step.status,
                "largest_abs_uncompensated_um": float(np.nanmax(np.abs(all_before))),
                "largest_abs_compensated_um": float(np.nanmax(np.abs(all_after))),
                "E_uncompensated_um": _systematic(q_before),
                "E_compensated_um": _systematic(q_after),
                "line_gap_um": step.parameters.line_gap_um,
                "reasons": reasons,
            }
        )
    return {
        "siemens_840d": pd.DataFrame(siemens),
        "twincat": pd.DataFrame(tc),
        "residuals": pd.DataFrame(residuals),
        "iso230_2": pd.DataFrame(iso),
        "summary": pd.DataFrame(summary),
    }


def file_header(kind: str, statement: str) -> str:
    """The comment block every compensation CSV starts with (read them with ``comment='#'``)."""
    lines = [f"thermaxis compensation: {kind}", statement, f"Convention: {CONVENTION}."] + HEADERS[kind]
    return "".join(f"# {line}\n" for line in lines)


HEADERS = {
    "siemens_840d": [
        "SINUMERIK 840D setting data per measurement of each held-out run, from that fold's model after the fallback policy;",
        "final_model_value: the model fitted on all runs, same temperatures. SD43900 TEMP_COMP_ABS_VALUE K0 [mm];",
        "SD43910 TEMP_COMP_SLOPE tan(beta) [dimensionless, mm/mm]; SD43920 TEMP_COMP_REF_POSITION P0 [mm].",
        "Source: SINUMERIK Function Manual Extended Functions K3 Compensations 03/2013 (6FC5397-1BP40-3BA1) sec. 4.2:",
        "compensation value = K0 + tan(beta) * (Px - P0); tan(beta)(T) = (T - T0) * TK_max * 1e-6 / (Tmax - T0) with TK in um/m,",
        "i.e. tan(beta) is dimensionless (not per mil). MD32750 TEMP_COMP_TYPE activates it (1 = position-independent only).",
    ],
    "twincat": [
        "TwinCAT CNC axis parameters per measurement of each held-out run, from that fold's model after the fallback policy;",
        "final_model_value: the model fitted on all runs, same temperatures. P-AXIS-00272 temp_comp_position_0 [0.1 um];",
        "P-AXIS-00273 temp_comp_offset_0 [0.1 um]; P-AXIS-00274 temp_comp_coefficient [um/m]; register: rounded for SGN32.",
        "Source: Beckhoff TwinCAT CNC axis parameters P-AXIS-00272/00273/00274 (infosys.beckhoff.com, tccncaxisparameter),",
        "activated by lr_param.temp_comp 1 (P-AXIS-00271), adjusted by the PLC.",
    ],
    "residuals": [
        "Per fold (held-out run), measurement, direction and target: uncompensated_um = deviation minus the static pitch table",
        "(the run's first measurement, mean of its passes); compensation_um from the exported K0, tan(beta), P0 after limits;",
        "residual_um = uncompensated_um + compensation_um (um).",
    ],
    "iso230_2": [
        "ISO 230-2 quantities one bidirectional pass supports (E_up, E_down, E, M, B; um) before and after compensation;",
        "rows with computed = False need repeated approaches and are not computed.",
    ],
    "summary": [
        "Per fold and measurement: largest |deviation| over the stroke and both directions, and E, before and after compensation (um);",
        "status ok / hold / ramp with the fallback reasons.",
    ],
}
