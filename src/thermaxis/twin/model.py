"""Free parameters, the heat inputs, the sensor mountings and the noise-free positioning error.

Heat inputs (W) follow the feed v (m/min) while the axis reciprocates: nut, bearing
and carriage friction and motor losses are each a coefficient times v; the motor also
dissipates standstill losses from servo-on (5 min before M1).

The positioning error at target x (mm) and time t is

    E(x, t) = g(x) + k_th(t) * (x - X_FIXED_MM) / 1000 + d(t)

* g(x): geometric error, a slope ``geometric_slope_um_per_m`` and a small periodic
  pitch error (amplitude ``PITCH_AMPLITUDE_UM``, period ``PITCH_PERIOD_MM``);
* k_th(t) = a_s (T_screw_core - 20) - a_r (T_bed_inner - 20), um/m: the screw's
  expansion driven by its HIDDEN core temperature (gain a_s <= 11.5 um/m/K of free
  steel) minus the interferometer's material normalisation to 20 degC with its
  material sensor on the bed (gain a_r).  Both act about the fixed bearing at
  X_FIXED_MM, so the expansion also moves the first target a little.  Because
  a_s != a_r, k depends on absolute temperatures, as the paper's Eq. 9 assumes;
* d(t) = -sum_n c_n T_n(t) over bearing seat, bed core, bed walls, carriages and nut,
  um: the drift of the table against the laser optics, independent of position (the
  fixed bearing moving with its seat, the bed carrying the optics and bending, the
  table and nut housing growing between nut and reflector).

The interferometer is zeroed once, at the first target just before M1, so a reading is
E(x, t) - E(185, t_zero) plus reversal error and noise (:mod:`thermaxis.twin.observe`).

The sensors the paper's fitted models use (Eq. 8: T1, T11, T12; Eq. 9: T1, T6, T12 and
T2, T7, T11) have calibrated mountings: what a PT100 clamped to a part reads is a mix
of that part and its neighbours (and the air), so each of them mixes a few candidate
surfaces (:data:`MOUNTING_SURFACES`) with fitted weights, plus a fitted calibration
offset within the PT100 class-B tolerance at 30 degC.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import conditions as cond
from .network import NODES, discretise, simulate

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
    "FreeParameter",
    "MOUNTING_SURFACES",
    "MOUNTING_DESIGN",
    "mounting",
    "CAPACITY_NODES",
    "DRIFT_NODES",
    "REFERENCE_NODE",
    "INITIAL_GROUPS",
    "parameter_bounds",
    "parameter_names",
    "capacity_scale",
    "load_fit",
    "conductance_scale",
    "CALIBRATED_LINKS",
    "NETWORK_PARAMETERS",
    "heat_inputs",
    "RunState",
    "initial_state",
    "simulate_timeline",
    "simulate_run",
    "thermal_slope",
    "drift",
    "geometric_error",
    "positioning_error",
]

PARAMS_PATH = Path(__file__).resolve().parent.parent / "twin_params.json"


@dataclass(frozen=True)
class FreeParameter:
    """A calibrated quantity: bounds, a weak prior (centre, width) and its meaning."""

    lower: float
    upper: float
    prior: float
    prior_width: float  # inf = no prior
    meaning: str


_NO_PRIOR = float("inf")

#: Free parameters of the network and the error model.  The priors only keep the fit
#: physical where the published targets do not pin a parameter down; they are wide
#: compared with the fitted departures.
_PHYSICAL_PARAMETERS: dict[str, FreeParameter] = {
    "nut_heat_W_per_m_min": FreeParameter(
        0.0, 6.0, 1.5, 1.5, "friction heat of the ball-screw nut per m/min of feed"
    ),
    "bearing_heat_W_per_m_min": FreeParameter(
        0.0, 6.0, 1.0, 1.5, "friction heat of the fixed-end bearings per m/min"
    ),
    "slider_heat_W_per_m_min": FreeParameter(
        0.0, 6.0, 1.0, 1.5, "friction heat of the four guide carriages per m/min"
    ),
    "motor_heat_W_per_m_min": FreeParameter(
        0.0, 12.0, 2.0, 3.0, "servo motor losses per m/min (reversals, viscous)"
    ),
    "motor_standstill_W": FreeParameter(
        0.0, 40.0, 10.0, 10.0, "motor losses with the drive enabled, at standstill"
    ),
    "screw_gain_um_per_m_K": FreeParameter(
        3.0, 11.5, 9.0, 3.0, "effective expansion of the preloaded screw"
    ),
    "reference_gain_um_per_m_K": FreeParameter(
        3.0, 12.0, 10.0, 3.0, "interferometer material normalisation (bed sensor)"
    ),
    "geometric_slope_um_per_m": FreeParameter(
        -300.0, 300.0, 0.0, _NO_PRIOR, "slope of the geometric error at 20 degC"
    ),
    "drift_bearing_seat_um_per_K": FreeParameter(
        -3.0, 3.0, 0.0, 1.5, "table drift per K of the bearing seat"
    ),
    "drift_bed_inner_um_per_K": FreeParameter(
        -12.0, 12.0, 0.0, 6.0, "table drift per K of the bed core"
    ),
    "drift_bed_outer_um_per_K": FreeParameter(
        -12.0, 12.0, 0.0, 6.0, "table drift per K of the bed's outer walls"
    ),
    "drift_sliders_um_per_K": FreeParameter(
        -3.5, 3.5, 0.0, 1.5, "table drift per K of the carriages/table"
    ),
    "drift_nut_um_per_K": FreeParameter(
        -1.5, 1.5, 0.0, 0.75, "table drift per K of the nut housing"
    ),
    "log_capacity_screw_core": FreeParameter(
        -2.3, 2.3, 0.0, 1.0, "ln factor on the screw core's heat capacity"
    ),
    "log_capacity_bearing_seat": FreeParameter(
        -2.3, 2.3, 0.0, 1.0, "ln factor on the bearing seat's heat capacity"
    ),
    "log_capacity_motor": FreeParameter(
        -2.3, 2.3, 0.0, 1.0, "ln factor on the motor's heat capacity"
    ),
    "log_capacity_sliders": FreeParameter(
        -2.3, 2.3, 0.0, 1.0, "ln factor on the carriages' heat capacity"
    ),
    "log_capacity_nut": FreeParameter(-2.3, 2.3, 0.0, 1.0, "ln factor on the nut's heat capacity"),
    "log_capacity_bed_outer": FreeParameter(
        -2.3, 2.3, 0.0, 1.0, "ln factor on the bed walls' heat capacity"
    ),
}

#: Thermal links whose conductance is calibrated: ``log_conductance_<name>`` multiplies the
#: documented estimate of :data:`thermaxis.twin.network.CONDUCTANCE_W_PER_K` by e^value.
#: BOUND: a factor of 3 either way (+-1.1), the spread of contact and film coefficients
#: for bolted joints, ball contacts and natural convection behind those estimates.
CALIBRATED_LINKS: dict[str, tuple[str, str]] = {
    "screw_nut": ("screw_core", "nut"),
    "screw_sleeve": ("screw_core", "sleeve"),
    "nut_sliders": ("nut", "sliders"),
    "nut_air": ("nut", "ambient"),
    "bearing_motor": ("bearing_seat", "motor"),
    "bearing_bed": ("bearing_seat", "bed_inner"),
    "sliders_bed": ("sliders", "bed_inner"),
    "motor_air": ("motor", "ambient"),
    "sleeve_air": ("sleeve", "ambient"),
    "bed_walls_air": ("bed_outer", "ambient"),
}
CONDUCTANCE_LIMIT = 1.1
_PHYSICAL_PARAMETERS.update(
    {
        f"log_conductance_{name}": FreeParameter(
            -CONDUCTANCE_LIMIT,
            CONDUCTANCE_LIMIT,
            0.0,
            0.5,
            f"ln factor on the conductance {a} - {b}",
        )
        for name, (a, b) in CALIBRATED_LINKS.items()
    }
)

#: What each PT100 of Table 2 may read: the part it is clamped to first, then the parts
#: in contact with it and the air (the BOUND of its mounting: no sensor reads a part it
#: does not touch).  The sleeve's support rides on the screw and its ends sit on the
#: bearing seat and the bed; the carriages run on the bed's guideways under the nut's
#: table; the bearing seat holds the screw's fixed end and carries the motor flange; the
#: bed's inner and outer faces are one casting; the air sensor hangs beside the bed's wall.
MOUNTING_SURFACES: dict[str, tuple[str, ...]] = {
    "T1": ("sleeve", "bearing_seat", "screw_core", "bed_inner", "ambient"),
    "T2": ("sleeve", "bed_inner", "bed_outer", "screw_core", "ambient"),
    "T3": ("sleeve", "nut", "screw_core", "sliders", "ambient"),
    "T4": ("sliders", "nut", "bed_inner", "ambient"),
    "T5": ("sliders", "bed_inner", "nut", "ambient"),
    "T6": ("bearing_seat", "motor", "bed_inner", "screw_core", "ambient"),
    "T7": ("motor", "bearing_seat", "ambient"),
    "T8": ("bed_inner", "bed_outer", "sliders", "ambient"),
    "T9": ("bed_outer", "bed_inner", "ambient"),
    # The air sensor reads the air only: Table 1's ambient ranges are read from it.
    "T10": ("ambient",),
    "T11": ("nut", "sliders", "screw_core", "ambient"),
    "T12": ("motor", "ambient"),
}
#: The design estimate of every mounting (weights, offset degC): the priors' centres.
MOUNTING_DESIGN: dict[str, tuple[dict[str, float], float]] = {
    "T1": ({"sleeve": 0.75, "bearing_seat": 0.15, "ambient": 0.10}, 0.06),
    "T2": ({"sleeve": 0.80, "ambient": 0.20}, -0.04),
    "T3": ({"sleeve": 0.85, "nut": 0.05, "ambient": 0.10}, 0.09),
    "T4": ({"sliders": 0.85, "nut": 0.10, "ambient": 0.05}, -0.07),
    "T5": ({"sliders": 0.85, "bed_inner": 0.10, "ambient": 0.05}, 0.03),
    "T6": ({"bearing_seat": 0.90, "motor": 0.05, "ambient": 0.05}, 0.05),
    "T7": ({"motor": 0.60, "ambient": 0.40}, -0.10),
    "T8": ({"bed_inner": 0.95, "ambient": 0.05}, 0.02),
    "T9": ({"bed_outer": 0.85, "ambient": 0.15}, -0.06),
    "T10": ({"ambient": 1.0}, 0.08),
    "T11": ({"nut": 0.90, "sliders": 0.10}, 0.15),
    "T12": ({"motor": 1.0}, -0.30),
}
#: PT100 class B at 30 degC: +-(0.3 + 0.005 * 30) degC.
OFFSET_LIMIT_C = 0.45
#: Prior centre of a neighbour the design does not mix in: its log weight relative to
#: the design's largest neighbour (e^-4, about 2 %).
_ABSENT_LOG_WEIGHT = -4.0


def _mounting_parameters() -> dict[str, FreeParameter]:
    """Per calibrated sensor: ``mount_<sensor>_share``, ``mount_<sensor>_<neighbour>``, ``offset_<sensor>_C``.

    The share of the part a sensor is clamped to stays at least one half (a sensor
    reads mostly its own part); the rest is split among the neighbours by the softmax
    of their log weights (none when there is a single neighbour).
    """
    out = {}
    for sensor, (primary, *neighbours) in MOUNTING_SURFACES.items():
        design, offset = MOUNTING_DESIGN[sensor]
        if neighbours:
            out[f"mount_{sensor}_share"] = FreeParameter(
                0.5, 1.0, design[primary], 0.25, f"{sensor}: share of {primary} in what it reads"
            )
        if len(neighbours) > 1:
            largest = max(design.get(n, 0.0) for n in neighbours)
            for n in neighbours:
                centre = float(np.log(design[n] / largest)) if n in design else _ABSENT_LOG_WEIGHT
                out[f"mount_{sensor}_{n}"] = FreeParameter(
                    -8.0, 8.0, centre, 3.0, f"{sensor}: log weight of {n} among the neighbours"
                )
        out[f"offset_{sensor}_C"] = FreeParameter(
            -OFFSET_LIMIT_C, OFFSET_LIMIT_C, offset, 0.3, f"{sensor}: calibration offset (degC)"
        )
    return out


#: Global free parameters: the physical ones, then the sensor mountings.
GLOBAL_PARAMETERS: dict[str, FreeParameter] = {**_PHYSICAL_PARAMETERS, **_mounting_parameters()}


def mounting(values: dict[str, float], sensor: str) -> tuple[dict[str, float], float]:
    """Surface weights (summing to 1) and calibration offset of a calibrated sensor."""
    primary, *neighbours = MOUNTING_SURFACES[sensor]
    if not neighbours:
        return {primary: 1.0}, values[f"offset_{sensor}_C"]
    share = values[f"mount_{sensor}_share"]
    if len(neighbours) == 1:
        split = np.array([1.0 - share])
    else:
        log_weight = np.array([values[f"mount_{sensor}_{n}"] for n in neighbours])
        split = np.exp(log_weight - log_weight.max())
        split *= (1.0 - share) / split.sum()
    return {
        primary: share,
        **dict(zip(neighbours, (float(w) for w in split), strict=False)),
    }, values[f"offset_{sensor}_C"]


#: Nodes whose capacity is calibrated (``log_capacity_<node>``).
CAPACITY_NODES: tuple[str, ...] = tuple(
    name.removeprefix("log_capacity_")
    for name in GLOBAL_PARAMETERS
    if name.startswith("log_capacity_")
)
#: Nodes that carry the position-independent drift (``drift_<node>_um_per_K``).
DRIFT_NODES: tuple[str, ...] = ("bearing_seat", "bed_inner", "bed_outer", "sliders", "nut")
#: The node under the interferometer's material sensor (normalisation reference).
REFERENCE_NODE = "bed_inner"

#: Per-run initial temperatures, K above the workshop air at the log start, one per node:
#: a machine is rarely at equilibrium when a test starts (the heavy bed still holds the
#: last days' air, the motor and nut their last use).  BOUND: +-4 K, the swing of the
#: workshop air between the four test days (Table 1: 27.4 ... 31.6 degC).
INITIAL_OFFSET_LIMIT_K = 4.0
INITIAL_PARAMETERS: dict[str, FreeParameter] = {
    f"{node}_offset_K": FreeParameter(
        -INITIAL_OFFSET_LIMIT_K, INITIAL_OFFSET_LIMIT_K, 0.0, 1.5, f"{node.replace('_', ' ')}"
    )
    for node in NODES
}
INITIAL_GROUPS: dict[str, tuple[str, ...]] = {f"{node}_offset_K": (node,) for node in NODES}

#: Machine coordinate of the screw's fixed bearing (motor end), mm.
X_FIXED_MM = 40.0
#: Periodic pitch error of the screw: amplitude (um), period (mm) and phase at X = 0.
#: The phase is chosen so that the cold-state intercept (M1) is about 0, as in Table 5.
PITCH_AMPLITUDE_UM = 0.25
PITCH_PERIOD_MM = 130.0
PITCH_PHASE_RAD = 1.4
#: Temperature at which the geometric error is defined (and the laser normalises to).
REFERENCE_C = 20.0


@dataclass(frozen=True)
class TwinParams:
    """The calibrated parameters: global ones and per-run initial offsets."""

    values: dict[str, float]
    initial: dict[str, dict[str, float]]

    def vector(self, runs: tuple[str, ...]) -> np.ndarray:
        """Flatten: GLOBAL_PARAMETERS, then INITIAL_PARAMETERS run by run."""
        return np.array(
            [self.values[n] for n in GLOBAL_PARAMETERS]
            + [self.initial[r][n] for r in runs for n in INITIAL_PARAMETERS]
        )

    @classmethod
    def from_vector(cls, x: np.ndarray, runs: tuple[str, ...]) -> TwinParams:
        n = len(GLOBAL_PARAMETERS)
        values = {name: float(v) for name, v in zip(GLOBAL_PARAMETERS, x[:n], strict=False)}
        m = len(INITIAL_PARAMETERS)
        initial = {
            run: {
                name: float(v)
                for name, v in zip(INITIAL_PARAMETERS, x[n + i * m : n + (i + 1) * m], strict=False)
            }
            for i, run in enumerate(runs)
        }
        return cls(values=values, initial=initial)


def parameter_bounds(runs: tuple[str, ...]) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper bounds in the order of :meth:`TwinParams.vector`."""
    free = list(GLOBAL_PARAMETERS.values()) + [p for _ in runs for p in INITIAL_PARAMETERS.values()]
    return np.array([p.lower for p in free]), np.array([p.upper for p in free])


def parameter_names(runs: tuple[str, ...]) -> list[str]:
    """Names in the order of :meth:`TwinParams.vector` (a run's offsets as ``run:name``)."""
    return list(GLOBAL_PARAMETERS) + [
        f"{run}:{name}" for run in runs for name in INITIAL_PARAMETERS
    ]


def capacity_scale(values: dict[str, float]) -> dict[str, float]:
    """Multiplicative capacity factors from the ``log_capacity_<node>`` parameters."""
    return {node: float(np.exp(values[f"log_capacity_{node}"])) for node in CAPACITY_NODES}


def conductance_scale(values: dict[str, float]) -> dict[tuple[str, str], float]:
    """Multiplicative conductance factors from the ``log_conductance_<link>`` parameters."""
    return {
        link: float(np.exp(values[f"log_conductance_{name}"]))
        for name, link in CALIBRATED_LINKS.items()
    }


#: The parameters that change the network itself: a new value needs a new integration.
NETWORK_PARAMETERS: tuple[str, ...] = tuple(
    name for name in GLOBAL_PARAMETERS if name.startswith(("log_capacity_", "log_conductance_"))
)


def load_params(path: Path | str = PARAMS_PATH) -> TwinParams:
    """Read the committed fitted parameters."""
    with open(path, encoding="utf-8") as fh:
        raw = json.load(fh)
    try:
        values = {name: float(raw["global"][name]) for name in GLOBAL_PARAMETERS}
        initial = {
            run: {name: float(v[name]) for name in INITIAL_PARAMETERS}
            for run, v in raw["initial_offset_K"].items()
        }
    except KeyError as exc:
        raise ValueError(
            f"{path}: missing {exc.args[0]!r} (expected 'global' with every twin parameter and "
            "'initial_offset_K' per run; rerun `python -m thermaxis.twin calibrate`)"
        ) from None
    missing = [c.run for c in cond.CONDITIONS if c.run not in initial]
    if missing:
        raise ValueError(
            f"{path}: no initial offsets for run(s) {missing}; rerun `python -m thermaxis.twin calibrate`"
        )
    return TwinParams(values=values, initial=initial)


#: Decimals of the written parameters (twin_params.json).
PARAMS_DECIMALS = 6


def save_params(params: TwinParams, path: Path | str, fit_summary: dict) -> None:
    """Write the parameters as stable, human-readable JSON (sorted, fixed precision)."""
    raw = {
        "about": "Fitted free parameters of thermaxis.twin (python -m thermaxis.twin calibrate).",
        "global": {name: round(params.values[name], PARAMS_DECIMALS) for name in GLOBAL_PARAMETERS},
        "initial_offset_K": {
            run: {name: round(v[name], PARAMS_DECIMALS) for name in INITIAL_PARAMETERS}
            for run, v in sorted(params.initial.items())
        },
        "fit": fit_summary,
    }
    Path(path).write_text(json.dumps(raw, indent=2) + "\n", encoding="utf-8")


def load_fit(path: Path | str = PARAMS_PATH) -> dict:
    """The calibration's own summary stored beside the parameters (``fit``)."""
    with open(path, encoding="utf-8") as fh:
        return json.load(fh).get("fit", {})


def heat_inputs(
    values: dict[str, float], feed_mm_min: float, motion: np.ndarray, servo: np.ndarray
) -> np.ndarray:
    """Heat per node (W) on each step; friction heat grows linearly with the feed."""
    v = feed_mm_min / 1000.0  # m/min
    q = np.zeros((motion.size, len(NODES)))
    idx = {n: i for i, n in enumerate(NODES)}
    q[:, idx["nut"]] = values["nut_heat_W_per_m_min"] * v * motion
    q[:, idx["bearing_seat"]] = values["bearing_heat_W_per_m_min"] * v * motion
    q[:, idx["sliders"]] = values["slider_heat_W_per_m_min"] * v * motion
    q[:, idx["motor"]] = (
        values["motor_heat_W_per_m_min"] * v * motion + values["motor_standstill_W"] * servo
    )
    return q


@dataclass(frozen=True)
class RunState:
    """Simulated hidden temperatures of one run on its grid (s from M1)."""

    timeline: cond.Timeline
    nodes: np.ndarray  # (n_grid, n_nodes)
    ambient: np.ndarray  # (n_grid,)

    @property
    def grid_s(self) -> np.ndarray:
        return self.timeline.grid_s

    def node(self, name: str, t_s) -> np.ndarray:
        return np.interp(t_s, self.grid_s, self.nodes[:, NODES.index(name)])


def initial_state(params: TwinParams, run: str, ambient_c: float) -> np.ndarray:
    """Node temperatures at the log start: the air plus the run's group offsets."""
    initial = np.full(len(NODES), float(ambient_c))
    for name, members in INITIAL_GROUPS.items():
        for node in members:
            initial[NODES.index(node)] += params.initial[run][name]
    return initial


def simulate_timeline(
    values: dict[str, float],
    tl: cond.Timeline,
    ambient,
    feed_mm_min: float,
    initial: np.ndarray,
) -> RunState:
    """Integrate the network over a timeline; ``ambient(t_s)`` gives the air temperature."""
    step_s = float(tl.grid_s[1] - tl.grid_s[0])
    mid = 0.5 * (tl.grid_s[:-1] + tl.grid_s[1:])
    q = heat_inputs(
        values, feed_mm_min, cond.motion_fraction(tl, step_s), cond.servo_fraction(tl, step_s)
    )
    inputs = np.column_stack([ambient(mid), q])
    nodes = simulate(
        discretise(step_s, capacity_scale(values), conductance_scale(values)), initial, inputs
    )
    return RunState(timeline=tl, nodes=nodes, ambient=ambient(tl.grid_s))


def simulate_run(
    condition: cond.Condition, params: TwinParams, step_s: float = cond.STEP_S
) -> RunState:
    """Integrate the network over one paper run's log window."""
    tl = cond.timeline(condition, step_s)
    ambient = lambda t: cond.ambient_at(condition, t)  # noqa: E731
    initial = initial_state(params, condition.run, float(ambient(tl.grid_s[:1])[0]))
    return simulate_timeline(params.values, tl, ambient, condition.feed_mm_min, initial)


def thermal_slope(values: dict[str, float], state: RunState, t_s) -> np.ndarray:
    """k_th(t), um/m: screw expansion minus the laser's material normalisation."""
    return values["screw_gain_um_per_m_K"] * (state.node("screw_core", t_s) - REFERENCE_C) - values[
        "reference_gain_um_per_m_K"
    ] * (state.node(REFERENCE_NODE, t_s) - REFERENCE_C)


def drift(values: dict[str, float], state: RunState, t_s) -> np.ndarray:
    """d(t), um: position-independent drift of the table against the optics."""
    return -sum(values[f"drift_{node}_um_per_K"] * state.node(node, t_s) for node in DRIFT_NODES)


def geometric_error(values: dict[str, float], x_mm) -> np.ndarray:
    x = np.asarray(x_mm, dtype=float)
    return values["geometric_slope_um_per_m"] * (
        x - X_FIXED_MM
    ) / 1000.0 + PITCH_AMPLITUDE_UM * np.sin(2 * np.pi * x / PITCH_PERIOD_MM + PITCH_PHASE_RAD)


def positioning_error(values: dict[str, float], state: RunState, x_mm, t_s) -> np.ndarray:
    """E(x, t), um, before zeroing (broadcasts x and t)."""
    x = np.asarray(x_mm, dtype=float)
    return (
        geometric_error(values, x)
        + thermal_slope(values, state, t_s) * (x - X_FIXED_MM) / 1000.0
        + drift(values, state, t_s)
    )
