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
(:mod:`thermaxis.method.decouple`), so for the decoupled model K0 = -delta b / 1000 and
tan(beta) = -delta k * 1e-6 exactly. For curves that are not straight (decoupling
degree 2-3, point-by-point models) the least-squares line over the targets is exported
and its largest distance from the curve is reported.

The model is stored as plain numbers (``model.json``, schema
``thermaxis/schemas/compensation_model.schema.json``): affine regressions as a constant
and one coefficient per degree C, kernel regressions (SVR, GPR) as an RBF expansion.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from dataclasses import asdict

import numpy as np
import pandas as pd

from thermaxis.config import (
    CompensationSettings,
    DecouplingSettings,
    FallbackSettings,
    ModelSettings,
)
from thermaxis.dataset.safety import check_finite
from thermaxis.errors import first_schema_error, schema_message, schema_where
from thermaxis.method.decouple import MM_PER_M
from thermaxis.method.features import relative_temperatures
from thermaxis.method.inputs import base_of, input_definition
from thermaxis.schemas import schema_path

__all__ = [
    "SCHEMA_VERSION",
    "MODEL_SCHEMA",
    "CONVENTION",
    "UM_PER_MM",
    "regression_record",
    "evaluate_regression",
    "model_record",
    "combined_record",
    "line_weights",
    "validate_model",
    "fit_axis_model",
    "fit_model_record",
]

SCHEMA_VERSION = 1
MODEL_SCHEMA = schema_path("compensation_model")
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
    """One fitted :func:`thermaxis.method.regressors.make_regressor` pipeline as plain numbers.

    ``inputs`` are indices into the model's input list. Affine fits (mlr, ridge, lasso, pls) keep
    the constant and one coefficient per input in physical units (target unit per degree
    C); SVR and GPR become ``offset + sum_i w_i exp(-gamma |z - z_i|^2)`` on standardised
    inputs z, scaled back to the target's unit.
    """
    record = {"target": target, "position_mm": position_mm, "inputs": [int(i) for i in inputs]}
    # The fitting side's imports (scikit-learn) stay out of the controller side's start.
    from thermaxis.method.regressors import linear_terms

    terms = linear_terms(pipeline, [str(i) for i in inputs])
    if terms is not None:
        return {
            **record,
            "form": "affine",
            "constant": terms["const"],
            "coefficients": [terms[str(i)] for i in inputs],
        }
    from sklearn.gaussian_process import GaussianProcessRegressor

    scaler = pipeline.named_steps["standardise"]
    target_scaler = pipeline.named_steps["regress"].transformer_
    regressor = pipeline.named_steps["regress"].regressor_
    if isinstance(regressor, GaussianProcessRegressor):
        # Constant * RBF + White: the white noise adds nothing off the training points.
        kernel = regressor.kernel_
        gamma = 1.0 / (2.0 * float(kernel.length_scale) ** 2)
        centres = regressor.X_train_
        weights = float(kernel.constant_value) * np.asarray(regressor.alpha_, dtype=float).ravel()
        offset = 0.0
    else:
        if regressor.kernel != "rbf":
            raise ValueError(
                f"compensation: SVR kernel {regressor.kernel!r} cannot be exported; expected 'rbf'"
            )
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
    """A record's prediction for input rows ``values`` (n, inputs of the record).

    Every row goes through the same operations in the same order (products, then numpy's
    sum along the row), so equal rows give equal predictions and a change since the
    reference state is exactly 0 at the reference. A BLAS matrix-vector product does not
    promise that: OpenBLAS's SkylakeX kernel summed the last row of six in another order
    than the first, and the first measurement's K0 came out -4.1e-35 mm instead of 0.
    """
    u = np.atleast_2d(np.asarray(values, dtype=float))
    if record["form"] == "affine":
        return record["constant"] + (u * np.asarray(record["coefficients"], dtype=float)).sum(
            axis=1
        )
    z = (u - np.asarray(record["input_mean"])) / np.asarray(record["input_scale"])
    centres = np.asarray(record["centres"], dtype=float)
    squared = ((z[:, None, :] - centres[None, :, :]) ** 2).sum(axis=2)
    kernel = np.exp(-record["gamma"] * squared)
    standardised = (kernel * np.asarray(record["weights"], dtype=float)).sum(axis=1)
    return (standardised + record["offset"]) * record["target_scale"] + record["target_mean"]


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
    """The model's inputs as (name, kind); operating signals (and their lags) come last, as logged."""
    signals = [(s, "signal") for s in estimator.signals]
    if approach == "decoupled":
        return (
            [(s, "absolute") for s in estimator.k_sensors]
            + [(s, "relative") for s in estimator.b_sensors]
            + signals
        )
    return [(s, "relative") for s in estimator.sensors] + signals


def _input_values(X: pd.DataFrame, inputs: Sequence[tuple[str, str]]) -> np.ndarray:
    sensors = sorted({s for s, kind in inputs if kind == "relative"})
    relative = relative_temperatures(X, sensors)
    return np.column_stack(
        [(relative[s] if kind == "relative" else X[s]).to_numpy(dtype=float) for s, kind in inputs]
    )


def model_record(
    estimator,
    approach: str,
    algorithm: str,
    X_train: pd.DataFrame,
    fallback: FallbackSettings,
    noise_c: Mapping[str, float] | None = None,
    **about,
) -> dict:
    """The ``model.json`` content of a fitted Decoupled- or PointwiseAxisModel.

    ``noise_c``: each temperature sensor's largest step between log samples in the
    training runs (:func:`thermaxis.compensation.held_out.step_noise`; 0 where absent).
    ``about`` adds descriptive keys (dataset, provenance, held_out_accuracy, ...).
    """
    inputs = _inputs_of(approach, estimator)
    index = {item: i for i, item in enumerate(inputs)}
    positions = np.asarray(estimator.positions_mm_, dtype=float)
    origin = float(positions[0])
    regressions, basis = _regressions(estimator, approach, index, positions)
    values = _input_values(X_train, inputs)
    return {
        "schema": "thermaxis-compensation-model",
        "schema_version": SCHEMA_VERSION,
        **about,
        "convention": CONVENTION,
        "approach": approach,
        "algorithm": algorithm,
        "degree": int(getattr(estimator, "degree", 0)),
        # The logged channels the controller reads (temperatures, then operating signals);
        # a time-aware input names its own.
        "sensors": list(dict.fromkeys(base_of(s) for s, _ in inputs)),
        "signals": list(dict.fromkeys(base_of(s) for s, kind in inputs if kind == "signal")),
        # To the micro-degree: the differences of logged decimals carry binary noise
        # (0.04100000000000037) that a PLC engineer should not have to read.
        "noise_c": {
            sensor: round(float((noise_c or {}).get(sensor, 0.0)), 6)
            for sensor in dict.fromkeys(base_of(s) for s, kind in inputs if kind != "signal")
        },
        "inputs": _input_entries(inputs, values),
        "reference": {
            "temperatures": "captured when the axis is homed (referenced); relative inputs are temperature minus this reference",
            "static_pitch_table": "measured in the reference state; the temperature compensation is zero there",
            "reference_position_mm": origin,
        },
        "positions_mm": positions.tolist(),
        "units": {
            "k": "um/m",
            "b": "um",
            "c2": "um/m^2",
            "c3": "um/m^3",
            "error": "um",
            "coefficients": "target unit per degree C",
        },
        "regressions": regressions,
        "line_weights": line_weights(positions, origin, basis).tolist(),
        "curve_basis": basis.tolist(),
        "fallback": asdict(fallback) | {"plausible_c": list(fallback.plausible_c)},
    }


def _regressions(estimator, approach: str, index: Mapping, positions: np.ndarray):
    """The regressions of the model and the curve basis that turns their targets into errors.

    Decoupled: one regression per coefficient (b, k, c2, c3), the basis the powers of the
    position from the first one, in metres.  Point by point: one regression per position,
    the basis the identity.
    """
    origin = float(positions[0])
    regressions = []
    # Every regression sees the operating signals after its temperatures (estimators._features).
    signal_inputs = [index[(s, "signal")] for s in estimator.signals]
    if approach == "decoupled":
        k_inputs = [index[(s, "absolute")] for s in estimator.k_sensors] + signal_inputs
        b_inputs = [index[(s, "relative")] for s in estimator.b_sensors] + signal_inputs
        for target, _, kind in estimator._targets():
            chosen = b_inputs if kind == "relative" else k_inputs
            regressions.append(
                regression_record(target, None, chosen, estimator.estimators_[target])
            )
        power = {"b": 0, "k": 1, "c2": 2, "c3": 3}
        shifted = (positions - origin) / MM_PER_M
        basis = np.column_stack([shifted ** power[r["target"]] for r in regressions])
    else:
        chosen = [index[(s, "relative")] for s in estimator.sensors] + signal_inputs
        for position, pipeline in zip(positions, estimator.estimators_, strict=False):
            regressions.append(regression_record("error", float(position), chosen, pipeline))
        basis = np.eye(positions.size)
    return regressions, basis


def _input_entries(inputs: Sequence[tuple[str, str]], values: np.ndarray) -> list[dict]:
    """Each input with its training range (and, time-aware, its definition)."""
    return [
        {
            "sensor": s,
            "temperature": kind,
            "training_min_c": float(values[:, i].min()),
            "training_max_c": float(values[:, i].max()),
            **({"definition": input_definition(s)} if "@" in s else {}),
        }
        for i, (s, kind) in enumerate(inputs)
    ]


def combined_record(members: Sequence[tuple[str, float, Mapping]], **about) -> dict:
    """One linear ``model.json`` from member records fitted on the same runs, weighted.

    ``members``: (candidate name, weight, its :func:`model_record`). The combination's
    predicted error curve is the weighted sum of the members' (the super learner,
    :mod:`thermaxis.method.nested`): the members' regressions are concatenated, their
    inputs merged, and each member's ``curve_basis`` columns scaled by its weight, so
    ``curve_basis`` times the regressions' changes is that sum, and ``line_weights`` its
    least-squares line. A member of weight 0 is left out (the controller reads nothing it
    does not use); an RBF member cannot share the block and is refused.
    """
    kept = [(name, float(w), r) for name, w, r in members if w > 0]
    first = kept[0][2]
    inputs: list[dict] = []
    index: dict[tuple[str, str], int] = {}
    regressions, bases, about_members = [], [], []
    for name, weight, record in kept:
        if record["positions_mm"] != first["positions_mm"]:
            raise ValueError(
                f"combination: member {name!r} has other positions than {kept[0][0]!r}"
            )
        regressions += _member_regressions(name, record, inputs, index)
        bases.append(weight * np.asarray(record["curve_basis"], dtype=float))
        about_members.append(
            {"candidate": name, "weight": weight, "approach": record["approach"],
             "algorithm": record["algorithm"], "regressions": len(record["regressions"])}
        )  # fmt: skip
    basis = np.hstack(bases)
    positions = np.asarray(first["positions_mm"], dtype=float)
    origin = float(first["reference"]["reference_position_mm"])
    return {
        "schema": first["schema"],
        "schema_version": first["schema_version"],
        **about,
        "convention": first["convention"],
        "approach": "combination",
        "algorithm": "super learner",
        "degree": max(int(r["degree"]) for _, _, r in kept),
        "members": about_members,
        "sensors": list(dict.fromkeys(s for _, _, r in kept for s in r["sensors"])),
        "signals": list(dict.fromkeys(s for _, _, r in kept for s in r["signals"])),
        "noise_c": _largest_noise(record for _, _, record in kept),
        "inputs": inputs,
        "reference": first["reference"],
        "positions_mm": first["positions_mm"],
        "units": first["units"],
        "regressions": regressions,
        "line_weights": line_weights(positions, origin, basis).tolist(),
        "curve_basis": basis.tolist(),
        "fallback": first["fallback"],
    }


def _member_regressions(name: str, record: Mapping, inputs: list, index: dict) -> list[dict]:
    """A member's regressions, their inputs renumbered into the merged ``inputs``.

    ``inputs`` and ``index`` (sensor, temperature) -> position grow with the member's
    inputs not seen yet, so a sensor two members read is read once.
    """
    regressions = []
    local = []
    for spec in record["inputs"]:
        key = (spec["sensor"], spec["temperature"])
        if key not in index:
            index[key] = len(inputs)
            inputs.append(dict(spec))
        local.append(index[key])
    for regression in record["regressions"]:
        if regression["form"] != "affine":
            raise ValueError(
                f"combination: member {name!r} is not linear ({regression['form']}); "
                "expected affine regressions only"
            )
        regressions.append({**regression, "inputs": [local[i] for i in regression["inputs"]]})
    return regressions


def _largest_noise(records) -> dict[str, float]:
    """Each sensor's step noise, the largest over the members: the fallback's safe side."""
    noise: dict[str, float] = {}
    for record in records:
        for sensor, value in record["noise_c"].items():
            noise[sensor] = max(noise.get(sensor, 0.0), value)
    return noise


def validate_model(record: Mapping, where: str = "model.json") -> None:
    """Raise ValueError with one line when ``record`` does not follow the committed schema."""
    with open(MODEL_SCHEMA, encoding="utf-8") as fh:
        schema = json.load(fh)
    error = first_schema_error(schema, record)
    if error is not None:
        raise ValueError(f"{where}: {schema_where(error)}: {schema_message(error)}")
    # Python's JSON reader takes NaN, Infinity and 1e999; a controller would apply them.
    check_finite(where, record)
    _check_consistency(record, where)
    _check_regression_shapes(record, where)
    # The runtime computes a derived input from its name; a definition saying otherwise
    # would describe a model other than the one run.
    for i, spec in enumerate(record["inputs"]):
        if "definition" in spec:
            try:
                expected = input_definition(spec["sensor"])
            except ValueError as exc:
                raise ValueError(f"{where}: inputs/{i}/sensor: {exc}") from None
            if spec["definition"] != expected:
                raise ValueError(
                    f"{where}: inputs/{i}/definition: does not match the input's name "
                    f"{spec['sensor']!r}; expected {expected}"
                )


def _check_consistency(record: Mapping, where: str) -> None:
    """What the schema cannot say: each input is of a sensor the model reads, with a
    training range low to high; the plausible range is low to high; the controller's
    matrices have a row per line term (b, k) and per position, a column per regression."""
    sensors = {base_of(s) for s in record["sensors"]}
    for i, spec in enumerate(record["inputs"]):
        if base_of(spec["sensor"]) not in sensors:
            raise ValueError(
                f"{where}: inputs/{i}/sensor: {spec['sensor']!r} is not of a sensor the model "
                f"reads (expected one of {', '.join(record['sensors'])})"
            )
        if not spec["training_min_c"] <= spec["training_max_c"]:
            raise ValueError(
                f"{where}: inputs/{i}: training_min_c {spec['training_min_c']:g} is above "
                f"training_max_c {spec['training_max_c']:g}; expected the training range low to high"
            )
    low, high = record["fallback"]["plausible_c"]
    if not low < high:
        raise ValueError(
            f"{where}: fallback/plausible_c: expected [low, high] with low < high, got "
            f"[{low:g}, {high:g}]"
        )
    n_regressions = len(record["regressions"])
    for name, rows in (("line_weights", 2), ("curve_basis", len(record["positions_mm"]))):
        matrix = record[name]
        if len(matrix) != rows or any(len(row) != n_regressions for row in matrix):
            raise ValueError(
                f"{where}: {name}: expected {rows} row(s) of {n_regressions} number(s) (one per "
                f"regression), got {len(matrix)} row(s) of "
                f"{', '.join(sorted({str(len(row)) for row in matrix})) or 'none'}"
            )


def _check_regression_shapes(record: Mapping, where: str) -> None:
    """Each regression reads inputs the model has, with one number per input (and per
    centre): the schema checks types, not how many."""
    n_inputs = len(record["inputs"])
    for i, regression in enumerate(record["regressions"]):
        at = f"{where}: regressions/{i}"
        beyond = [j for j in regression["inputs"] if j >= n_inputs]
        if beyond:
            raise ValueError(
                f"{at}/inputs: index {beyond[0]} is beyond the model's {n_inputs} inputs "
                f"(expected 0 to {n_inputs - 1})"
            )
        n = len(regression["inputs"])
        if regression["form"] == "affine":
            sized = {"coefficients": regression["coefficients"]}
        else:
            sized = {
                "input_mean": regression["input_mean"],
                "input_scale": regression["input_scale"],
                **{f"centres/{c}": row for c, row in enumerate(regression["centres"])},
            }
        for name, values in sized.items():
            if len(values) != n:
                raise ValueError(
                    f"{at}/{name}: {len(values)} number(s) for {n} input(s); expected one per input"
                )
        if regression["form"] == "rbf" and len(regression["weights"]) != len(regression["centres"]):
            raise ValueError(
                f"{at}/weights: {len(regression['weights'])} weight(s) for "
                f"{len(regression['centres'])} centre(s); expected one per centre"
            )


# --------------------------------------------------------------------------- fitting and held-out evaluation


def fit_axis_model(
    X: pd.DataFrame,
    Y: pd.DataFrame,
    approach: str,
    algorithm: str,
    selection,
    model_settings,
    degree: int | None,
):
    """The configured model fitted on the rows given (all runs, or a fold's training runs)."""
    # The estimator the folds are evaluated with, so the deployed model is the one scored.
    from thermaxis.method.folds import build_model

    return build_model(approach, algorithm, selection, model_settings, degree).fit(X, Y)


def fit_model_record(
    X: pd.DataFrame,
    Y: pd.DataFrame,
    selection,
    approach: str,
    models: ModelSettings,
    decoupling: DecouplingSettings,
    settings: CompensationSettings,
    noise_c: Mapping[str, float] | None = None,
    **about,
) -> dict:
    """Fit the configured model on X, Y and return its ``model.json`` record.

    ``approach`` is the workflow's (pointwise for a single-position dataset, else
    ``settings.approach``); ``about`` adds descriptive keys. The record names the runs
    it was fitted on.
    """
    estimator = fit_axis_model(
        X, Y, approach, settings.algorithm, selection, models, decoupling.degree
    )
    trained_on = sorted(X["run"].unique().tolist())
    return model_record(
        estimator,
        approach,
        settings.algorithm,
        X,
        settings.fallback,
        noise_c,
        trained_on=trained_on,
        **about,
    )
