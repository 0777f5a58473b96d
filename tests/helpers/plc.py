"""The generated Structured Text block read back: blark's parse tree, its constants, and the
block's arithmetic on them in plain numpy (tests/unit/test_structured_text.py)."""

import numpy as np
from blark.parse import parse_source_code


def value_of(node):
    """An initial value from blark's tree: literals, unary minus, (nested) array initialisers."""
    kind = type(node).__name__
    if kind == "Integer":
        return int(str(node.value))
    if kind == "Real":
        return float(str(node.value))
    if kind == "Boolean":
        return str(node.value).upper() == "TRUE"
    if kind == "UnaryOperation" and str(node.op) == "-":
        return -value_of(node.expr)
    if kind == "ArrayInitialization":
        out = []
        for element in node.elements:
            value = value_of(element.element)
            count = 1 if element.count is None else int(str(element.count))
            out += (value if isinstance(value, list) else [value]) * count
        return out
    raise AssertionError(f"unexpected constant expression {node!r}")


def parsed_constants(source: str) -> dict:
    result = parse_source_code(source)
    assert result.exception is None, result.exception
    (block,) = result.transform().items
    assert str(block.name) == "ThermalCompensation"
    constants = {}
    for declarations in block.declarations:
        if "constant" in str(getattr(declarations, "attrs", "")).lower():
            for item in declarations.items:
                for variable in item.variables:
                    constants[str(variable)] = value_of(item.init.value)
    return constants


def st_twincat(c: dict, temperatures: np.ndarray, reference: np.ndarray, lags=None) -> dict:
    """The block's arithmetic on its own constants: P-AXIS-00272/273/274.

    ``lags``: the lag filters' outputs now and at homing, for a block with lag inputs."""
    sensor = np.asarray(c["INPUT_SENSOR"]) - 1
    relative = np.asarray(c["INPUT_RELATIVE"])
    now = np.where(relative, temperatures[sensor] - reference[sensor], temperatures[sensor])
    ref = np.where(relative, 0.0, reference[sensor])
    if lags is not None:
        y, y_homing = lags
        lag = np.asarray(c["INPUT_LAG"]) - 1
        filtered = lag >= 0
        now = np.where(filtered, np.where(relative, y[lag] - y_homing[lag], y[lag]), now)
        ref = np.where(filtered, np.where(relative, 0.0, y_homing[lag]), ref)
    if "COEFF" in c:
        change = np.asarray(c["COEFF"]).reshape(c["N_REGRESSIONS"], c["N_INPUTS"]) @ (now - ref)
    else:
        change = np.array(
            [rbf(c, r, now) - rbf(c, r, ref) for r in range(1, c["N_REGRESSIONS"] + 1)]
        )
    b = np.dot(c["LINE_B"], change)
    k = np.dot(c["LINE_K"], change)
    return {
        "P-AXIS-00272": c["P0_MM"] * c["TENTHS_UM_PER_MM"],
        "P-AXIS-00273": -b * c["TENTHS_UM_PER_UM"],
        "P-AXIS-00274": -k,
    }


def rbf(c: dict, r: int, inputs: np.ndarray) -> float:
    """Regression r of a kernel block:
    (sum_i w_i exp(-gamma |z - z_i|^2) + offset) * scale + mean."""
    name = f"R{r}_"
    chosen = np.asarray(c[name + "INPUTS"]) - 1
    z = (inputs[chosen] - np.asarray(c[name + "MEAN"])) / np.asarray(c[name + "SCALE"])
    centres = np.asarray(c[name + "CENTRES"]).reshape(-1, chosen.size)
    kernel = np.exp(-c[name + "GAMMA"] * ((z - centres) ** 2).sum(axis=1))
    return (kernel @ np.asarray(c[name + "WEIGHTS"]) + c[name + "OFFSET"]) * c[
        name + "TARGET_SCALE"
    ] + c[name + "TARGET_MEAN"]
