"""A generated IEC 61131-3 Structured Text function block computing the TwinCAT values.

The block is written from ``model.json`` alone: the same constants the
:class:`thermaxis.compensation.runtime.Compensator` uses, printed with ``repr`` precision so a
parser reads back the very same doubles, into the Structured Text templates of
``thermaxis/compensation/templates`` (the block, and the constants and statements of
affine or RBF regressions). Each model input is a sensor's temperature
(absolute), its rise since homing (relative) or an operating signal as logged; each regression's change is its value
at the current inputs minus its value at the reference inputs. Affine models (mlr,
ridge, pls) need only

    change_r = sum_j COEFF[r, j] * (input_j - input_j at the reference)

(the constants cancel); kernel models (SVR, GPR) evaluate their RBF expansion twice.
The exported line is b = sum_r LINE_B[r] * change_r [um], k = sum_r LINE_K[r] * change_r
[um/m], and the TwinCAT values follow from the compensation = -change convention.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from thermaxis.compensation.model import CONVENTION, TENTHS_UM_PER_MM, UM_PER_MM
from thermaxis.method.inputs import base_of, parse_input_name
from thermaxis.templates import fill

__all__ = ["structured_text", "st_real"]


def st_real(value: float) -> str:
    """An LREAL literal that reads back as exactly ``value`` (IEC 61131-3 needs the decimal point)."""
    text = repr(float(value))
    if not np.isfinite(value):
        raise ValueError(
            f"cannot write {value!r} as an IEC 61131-3 literal; expected a finite number"
        )
    mantissa, _, exponent = text.partition("e")
    if "." not in mantissa:
        mantissa += ".0"
    return f"{mantissa}E{exponent}" if exponent else mantissa


def _array(values) -> str:
    return "[" + ", ".join(st_real(v) for v in values) + "]"


def _bools(values) -> str:
    return "[" + ", ".join("TRUE" if v else "FALSE" for v in values) + "]"


def _st(name: str, **values) -> str:
    """A Structured Text template of ``thermaxis/compensation/templates`` filled with ``values``."""
    return fill("thermaxis.compensation", name, **values)


def _affine_regressions(model: Mapping) -> tuple[str, str]:
    """COEFF, one row per regression over every input, and the loop computing aChange from it."""
    matrix = np.zeros((len(model["regressions"]), len(model["inputs"])))
    for r, record in enumerate(model["regressions"]):
        matrix[r, record["inputs"]] = record["coefficients"]
    constants = _st(
        "affine_constants.st.tmpl",
        n_regressions=matrix.shape[0],
        n_inputs=matrix.shape[1],
        coefficients=_array(matrix.ravel()),
    )
    return constants, _st("affine_changes.st.tmpl")


def _rbf_values(r: int, record: Mapping) -> dict:
    """The placeholders of regression ``r``'s RBF templates: its constants' prefix, sizes and values."""
    centres = np.asarray(record["centres"], dtype=float)
    n_centres, n_inputs = centres.shape
    return dict(
        r=r,
        prefix=f"R{r}_",
        target=record["target"],
        n_centres=n_centres,
        n_inputs=n_inputs,
        inputs=", ".join(str(i + 1) for i in record["inputs"]),
        input_mean=_array(record["input_mean"]),
        input_scale=_array(record["input_scale"]),
        centres=_array(centres.ravel()),
        weights=_array(record["weights"]),
        gamma=st_real(record["gamma"]),
        offset=st_real(record["offset"]),
        target_mean=st_real(record["target_mean"]),
        target_scale=st_real(record["target_scale"]),
    )


def _rbf_regressions(model: Mapping) -> tuple[str, str]:
    """Each regression's RBF constants, and its expansion at the current and at the reference inputs."""
    values = [_rbf_values(r, record) for r, record in enumerate(model["regressions"], start=1)]
    constants = "".join(_st("rbf_constants.st.tmpl", **v) for v in values)
    return constants, "".join(_st("rbf_change.st.tmpl", **v) for v in values)


def _regressions(model: Mapping) -> tuple[str, str]:
    """The constants and the statements computing aChange, for affine or RBF regressions."""
    forms = {record["form"] for record in model["regressions"]}
    if forms == {"affine"}:
        return _affine_regressions(model)
    if forms == {"rbf"}:
        return _rbf_regressions(model)
    raise ValueError(
        f"model.json: regressions mix the forms {sorted(forms)}; expected one form per model"
    )


def structured_text(model: Mapping, statement: str) -> str:
    """The function block ``ThermalCompensation`` for one ``model.json`` record."""
    constants, changes = _regressions(model)
    return _st(
        "ThermalCompensation.st.tmpl",
        **_header_values(model, statement),
        **_input_values(model),
        **_fallback_values(model["fallback"]),
        **_lag_values(model),
        regression_constants=constants,
        regression_changes=changes,
    )


def _header_values(model: Mapping, statement: str) -> dict:
    """What the comment above the block says of the model, its inputs and its fallback."""
    sensors, inputs, policy = list(model["sensors"]), model["inputs"], model["fallback"]["policy"]
    signals = list(model.get("signals", ()))
    offset_only = len(model["positions_mm"]) == 1
    return dict(
        statement=statement,
        approach=model["approach"],
        algorithm=model["algorithm"],
        dataset=model.get("dataset", "?"),
        schema_version=model["schema_version"],
        convention=CONVENTION,
        single_target_note=" Single target: offset only, coefficient 0." if offset_only else "",
        sensor_list=", ".join(f"{i}: {s}" for i, s in enumerate(sensors, start=1)),
        signal_note=_signal_note(sensors, signals),
        input_list="; ".join(
            f"{j}: {i['sensor']} {i['temperature']}" for j, i in enumerate(inputs, start=1)
        ),
        policy=policy,
        policy_effect=(
            "the last good values ramp linearly to zero over RAMP_TIME"
            if policy == "ramp_to_zero"
            else "the last good values are held"
        ),
    )


def _signal_note(sensors: list, signals: list) -> str:
    """The header's line naming the channels that hold operating signals (none: empty)."""
    if not signals:
        return ""
    channels = ", ".join(f"{sensors.index(s) + 1} ({s})" for s in signals)
    if len(signals) == 1:
        return f"\n     channel {channels} is an operating signal in its logged unit, not a temperature"
    return (
        f"\n     channels {channels} are operating signals in their logged units, not temperatures"
    )


def _input_values(model: Mapping) -> dict:
    """Sizes, the inputs' sensors, kinds and training ranges, the line weights and P0."""
    sensors, inputs = list(model["sensors"]), model["inputs"]
    weights = np.asarray(model["line_weights"], dtype=float)
    return dict(
        n_sensors=len(sensors),
        n_inputs=len(inputs),
        n_regressions=len(model["regressions"]),
        sensor_signal=_bools(s in model.get("signals", ()) for s in sensors),
        sensor_noise=_array(model.get("noise_c", {}).get(s, 0.0) for s in sensors),
        input_sensor=", ".join(str(sensors.index(base_of(i["sensor"])) + 1) for i in inputs),
        input_relative=_bools(i["temperature"] == "relative" for i in inputs),
        input_min=_array(i["training_min_c"] for i in inputs),
        input_max=_array(i["training_max_c"] for i in inputs),
        line_b=_array(weights[0]),
        line_k=_array(weights[1]),
        p0_mm=st_real(float(model["reference"]["reference_position_mm"])),
        tenths_um_per_mm=st_real(TENTHS_UM_PER_MM),
        tenths_um_per_um=st_real(TENTHS_UM_PER_MM / UM_PER_MM),
    )


def _lag_values(model: Mapping) -> dict:
    """The lag filters' constants, state and statements; empty for a model without lag inputs.

    Each lag input gets its own filter (its sensor and time constant), so an input's
    INPUT_LAG names the filter whose output replaces its sensor's temperature.
    """
    sensors, names = list(model["sensors"]), [i["sensor"] for i in model["inputs"]]
    derived = {name: parse_input_name(name) for name in names if "@" in name}
    rates = [name for name, (_, kind, _) in derived.items() if kind != "lag"]
    if rates:
        raise ValueError(
            f"model.json input {rates[0]!r}: the Structured Text block computes lag inputs only; "
            "expected <sensor>@lag<duration> (deploy a rate input with thermaxis's Compensator)"
        )
    lags = list(dict.fromkeys(derived))
    if not lags:
        return dict(lag_constants="", lag_variables="", lag_update="", lag_input="")
    values = dict(
        n_lags=len(lags),
        n_inputs=len(names),
        lag_sensor=", ".join(str(sensors.index(derived[n][0]) + 1) for n in lags),
        lag_tau=_array(derived[n][2] for n in lags),
        input_lag=", ".join(str(lags.index(n) + 1) if n in derived else "0" for n in names),
    )
    return dict(
        lag_constants=_st("lag_constants.st.tmpl", **values),
        lag_variables=_st("lag_variables.st.tmpl", **values),
        lag_update=_st("lag_update.st.tmpl"),
        lag_input=_st("lag_input.st.tmpl"),
    )


def _fallback_values(fallback: Mapping) -> dict:
    """The fault limits and the fallback policy as constants of the block."""
    return dict(
        range_margin=st_real(fallback["range_margin_c"]),
        plausible_min=st_real(fallback["plausible_c"][0]),
        plausible_max=st_real(fallback["plausible_c"][1]),
        max_rate=st_real(fallback["max_rate_c_per_min"]),
        max_age=st_real(fallback["max_sensor_age_s"]),
        policy_ramp="TRUE" if fallback["policy"] == "ramp_to_zero" else "FALSE",
        ramp_time=st_real(fallback["ramp_to_zero_min"] * 60.0),
    )
