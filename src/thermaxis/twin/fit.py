"""Calibration of the twin's free parameters against the paper's published fits and tables.

The fit works on the NOISE-FREE model: for each of the 32 measurements it forms the
pass-mean error curve (with the deterministic reversal error, without noise) relative
to the datum and decouples it by least squares (the paper's Eq. 6), and it forms each
sensor's temperature during the measurement (mounting mix, lag, offset; mean over the
measurement's readings, as the pipeline's window mean).  The targets:

* Table 5: k and b of the 32 measurements (accepted at :data:`TOLERANCE_K`, :data:`TOLERANCE_B`);
* Eq. 9 applied to the twin's sensor temperatures against the twin's own k and b
  (accepted at the paper's Table 7 RMSE of its decoupled MLR, 2.6 um/m and 0.5 um);
* Eq. 8 at the printed positions against the twin's pass-mean error there
  (accepted at the paper's Table 7 error RMSE, 0.6 um);

each residual divided by its acceptance bound times :data:`OBJECTIVE_FACTOR`, plus weak priors (:class:`thermaxis.twin.model.FreeParameter`) that keep the
parameters the targets leave loose near physical values.  Table 1's ambient ranges are
met by construction (:mod:`thermaxis.twin.conditions`).  The pipeline's held-out
results (Tables 7 and 8 as reproduced, the selected sensors) never enter the objective.

Speed: the network is linear, so a run's node temperatures are a sum of basis responses
(ambient, one per initial-offset group, one per heat input) weighted by the initial
offsets and heat coefficients; sensor temperatures are linear in those too.  All bases
of all runs are integrated together in one loop; only the capacity factors force a new
integration.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from . import conditions as cond
from . import model as mdl
from .network import NODES, discretise
from .observe import INTERFEROMETER, SENSORS, calibrated_sensors, lagged
from .published import PublishedTargets, published_targets

__all__ = [
    "PAPER_TABLE5",
    "TOLERANCE_K",
    "TOLERANCE_B",
    "RunObservables",
    "FitResult",
    "target_residuals",
    "OBJECTIVE_FACTOR",
    "acceptance_bounds",
    "objective_weights",
    "rms_by_target",
    "calibrate",
]

#: Table 5 of the paper: slope k (um/m) and intercept b (um) of the 32 measurements.
PAPER_TABLE5: dict[str, tuple[tuple[float, ...], tuple[float, ...]]] = {
    "E1": (
        (-9.8, -9.0, -8.8, -8.6, -8.2, -7.7, -7.5, -6.6),
        (0.1, -1.1, -1.8, -2.3, -2.6, -2.9, -3.4, -4.0),
    ),
    "E2": (
        (-23.7, -22.1, -22.1, -21.7, -21.5, -20.4, -19.6, -18.7),
        (-0.2, -1.2, -1.4, -1.7, -3.2, -5.1, -6.9, -8.7),
    ),
    "E3": (
        (-22.9, -22.1, -21.8, -21.3, -20.5, -20.1, -18.3, -18.0),
        (0.2, -1.1, -1.8, -2.5, -2.8, -3.0, -3.4, -3.2),
    ),
    "E4": (
        (-13.5, -12.8, -12.6, -11.9, -11.0, -10.0, -8.8, -7.3),
        (-0.1, -1.1, -1.7, -2.5, -3.4, -4.0, -4.7, -5.5),
    ),
}
TOLERANCE_K = 0.5
TOLERANCE_B = 0.3
#: Each target's tolerance in the objective is its acceptance bound times this factor.
#: Below 1 where the targets compete: weighted at their bounds, Eq. 8 and Eq. 9 pull
#: Table 5's intercepts to an RMS of 0.36-0.40 um (> 0.3), and Table 5 then pushes
#: Eq. 9's b just past its bound.
OBJECTIVE_FACTOR: dict[str, float] = {
    "table5_k": 0.8,
    "table5_b": 0.5,
    "eq9_k": 1.0,
    "eq9_b": 0.8,
    "eq8": 1.0,
}

_HEAT_BASES = ("nut", "bearing_seat", "sliders", "motor_feed", "motor_standstill")
_HEAT_PARAMETERS = (
    "nut_heat_W_per_m_min",
    "bearing_heat_W_per_m_min",
    "slider_heat_W_per_m_min",
    "motor_heat_W_per_m_min",
    "motor_standstill_W",
)


def _decoupling_operator() -> np.ndarray:
    """Rows (b, k) of the least-squares line through the 14 targets, origin 185 mm."""
    shifted_m = (cond.TARGETS_MM - cond.FIRST_TARGET_MM) / 1000.0
    return np.linalg.pinv(np.vander(shifted_m, 2, increasing=True))


#: Surfaces a sensor may see: the network's nodes, then the workshop air.
_SURFACES: tuple[str, ...] = NODES + ("ambient",)
_READINGS = 2 * cond.TARGETS_MM.size


@dataclass(frozen=True)
class _Problem:
    runs: tuple[str, ...]
    forcing_inputs: np.ndarray  # (n_steps, 1 + n_nodes, n_runs * n_bases)
    initial: np.ndarray  # (n_nodes, n_runs * n_bases)
    air: np.ndarray  # (n_steps + 1, n_runs * n_bases): the air, in each run's basis 0
    sample_index: np.ndarray  # (n_runs, n_times) step boundary left of each time
    sample_weight: np.ndarray  # (n_runs, n_times)
    n_bases: int


def _reading_times(tl: cond.Timeline) -> np.ndarray:
    """Datum time, then each measurement's forward pass and its backward pass reversed."""
    times = [np.array([float(cond.ZERO_S)])]
    for start in tl.measurement_start_s:
        forward, backward = cond.reading_times(start)
        times += [forward, backward[::-1]]
    return np.concatenate(times)


def _problem(step_s: float) -> _Problem:
    runs = tuple(c.run for c in cond.CONDITIONS)
    n = len(NODES)
    n_bases = 1 + len(mdl.INITIAL_GROUPS) + len(_HEAT_BASES)
    timelines = [cond.timeline(c, step_s) for c in cond.CONDITIONS]
    n_steps = max(tl.grid_s.size - 1 for tl in timelines)
    U = np.zeros((n_steps, 1 + n, len(runs) * n_bases))
    S0 = np.zeros((n, len(runs) * n_bases))
    air = np.zeros((n_steps + 1, len(runs) * n_bases))
    index, weight = [], []
    for r, (c, tl) in enumerate(zip(cond.CONDITIONS, timelines, strict=False)):
        col = r * n_bases
        grid = tl.grid_s
        steps = grid.size - 1
        mid = 0.5 * (grid[:-1] + grid[1:])
        # Basis 0: the ambient drive and the machine starting at the air temperature.
        U[:steps, 0, col] = cond.ambient_at(c, mid)
        S0[:, col] = cond.ambient_at(c, grid[:1])[0]
        air[: steps + 1, col] = cond.ambient_at(c, grid)
        for g, members in enumerate(mdl.INITIAL_GROUPS.values(), start=1):
            for node in members:
                S0[NODES.index(node), col + g] = 1.0
        v = c.feed_mm_min / 1000.0
        motion = cond.motion_fraction(tl, step_s)
        servo = cond.servo_fraction(tl, step_s)
        first_heat = col + 1 + len(mdl.INITIAL_GROUPS)
        for h, basis in enumerate(_HEAT_BASES):
            node = "motor" if basis.startswith("motor") else basis
            U[:steps, 1 + NODES.index(node), first_heat + h] = (
                servo if basis == "motor_standstill" else v * motion
            )
        times = _reading_times(tl)
        j = np.searchsorted(grid, times, side="right") - 1
        index.append(j)
        weight.append((times - grid[j]) / step_s)
    return _Problem(
        runs=runs,
        forcing_inputs=U,
        initial=S0,
        air=air,
        sample_index=np.array(index),
        sample_weight=np.array(weight),
        n_bases=n_bases,
    )


@dataclass(frozen=True)
class _Bases:
    """Basis responses of every surface (nodes, then the air) at the reading times."""

    surfaces: np.ndarray  # (n_runs, n_times, n_surfaces, n_bases), the datum first
    sensors: dict[
        float, np.ndarray
    ]  # lag (s) -> lagged, mean per measurement: (n_runs, n_meas, n_surfaces, n_bases)


def _sample(problem: _Problem, states: np.ndarray) -> np.ndarray:
    nb = problem.n_bases
    out = []
    for r in range(len(problem.runs)):
        j = problem.sample_index[r]
        w = problem.sample_weight[r][:, None, None]
        block = states[:, :, r * nb : (r + 1) * nb]
        out.append((1.0 - w) * block[j] + w * block[j + 1])
    return np.array(out)


def _bases(problem: _Problem, values: dict[str, float], step_s: float) -> _Bases:
    disc = discretise(step_s, mdl.capacity_scale(values))
    forcing = np.einsum("ij,sjc->sic", disc.Bd, problem.forcing_inputs)
    states = np.empty((forcing.shape[0] + 1,) + problem.initial.shape)
    state = problem.initial
    states[0] = state
    Ad = disc.Ad
    for i in range(forcing.shape[0]):
        state = Ad @ state + forcing[i]
        states[i + 1] = state
    states = np.concatenate([states, problem.air[:, None, :]], axis=1)
    sensors = {}
    for lag in sorted({s.lag_s for s in SENSORS}):
        at_readings = _sample(problem, lagged(states, step_s, lag))[:, 1:]
        n_runs, n_times = at_readings.shape[:2]
        shape = (n_runs, n_times // _READINGS, _READINGS) + at_readings.shape[2:]
        sensors[lag] = at_readings.reshape(shape).mean(axis=2)
    return _Bases(surfaces=_sample(problem, states), sensors=sensors)


def _geometric_curve(values: dict[str, float]) -> np.ndarray:
    """Geometric error at the 14 targets relative to the first target (constant in time)."""
    return mdl.geometric_error(values, cond.TARGETS_MM) - mdl.geometric_error(
        values, cond.FIRST_TARGET_MM
    )


@dataclass(frozen=True)
class RunObservables:
    """What the instruments report per measurement of one run (noise-free in the fit)."""

    k: np.ndarray  # (n_meas,) um/m
    b: np.ndarray  # (n_meas,) um at 185 mm
    curve: np.ndarray  # (n_meas, 14) pass-mean error (with half the reversal error), um
    temperatures: dict[str, np.ndarray]  # sensor -> mean over each measurement, degC


def _runs_from_bases(
    params: mdl.TwinParams, problem: _Problem, bases: _Bases
) -> dict[str, RunObservables]:
    values = params.values
    operator = _decoupling_operator()
    geometric = _geometric_curve(values) + 0.5 * INTERFEROMETER.reversal_um
    heat = np.array([values[name] for name in _HEAT_PARAMETERS])
    lever_m = (cond.TARGETS_MM - mdl.X_FIXED_MM) / 1000.0
    ref_m = (cond.FIRST_TARGET_MM - mdl.X_FIXED_MM) / 1000.0
    idx = {name: i for i, name in enumerate(_SURFACES)}
    sensors = calibrated_sensors(values)
    out = {}
    for r, run in enumerate(problem.runs):
        offsets = np.array([params.initial[run][name] for name in mdl.INITIAL_GROUPS])
        coef = np.concatenate([[1.0], offsets, heat])
        T = bases.surfaces[r] @ coef  # (n_times, n_surfaces)
        k_th = values["screw_gain_um_per_m_K"] * (
            T[:, idx["screw_core"]] - mdl.REFERENCE_C
        ) - values["reference_gain_um_per_m_K"] * (T[:, idx[mdl.REFERENCE_NODE]] - mdl.REFERENCE_C)
        d = -sum(values[f"drift_{node}_um_per_K"] * T[:, idx[node]] for node in mdl.DRIFT_NODES)
        datum = k_th[0] * ref_m + d[0]
        n_meas = (k_th.size - 1) // _READINGS
        k_r = k_th[1:].reshape(n_meas, 2, -1)
        d_r = d[1:].reshape(n_meas, 2, -1)
        # The pass mean keeps half the reversal error (the backward pass reads lower).
        curve = (k_r * lever_m + d_r).mean(axis=1) - datum + geometric
        b, k = operator @ curve.T
        temperatures = {}
        for sensor in sensors:
            surfaces = bases.sensors[sensor.lag_s][r] @ coef  # (n_meas, n_surfaces)
            mix = sum(w * surfaces[:, idx[name]] for name, w in sensor.weights.items())
            temperatures[sensor.id] = mix + sensor.offset_c
        out[run] = RunObservables(k=k, b=b, curve=curve, temperatures=temperatures)
    return out


def target_residuals(
    runs: dict[str, RunObservables], targets: PublishedTargets
) -> dict[str, dict[str, np.ndarray]]:
    """Differences from every published target, per run (um/m for k, um otherwise).

    ``table5_k``, ``table5_b``: twin minus Table 5; ``eq9_k``, ``eq9_b``: Eq. 9 on the
    twin's temperatures minus the twin's k and b; ``eq8``: Eq. 8 on the twin's
    temperatures minus the twin's error, at the printed positions (n_meas, n_positions).
    """
    position = {x: int(np.flatnonzero(cond.TARGETS_MM == x)[0]) for x in targets.pointwise}
    out: dict[str, dict[str, np.ndarray]] = {}
    for run, o in runs.items():
        k_paper, b_paper = (np.asarray(v, dtype=float) for v in PAPER_TABLE5[run])
        out[run] = {
            "table5_k": o.k - k_paper,
            "table5_b": o.b - b_paper,
            "eq9_k": targets.k.predict(o.temperatures) - o.k,
            "eq9_b": targets.b.predict(o.temperatures) - o.b,
            "eq8": np.column_stack(
                [
                    m.predict(o.temperatures) - o.curve[:, position[x]]
                    for x, m in targets.pointwise.items()
                ]
            ),
        }
    return out


def acceptance_bounds(targets: PublishedTargets) -> dict[str, float]:
    """Each target's acceptance: RMS over the 32 measurements at most this."""
    return {
        "table5_k": TOLERANCE_K,
        "table5_b": TOLERANCE_B,
        "eq9_k": targets.bound_k_um_per_m,
        "eq9_b": targets.bound_b_um,
        "eq8": targets.bound_error_um,
    }


def objective_weights(targets: PublishedTargets) -> dict[str, float]:
    """Each target's tolerance: its residuals enter the objective divided by it."""
    return {
        name: bound * OBJECTIVE_FACTOR[name] for name, bound in acceptance_bounds(targets).items()
    }


@dataclass(frozen=True)
class FitResult:
    params: mdl.TwinParams
    rms: dict[str, float]  # target -> RMS difference over the 32 measurements
    cost: float
    evaluations: int


def _prior_residuals(x: np.ndarray, runs: tuple[str, ...]) -> np.ndarray:
    free = list(mdl.GLOBAL_PARAMETERS.values()) + [
        p for _ in runs for p in mdl.INITIAL_PARAMETERS.values()
    ]
    centre = np.array([p.prior for p in free])
    width = np.array([p.prior_width for p in free])
    return (x - centre) / width


def rms_by_target(residuals: dict[str, dict[str, np.ndarray]]) -> dict[str, float]:
    """RMS of each target's residuals over all runs."""
    names = next(iter(residuals.values()))
    return {
        name: float(
            np.sqrt(np.mean(np.concatenate([np.ravel(r[name]) for r in residuals.values()]) ** 2))
        )
        for name in names
    }


def calibrate(
    start: mdl.TwinParams | None = None, step_s: float = cond.STEP_S, max_evaluations: int = 4000
) -> FitResult:
    """Fit the free parameters to the published targets (deterministic trust-region least squares).

    Parameters
    ----------
    start
        Starting point; defaults to the priors' centres (initial offsets 0).
    step_s
        Integration step of the network.
    max_evaluations
        Budget of model evaluations.
    """
    problem = _problem(step_s)
    runs = problem.runs
    targets = published_targets()
    weights = objective_weights(targets)
    if start is None:
        x0 = np.array(
            [p.prior if np.isfinite(p.prior_width) else 0.0 for p in mdl.GLOBAL_PARAMETERS.values()]
            + [p.prior for _ in runs for p in mdl.INITIAL_PARAMETERS.values()]
        )
    else:
        x0 = start.vector(runs)
    lower, upper = mdl.parameter_bounds(runs)
    x0 = np.clip(x0, lower, upper)
    cache: dict[tuple, _Bases] = {}

    def target_differences(x: np.ndarray) -> dict[str, dict[str, np.ndarray]]:
        params = mdl.TwinParams.from_vector(x, runs)
        key = tuple(params.values[f"log_capacity_{n}"] for n in mdl.CAPACITY_NODES)
        if key not in cache:
            cache.clear()
            cache[key] = _bases(problem, params.values, step_s)
        return target_residuals(_runs_from_bases(params, problem, cache[key]), targets)

    def residuals(x: np.ndarray) -> np.ndarray:
        diff = target_differences(x)
        scaled = [np.ravel(diff[run][name]) / tol for name, tol in weights.items() for run in runs]
        return np.concatenate(scaled + [_prior_residuals(x, runs)])

    solution = least_squares(
        residuals,
        x0,
        bounds=(lower, upper),
        x_scale="jac",
        max_nfev=max_evaluations,
        xtol=1e-10,
        ftol=1e-10,
    )
    return FitResult(
        params=mdl.TwinParams.from_vector(solution.x, runs),
        rms=rms_by_target(target_differences(solution.x)),
        cost=float(solution.cost),
        evaluations=int(solution.nfev),
    )
