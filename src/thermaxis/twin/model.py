"""Free parameters, the heat inputs and the noise-free positioning error of the twin.

The positioning error read by the interferometer at target x (mm) and time t is

    E(x, t) = g(x) + k_th(t) * (x - X_FIXED_MM) / 1000 + d(t)

* g(x): geometric error, a slope ``geometric_slope_um_per_m`` and a small periodic
  pitch error (amplitude ``PITCH_AMPLITUDE_UM``, period ``PITCH_PERIOD_MM``);
* k_th(t) = a_s (T_screw_core - 20) - a_r (T_bed_inner - 20): the screw's expansion
  (the hidden core temperature, effective gain a_s; the preloaded screw absorbs part of
  the free expansion 11.5 um/m/K) minus the interferometer's material normalisation to
  20 degC with its material sensor on the bed (gain a_r).  Both are about the fixed
  bearing at X_FIXED_MM, so the expansion also moves the first target a little;
* d(t) = -(c_bs T_bearing_seat + c_bi T_bed_inner + c_bo T_bed_outer): drift of the
  table against the laser optics, independent of position (the fixed bearing moving
  with its seat, bed bending and the bed carrying the optics).

The interferometer is zeroed once, at the first target just before M1, so a reading is
E(x, t) - E(185, t_zero) plus reversal error and noise (:mod:`thermaxis.twin.observe`).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import conditions as cond
from .network import NODES, Discretised, discretise, simulate

__all__ = [
    "PARAMS_PATH",
    "GLOBAL_PARAMETERS",
    "INITIAL_PARAMETERS",
    "X_FIXED_MM",
    "PITCH_AMPLITUDE_UM",
    "PITCH_PERIOD_MM",
    "PITCH_PHASE_RAD",
    "TwinParams",
    "load_params",
    "save_params",
    "heat_inputs",
    "RunState",
    "simulate_run",
    "positioning_error",
]

PARAMS_PATH = Path(__file__).resolve().parent.parent / "twin_params.json"

#: Global free parameters: name -> (lower bound, upper bound, meaning).
GLOBAL_PARAMETERS: dict[str, tuple[float, float, str]] = {
    "nut_heat_W_per_m_min": (0.0, 5.0, "friction heat of the ball-screw nut per m/min of feed"),
    "bearing_heat_W_per_m_min": (0.0, 5.0, "friction heat of the fixed-end bearings per m/min"),
    "slider_heat_W_per_m_min": (0.0, 5.0, "friction heat of the four guide carriages per m/min"),
    "motor_heat_W_per_m_min": (0.0, 10.0, "servo motor losses per m/min (reversals, viscous)"),
    "motor_standstill_W": (0.0, 40.0, "motor and brake losses with the drive enabled, at standstill"),
    "screw_gain_um_per_m_K": (0.0, 11.5, "effective expansion of the preloaded screw"),
    "reference_gain_um_per_m_K": (0.0, 11.5, "interferometer material normalisation (bed sensor)"),
    "geometric_slope_um_per_m": (-300.0, 300.0, "slope of the geometric error at 20 degC"),
    "drift_bearing_seat_um_per_K": (-20.0, 20.0, "table drift per K of the bearing seat"),
    "drift_bed_inner_um_per_K": (-20.0, 20.0, "table drift per K of the bed core"),
    "drift_bed_outer_um_per_K": (-20.0, 20.0, "table drift per K of the bed's outer walls"),
}

#: Per-run initial temperatures, K above the workshop air at the log start.
INITIAL_PARAMETERS: dict[str, tuple[float, float, str]] = {
    "screw_offset_K": (-3.0, 3.0, "ball screw, nut and sleeve"),
    "drive_offset_K": (-3.0, 3.0, "bearing seat, motor and sliders"),
    "bed_inner_offset_K": (-3.0, 3.0, "the bed's core"),
    "bed_outer_offset_K": (-3.0, 3.0, "the bed's outer walls"),
}
_INITIAL_GROUPS: dict[str, tuple[str, ...]] = {
    "screw_offset_K": ("screw_core", "nut", "sleeve"),
    "drive_offset_K": ("bearing_seat", "motor", "sliders"),
    "bed_inner_offset_K": ("bed_inner",),
    "bed_outer_offset_K": ("bed_outer",),
}

#: Machine coordinate of the screw's fixed bearing (motor end), mm.
X_FIXED_MM = 40.0
#: Periodic pitch error of the screw: amplitude (um), period (mm) and phase at X = 0.
PITCH_AMPLITUDE_UM = 0.25
PITCH_PERIOD_MM = 130.0
PITCH_PHASE_RAD = 0.6
#: Temperature at which the geometric error is defined (and the laser normalises to).
REFERENCE_C = 20.0
STEP_S = 10.0


@dataclass(frozen=True)
class TwinParams:
    """The calibrated parameters: global ones and per-run initial offsets."""

    values: dict[str, float]
    initial: dict[str, dict[str, float]]

    def vector(self, runs: tuple[str, ...]) -> np.ndarray:
        """Flatten in the order of :func:`parameter_names`."""
        return np.array([self.values[n] for n in GLOBAL_PARAMETERS] + [
            self.initial[r][n] for r in runs for n in INITIAL_PARAMETERS
        ])

    @classmethod
    def from_vector(cls, x: np.ndarray, runs: tuple[str, ...]) -> "TwinParams":
        n = len(GLOBAL_PARAMETERS)
        values = {name: float(v) for name, v in zip(GLOBAL_PARAMETERS, x[:n])}
        m = len(INITIAL_PARAMETERS)
        initial = {
            run: {name: float(v) for name, v in zip(INITIAL_PARAMETERS, x[n + i * m : n + (i + 1) * m])}
            for i, run in enumerate(runs)
        }
        return cls(values=values, initial=initial)


def parameter_bounds(runs: tuple[str, ...]) -> tuple[np.ndarray, np.ndarray]:
    lo = [b[0] for b in GLOBAL_PARAMETERS.values()] + [b[0] for _ in runs for b in INITIAL_PARAMETERS.values()]
    hi = [b[1] for b in GLOBAL_PARAMETERS.values()] + [b[1] for _ in runs for b in INITIAL_PARAMETERS.values()]
    return np.array(lo), np.array(hi)


def load_params(path: Path | str = PARAMS_PATH) -> TwinParams:
    """Read the committed fitted parameters."""
    with open(path, encoding="utf-8") as fh:
        raw = json.load(fh)
    values = {name: float(raw["global"][name]) for name in GLOBAL_PARAMETERS}
    initial = {
        run: {name: float(v[name]) for name in INITIAL_PARAMETERS} for run, v in raw["initial_offset_K"].items()
    }
    return TwinParams(values=values, initial=initial)


def save_params(params: TwinParams, path: Path | str, fit_summary: dict) -> None:
    """Write the parameters as stable, human-readable JSON (sorted, fixed precision)."""
    raw = {
        "about": "Fitted free parameters of thermaxis.twin (python -m thermaxis.twin calibrate).",
        "global": {name: round(params.values[name], 6) for name in GLOBAL_PARAMETERS},
        "initial_offset_K": {
            run: {name: round(v[name], 6) for name in INITIAL_PARAMETERS} for run, v in sorted(params.initial.items())
        },
        "fit": fit_summary,
    }
    Path(path).write_text(json.dumps(raw, indent=2) + "\n", encoding="utf-8")


def heat_inputs(values: dict[str, float], feed_mm_min: float, motion: np.ndarray, servo: np.ndarray) -> np.ndarray:
    """Heat per node (W) on each step; friction heat grows linearly with the feed."""
    v = feed_mm_min / 1000.0  # m/min
    q = np.zeros((motion.size, len(NODES)))
    idx = {n: i for i, n in enumerate(NODES)}
    q[:, idx["nut"]] = values["nut_heat_W_per_m_min"] * v * motion
    q[:, idx["bearing_seat"]] = values["bearing_heat_W_per_m_min"] * v * motion
    q[:, idx["sliders"]] = values["slider_heat_W_per_m_min"] * v * motion
    q[:, idx["motor"]] = values["motor_heat_W_per_m_min"] * v * motion + values["motor_standstill_W"] * servo
    return q


@dataclass(frozen=True)
class RunState:
    """Simulated hidden temperatures of one run on its grid (s from M1)."""

    condition: cond.Condition
    timeline: cond.Timeline
    grid_s: np.ndarray
    nodes: np.ndarray  # (n_grid, n_nodes)
    ambient: np.ndarray  # (n_grid,)

    def node(self, name: str, t_s) -> np.ndarray:
        return np.interp(t_s, self.grid_s, self.nodes[:, NODES.index(name)])


_DISC_CACHE: dict[float, Discretised] = {}


def _disc(step_s: float) -> Discretised:
    if step_s not in _DISC_CACHE:
        _DISC_CACHE[step_s] = discretise(step_s)
    return _DISC_CACHE[step_s]


def simulate_run(condition: cond.Condition, params: TwinParams, step_s: float = STEP_S) -> RunState:
    """Integrate the network over the run's log window."""
    tl = cond.timeline(condition, step_s)
    grid = tl.grid_s
    mid = 0.5 * (grid[:-1] + grid[1:])
    ambient_mid = cond.ambient_at(condition, mid)
    q = heat_inputs(
        params.values,
        condition.feed_mm_min,
        cond.motion_fraction(tl, step_s),
        cond.servo_fraction(tl, step_s),
    )
    inputs = np.column_stack([ambient_mid, q])
    a0 = float(cond.ambient_at(condition, grid[:1])[0])
    initial = np.full(len(NODES), a0)
    offsets = params.initial[condition.run]
    for name, members in _INITIAL_GROUPS.items():
        for node in members:
            initial[NODES.index(node)] += offsets[name]
    nodes = simulate(_disc(step_s), initial, inputs)
    return RunState(
        condition=condition,
        timeline=tl,
        grid_s=grid,
        nodes=nodes,
        ambient=cond.ambient_at(condition, grid),
    )


def thermal_slope(values: dict[str, float], state: RunState, t_s) -> np.ndarray:
    """k_th(t), um/m: screw expansion minus the laser's material normalisation."""
    return values["screw_gain_um_per_m_K"] * (state.node("screw_core", t_s) - REFERENCE_C) - values[
        "reference_gain_um_per_m_K"
    ] * (state.node("bed_inner", t_s) - REFERENCE_C)


def drift(values: dict[str, float], state: RunState, t_s) -> np.ndarray:
    """d(t), um: position-independent drift of the table against the optics."""
    return -(
        values["drift_bearing_seat_um_per_K"] * state.node("bearing_seat", t_s)
        + values["drift_bed_inner_um_per_K"] * state.node("bed_inner", t_s)
        + values["drift_bed_outer_um_per_K"] * state.node("bed_outer", t_s)
    )


def geometric_error(values: dict[str, float], x_mm) -> np.ndarray:
    x = np.asarray(x_mm, dtype=float)
    return values["geometric_slope_um_per_m"] * (x - X_FIXED_MM) / 1000.0 + PITCH_AMPLITUDE_UM * np.sin(
        2 * np.pi * x / PITCH_PERIOD_MM + PITCH_PHASE_RAD
    )


def positioning_error(values: dict[str, float], state: RunState, x_mm, t_s) -> np.ndarray:
    """E(x, t), um, before zeroing (broadcasts x and t)."""
    x = np.asarray(x_mm, dtype=float)
    return (
        geometric_error(values, x)
        + thermal_slope(values, state, t_s) * (x - X_FIXED_MM) / 1000.0
        + drift(values, state, t_s)
    )
