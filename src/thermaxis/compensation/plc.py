"""A generated IEC 61131-3 Structured Text function block computing the TwinCAT values.

The block is written from ``model.json`` alone: the same constants the
:class:`thermaxis.compensation.runtime.Compensator` uses, printed with ``repr`` precision so a
parser reads back the very same doubles. Each model input is a sensor's temperature
(absolute) or its rise since homing (relative); each regression's change is its value
at the current inputs minus its value at the reference inputs. Affine models (mlr,
ridge, pls) need only

    change_r = sum_j COEFF[r, j] * (input_j - input_j at the reference)

(the constants cancel); kernel models (SVR, GPR) evaluate their RBF expansion twice.
The exported line is b = sum_r LINE_B[r] * change_r [um], k = sum_r LINE_K[r] * change_r
[um/m], and the TwinCAT values follow from the compensation = -change convention.
"""

from __future__ import annotations

from typing import Mapping

import numpy as np

from thermaxis.compensation.model import CONVENTION, TENTHS_UM_PER_MM, UM_PER_MM

__all__ = ["structured_text", "st_real"]


def st_real(value: float) -> str:
    """An LREAL literal that reads back as exactly ``value`` (IEC 61131-3 needs the decimal point)."""
    text = repr(float(value))
    if not np.isfinite(value):
        raise ValueError(f"cannot write {value!r} as an IEC 61131-3 literal; expected a finite number")
    mantissa, _, exponent = text.partition("e")
    if "." not in mantissa:
        mantissa += ".0"
    return f"{mantissa}E{exponent}" if exponent else mantissa


def _array(values) -> str:
    return "[" + ", ".join(st_real(v) for v in values) + "]"


def _bools(values) -> str:
    return "[" + ", ".join("TRUE" if v else "FALSE" for v in values) + "]"


def _affine_constants(model: Mapping) -> str:
    matrix = np.zeros((len(model["regressions"]), len(model["inputs"])))
    for r, record in enumerate(model["regressions"]):
        matrix[r, record["inputs"]] = record["coefficients"]
    return f"    COEFF : ARRAY[1..{matrix.shape[0]}, 1..{matrix.shape[1]}] OF LREAL := {_array(matrix.ravel())};\n"


AFFINE_CHANGES = """    FOR r := 1 TO N_REGRESSIONS DO
        aChange[r] := 0.0;
        FOR j := 1 TO N_INPUTS DO
            aChange[r] := aChange[r] + COEFF[r, j] * (aInputNow[j] - aInputRef[j]);
        END_FOR
    END_FOR
"""


def _rbf_constants(r: int, record: Mapping) -> str:
    centres = np.asarray(record["centres"], dtype=float)
    n_c, n_j = centres.shape
    name = f"R{r}_"
    return (
        f"    {name}INPUTS : ARRAY[1..{n_j}] OF INT := [{', '.join(str(i + 1) for i in record['inputs'])}];\n"
        f"    {name}MEAN : ARRAY[1..{n_j}] OF LREAL := {_array(record['input_mean'])};\n"
        f"    {name}SCALE : ARRAY[1..{n_j}] OF LREAL := {_array(record['input_scale'])};\n"
        f"    {name}CENTRES : ARRAY[1..{n_c}, 1..{n_j}] OF LREAL := {_array(centres.ravel())};\n"
        f"    {name}WEIGHTS : ARRAY[1..{n_c}] OF LREAL := {_array(record['weights'])};\n"
        f"    {name}GAMMA : LREAL := {st_real(record['gamma'])};\n"
        f"    {name}OFFSET : LREAL := {st_real(record['offset'])};\n"
        f"    {name}TARGET_MEAN : LREAL := {st_real(record['target_mean'])};\n"
        f"    {name}TARGET_SCALE : LREAL := {st_real(record['target_scale'])};\n"
    )


def _rbf_change(r: int, record: Mapping) -> str:
    n_c, n_j = np.asarray(record["centres"], dtype=float).shape
    name = f"R{r}_"
    return f"""    (* regression {r} ({record['target']}): RBF expansion at the current (pass 0) and reference (pass 1) inputs *)
    FOR nPass := 0 TO 1 DO
        fSum := 0.0;
        FOR nCentre := 1 TO {n_c} DO
            fDistance := 0.0;
            FOR j := 1 TO {n_j} DO
                IF nPass = 0 THEN
                    fInput := aInputNow[{name}INPUTS[j]];
                ELSE
                    fInput := aInputRef[{name}INPUTS[j]];
                END_IF
                fZ := (fInput - {name}MEAN[j]) / {name}SCALE[j] - {name}CENTRES[nCentre, j];
                fDistance := fDistance + fZ * fZ;
            END_FOR
            fSum := fSum + {name}WEIGHTS[nCentre] * EXP(-{name}GAMMA * fDistance);
        END_FOR
        fValue := (fSum + {name}OFFSET) * {name}TARGET_SCALE + {name}TARGET_MEAN;
        IF nPass = 0 THEN
            aChange[{r}] := fValue;
        ELSE
            aChange[{r}] := aChange[{r}] - fValue;
        END_IF
    END_FOR
"""


def _regressions(model: Mapping) -> tuple[str, str]:
    """The constants and the statements computing aChange, for affine or RBF regressions."""
    forms = {record["form"] for record in model["regressions"]}
    if forms == {"affine"}:
        return _affine_constants(model), AFFINE_CHANGES
    if forms == {"rbf"}:
        records = list(enumerate(model["regressions"], start=1))
        return "".join(_rbf_constants(r, x) for r, x in records), "".join(_rbf_change(r, x) for r, x in records)
    raise ValueError(f"model.json: regressions mix the forms {sorted(forms)}; expected one form per model")


def structured_text(model: Mapping, statement: str) -> str:
    """The function block ``ThermalCompensation`` for one ``model.json`` record."""
    sensors = list(model["sensors"])
    inputs = model["inputs"]
    constants, changes = _regressions(model)
    weights = np.asarray(model["line_weights"], dtype=float)
    f = model["fallback"]
    n_s, n_i, n_r = len(sensors), len(inputs), len(model["regressions"])
    sensor_index = [sensors.index(i["sensor"]) + 1 for i in inputs]
    offset_only = len(model["positions_mm"]) == 1
    p0 = float(model["reference"]["reference_position_mm"])
    sensor_list = ", ".join(f"{i}: {s}" for i, s in enumerate(sensors, start=1))
    input_list = "; ".join(f"{j}: {i['sensor']} {i['temperature']}" for j, i in enumerate(inputs, start=1))
    ramp = f["policy"] == "ramp_to_zero"
    header = f"""(* ThermalCompensation -- generated by thermaxis from model.json; do not edit by hand.
   {statement}
   Model: {model['approach']} {model['algorithm']}, dataset {model.get('dataset', '?')}, schema version {model['schema_version']}.
   Convention: {CONVENTION}.
   Outputs (TwinCAT CNC, write them cyclically to the axis; lr_param.temp_comp 1):
     fPosition0 / nPosition0       P-AXIS-00272 temp_comp_position_0 [0.1 um]
     fOffset0 / nOffset0           P-AXIS-00273 temp_comp_offset_0 [0.1 um] = -(predicted change of b) * 10
     fCoefficient / nCoefficient   P-AXIS-00274 temp_comp_coefficient [um/m] = -(predicted change of k)
     The n* outputs are rounded for the SGN32 parameters.{' Single target: offset only, coefficient 0.' if offset_only else ''}
   Inputs: aTemperature and aReference [degC] in sensor order {sensor_list};
     aReference holds the temperatures captured when the axis was homed (the reference state of the pitch table);
     aValid FALSE marks a missing sensor; aAge [s] since each sensor's last update; fDeltaTime [s] since the previous call.
   Model inputs: {input_list}.
   Fallback: a sample with any fault (nReasons bits: 1 missing or stale, 2 implausible, 4 rate, 8 outside the training
     range) is not used; policy {f['policy']}: {'the last good values ramp linearly to zero over RAMP_TIME' if ramp else 'the last good values are held'};
     before the first good sample the outputs are zero. bFallback tells the PLC. *)
"""
    return f"""{header}FUNCTION_BLOCK ThermalCompensation
VAR_INPUT
    aTemperature : ARRAY[1..{n_s}] OF LREAL;
    aReference : ARRAY[1..{n_s}] OF LREAL;
    aValid : ARRAY[1..{n_s}] OF BOOL;
    aAge : ARRAY[1..{n_s}] OF LREAL;
    fDeltaTime : LREAL;
END_VAR
VAR_OUTPUT
    fPosition0 : LREAL;
    fOffset0 : LREAL;
    fCoefficient : LREAL;
    nPosition0 : DINT;
    nOffset0 : DINT;
    nCoefficient : DINT;
    bFallback : BOOL;
    nReasons : DWORD;
END_VAR
VAR CONSTANT
    N_SENSORS : INT := {n_s};
    N_INPUTS : INT := {n_i};
    N_REGRESSIONS : INT := {n_r};
    INPUT_SENSOR : ARRAY[1..{n_i}] OF INT := [{', '.join(map(str, sensor_index))}];
    INPUT_RELATIVE : ARRAY[1..{n_i}] OF BOOL := {_bools(i['temperature'] == 'relative' for i in inputs)};
    INPUT_MIN : ARRAY[1..{n_i}] OF LREAL := {_array(i['training_min_c'] for i in inputs)};
    INPUT_MAX : ARRAY[1..{n_i}] OF LREAL := {_array(i['training_max_c'] for i in inputs)};
{constants}    LINE_B : ARRAY[1..{n_r}] OF LREAL := {_array(weights[0])};
    LINE_K : ARRAY[1..{n_r}] OF LREAL := {_array(weights[1])};
    P0_MM : LREAL := {st_real(p0)};
    TENTHS_UM_PER_MM : LREAL := {st_real(TENTHS_UM_PER_MM)};
    TENTHS_UM_PER_UM : LREAL := {st_real(TENTHS_UM_PER_MM / UM_PER_MM)};
    RANGE_MARGIN : LREAL := {st_real(f['range_margin_c'])};
    PLAUSIBLE_MIN : LREAL := {st_real(f['plausible_c'][0])};
    PLAUSIBLE_MAX : LREAL := {st_real(f['plausible_c'][1])};
    MAX_RATE : LREAL := {st_real(f['max_rate_c_per_min'])};
    MAX_AGE : LREAL := {st_real(f['max_sensor_age_s'])};
    POLICY_RAMP : BOOL := {'TRUE' if ramp else 'FALSE'};
    RAMP_TIME : LREAL := {st_real(f['ramp_to_zero_min'] * 60.0)};
END_VAR
VAR
    aPrevious : ARRAY[1..{n_s}] OF LREAL;
    aSince : ARRAY[1..{n_s}] OF LREAL;
    aHavePrevious : ARRAY[1..{n_s}] OF BOOL;
    bPlausible : BOOL;
    fGoodOffset : LREAL := 0.0;
    fGoodCoefficient : LREAL := 0.0;
    fFaultTime : LREAL := 0.0;
    fScale : LREAL;
    aInputNow : ARRAY[1..{n_i}] OF LREAL;
    aInputRef : ARRAY[1..{n_i}] OF LREAL;
    aChange : ARRAY[1..{n_r}] OF LREAL;
    fInput : LREAL;
    fZ : LREAL;
    fDistance : LREAL;
    fSum : LREAL;
    fValue : LREAL;
    nPass : INT;
    nCentre : INT;
    fB : LREAL;
    fK : LREAL;
    i : INT;
    j : INT;
    r : INT;
END_VAR

nReasons := 0;
FOR i := 1 TO N_SENSORS DO
    IF aHavePrevious[i] THEN
        aSince[i] := aSince[i] + fDeltaTime;
    END_IF
    bPlausible := FALSE;
    IF (NOT aValid[i]) OR (aAge[i] > MAX_AGE) THEN
        nReasons := nReasons OR 1;
    ELSIF (aTemperature[i] < PLAUSIBLE_MIN) OR (aTemperature[i] > PLAUSIBLE_MAX) THEN
        nReasons := nReasons OR 2;
    ELSE
        bPlausible := TRUE;
        IF aHavePrevious[i] AND (aSince[i] > 0.0) THEN
            IF ABS(aTemperature[i] - aPrevious[i]) / aSince[i] * 60.0 > MAX_RATE THEN
                nReasons := nReasons OR 4;
            END_IF
        END_IF
    END_IF
    IF (aReference[i] < PLAUSIBLE_MIN) OR (aReference[i] > PLAUSIBLE_MAX) THEN
        nReasons := nReasons OR 2;
    END_IF
    (* The rate is measured against the last plausible reading, so one wild sample does not fail the next. *)
    IF bPlausible THEN
        aPrevious[i] := aTemperature[i];
        aSince[i] := 0.0;
        aHavePrevious[i] := TRUE;
    END_IF
END_FOR

FOR j := 1 TO N_INPUTS DO
    aInputNow[j] := aTemperature[INPUT_SENSOR[j]];
    aInputRef[j] := aReference[INPUT_SENSOR[j]];
    IF INPUT_RELATIVE[j] THEN
        aInputNow[j] := aInputNow[j] - aReference[INPUT_SENSOR[j]];
        aInputRef[j] := 0.0;
    END_IF
    IF (nReasons = 0) AND ((aInputNow[j] < INPUT_MIN[j] - RANGE_MARGIN) OR (aInputNow[j] > INPUT_MAX[j] + RANGE_MARGIN)) THEN
        nReasons := nReasons OR 8;
    END_IF
END_FOR

IF nReasons = 0 THEN
{changes}    fB := 0.0;
    fK := 0.0;
    FOR r := 1 TO N_REGRESSIONS DO
        fB := fB + LINE_B[r] * aChange[r];
        fK := fK + LINE_K[r] * aChange[r];
    END_FOR
    fGoodOffset := -fB * TENTHS_UM_PER_UM;
    fGoodCoefficient := -fK;
    fScale := 1.0;
    bFallback := FALSE;
ELSE
    IF bFallback THEN
        fFaultTime := fFaultTime + fDeltaTime;
    ELSE
        fFaultTime := 0.0;
    END_IF
    bFallback := TRUE;
    fScale := 1.0;
    IF POLICY_RAMP THEN
        IF RAMP_TIME > 0.0 THEN
            fScale := MAX(0.0, 1.0 - fFaultTime / RAMP_TIME);
        ELSE
            fScale := 0.0;
        END_IF
    END_IF
END_IF

fPosition0 := P0_MM * TENTHS_UM_PER_MM;
fOffset0 := fGoodOffset * fScale;
fCoefficient := fGoodCoefficient * fScale;
nPosition0 := LREAL_TO_DINT(fPosition0);
nOffset0 := LREAL_TO_DINT(fOffset0);
nCoefficient := LREAL_TO_DINT(fCoefficient);
END_FUNCTION_BLOCK
"""
