"""The twin's forward problem and its targets: what the calibration fits, and against what.

The fit works on the NOISE-FREE model: for each of the 32 measurements it forms the
pass-mean error curve (with the deterministic reversal error, without noise) relative
to the datum and decouples it by least squares (the paper's Eq. 6), and it forms each
sensor's temperature during the measurement (mounting mix, lag, offset; mean over the
measurement's readings, as the pipeline's window mean).  The targets:

* the published fits -- Table 5 (k and b of the 32 measurements, read from the paper's
  transcription by :func:`paper_table5`, accepted at :data:`TOLERANCE_K`,
  :data:`TOLERANCE_B`); Eq. 9 applied to the twin's sensor
  temperatures against the twin's own k and b (accepted at the paper's Table 7 RMSE of
  its decoupled MLR, 2.6 um/m and 0.5 um); Eq. 8 at the printed positions -- each
  residual divided by its acceptance bound times :data:`OBJECTIVE_FACTOR`;
* the published results on fold E4 (:mod:`thermaxis.twin.results`): Table 6's
  partitions and points, Table 3's per-position points, the largest |residual| and
  the RMSE of decoupled and point-by-point MLR (Tables 7 and 4), Table 7's RMSE of
  the held-out slope k, the heated parts' warming -- margins divided by
  :data:`RESULT_TOLERANCE`;
* weak priors (:class:`thermaxis.twin.model.FreeParameter`) that keep the parameters the
  targets leave loose near physical values (applied by :mod:`thermaxis.twin.solver`).

Table 1's ambient ranges are met by construction (:mod:`thermaxis.twin.conditions`).
The selections and models inside the targets are the pipeline's own functions.

Speed: the network is linear, so a run's node temperatures are a sum of basis responses
(ambient, one per node's initial offset, one per heat input) weighted by the initial
offsets and heat coefficients; sensor temperatures are linear in those too.  All bases
of all runs are integrated together in one loop; only the capacity and conductance
factors force a new integration (the solver caches them per Jacobian).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import numpy as np

from thermaxis.method.selection import common_points
from thermaxis.paper.equations import PublishedTargets
from thermaxis.paper.published import load_table

from . import conditions as cond
from . import model as mdl
from .network import NODES, discretise
from .observe import INTERFEROMETER, SENSORS, calibrated_sensors, lagged
from .results import (
    HEATED_RISE_K,
    FoldData,
    ResultTargets,
    grades,
    held_out_max_residuals,
    held_out_slope_rmse,
    partition_margins,
    point_margins,
)

__all__ = [
    "paper_table5",
    "TOLERANCE_K",
    "TOLERANCE_B",
    "OBJECTIVE_FACTOR",
    "RunObservables",
    "target_residuals",
    "acceptance_bounds",
    "objective_weights",
    "fold_data",
    "PARTITION_DELTA",
    "POINT_DELTA",
    "TABLE3_DELTA",
    "RESULT_TOLERANCE",
    "result_residuals",
    "rms_by_target",
]


@cache
def paper_table5() -> dict[str, tuple[tuple[float, ...], tuple[float, ...]]]:
    """Table 5 of the paper: run -> (slope k in um/m, intercept b in um) of its measurements.

    Read from the package's transcription (``table5_slope_intercept.csv``), the one copy
    of these numbers; cached, as the objective asks for it at every evaluation.
    """
    table = load_table("table5").sort_values(["run", "measurement"], kind="stable")
    out = {}
    for run, rows in table.groupby("run", sort=True):
        if list(rows["measurement"]) != list(range(1, len(rows) + 1)):
            # The twin indexes Table 5 by measurement number: a gap would shift every value.
            raise ValueError(
                f"table5_slope_intercept.csv: run {run}: measurements must be 1..{len(rows)}, "
                f"found {list(rows['measurement'])}"
            )
        out[str(run)] = (
            tuple(float(v) for v in rows["k_um_per_m"]),
            tuple(float(v) for v in rows["b_um"]),
        )
    return out


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
    disc = discretise(step_s, mdl.capacity_scale(values), mdl.conductance_scale(values))
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
        k_paper, b_paper = (np.asarray(v, dtype=float) for v in paper_table5()[run])
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


def fold_data(runs: dict[str, RunObservables], fold: str) -> FoldData:
    """The paper's fold as arrays: the training runs (all but ``fold``) and ``fold`` itself."""
    sensors = tuple(s.id for s in SENSORS)

    def stack(names, what):
        return np.concatenate([what(runs[r]) for r in names])

    def absolute(o):
        return np.column_stack([o.temperatures[s] for s in sensors])

    def relative(o):
        a = absolute(o)
        return a - a[:1]

    train = [r for r in runs if r != fold]
    return FoldData(
        sensors=sensors,
        positions_mm=cond.TARGETS_MM,
        absolute=stack(train, absolute),
        relative=stack(train, relative),
        k=stack(train, lambda o: o.k),
        b=stack(train, lambda o: o.b),
        curves=stack(train, lambda o: o.curve),
        test_absolute=absolute(runs[fold]),
        test_relative=relative(runs[fold]),
        test_curves=runs[fold].curve,
        test_k=runs[fold].k,
    )


#: Margins the calibration keeps from a flip (similarity, grade units): the pipeline runs
#: on the NOISY raw files, whose cleaned window means differ from the noise-free model's.
PARTITION_DELTA = 0.03
POINT_DELTA = 0.01
TABLE3_DELTA = 0.01
#: Tolerances of the results' residuals in the objective (their units, see results.py).
RESULT_TOLERANCE: dict[str, float] = {
    "table6_classes": 0.003,
    "table6_points": 0.001,
    "table3_points": 0.01,
    "heldout": 0.3,
    "rise": 0.1,
    "heldout_rmse": 0.3,
    "heldout_slope": 0.5,
}


def result_residuals(
    runs: dict[str, RunObservables], targets: ResultTargets, eta: tuple[float, float]
) -> tuple[dict[str, np.ndarray], dict[str, float]]:
    """Residuals towards Tables 3, 4, 6, 7 and 8 (fold ``targets.fold``), and a summary.

    ``eta``: the lambda-cut thresholds of k and b the partitions are measured against
    (free variables of the optimiser, not of the twin).
    """
    data = fold_data(runs, targets.fold)
    col = {s: i for i, s in enumerate(data.sensors)}
    options, out, summary = _table6_residuals(data, targets, eta, col)
    # Table 3 is selected within the b partition (same relative temperatures).
    chosen, total, table3, hits = _table3_residuals(data, targets, options["b"], col)
    out["table3_points"] = table3
    summary["table3_hits"] = hits
    # The point-by-point inputs as the pipeline picks them from these selections.
    pointwise = common_points(
        chosen, 3, order=data.sensors, scores=dict(zip(data.sensors, total, strict=True))
    )
    held_out = held_out_max_residuals(data, targets, pointwise)
    out["heldout"] = np.array(
        [value - targets.max_residual_um[model] for model, (value, _) in held_out.items()]
    )
    out["heldout_rmse"] = np.array(
        [rmse - targets.rmse_um[model] for model, (_, rmse) in held_out.items()]
    )
    slope_rmse = held_out_slope_rmse(data, targets)
    out["heldout_slope"] = np.array([slope_rmse - targets.slope_rmse_um_per_m])
    summary["decoupled_mlr_k_rmse"] = slope_rmse
    for (approach, algorithm), (value, rmse) in held_out.items():
        summary[f"{approach}_{algorithm}_max_abs"] = value
        summary[f"{approach}_{algorithm}_rmse"] = rmse
    out["rise"] = np.array(
        [
            max(0.0, low - (o.temperatures[s][-1] - o.temperatures[s][0]))
            for o in runs.values()
            for s, low in HEATED_RISE_K.items()
        ]
    )
    return out, summary


def _table6_residuals(data, targets: ResultTargets, eta, col: dict) -> tuple[dict, dict, dict]:
    """Table 6: each target's partition option, the residuals of the k and b partitions
    and sensitive points, and their summary."""
    out, summary = {}, {}
    classes_residuals, points_residuals, options = [], [], {}
    for name, values, target, classes, points, threshold in (
        ("k", data.absolute, data.k, targets.k_classes, targets.k_points, eta[0]),
        ("b", data.relative, data.b, targets.b_classes, targets.b_points, eta[1]),
    ):
        residuals, option, margin = partition_margins(
            values, data.sensors, classes, threshold, PARTITION_DELTA
        )
        classes_residuals.append(residuals)
        options[name] = option
        gap, wins = point_margins(
            grades(target, values), option, [col[p] for p in points], POINT_DELTA
        )
        points_residuals.append(gap)
        summary[f"{name}_partition_margin"] = margin
        summary[f"{name}_points"] = wins
    out["table6_classes"] = np.concatenate(classes_residuals)
    out["table6_points"] = np.concatenate(points_residuals)
    return options, out, summary


def _table3_residuals(data, targets: ResultTargets, b_option, col: dict):
    """Table 3: the winners per position, the summed grades, the margins of the
    point-by-point sensitive points and how many the b partition's winners hit."""
    table3, hits, chosen, total = [], 0, [], np.zeros(len(data.sensors))
    for j, x in enumerate(data.positions_mm):
        g = grades(data.curves[:, j], data.relative)
        aimed = [col[p] for p in targets.switch_targets[float(x)]]
        table3.append(point_margins(g, b_option, aimed, TABLE3_DELTA)[0])
        winners = [data.sensors[int(max(members, key=lambda m: g[m]))] for members in b_option]
        hits += sum(p in winners for p in targets.per_position[float(x)])
        chosen.append(winners)
        total += g
    return chosen, total, np.concatenate(table3), hits


def rms_by_target(residuals: dict[str, dict[str, np.ndarray]]) -> dict[str, float]:
    """RMS of each target's residuals over all runs."""
    names = next(iter(residuals.values()))
    return {
        name: float(
            np.sqrt(np.mean(np.concatenate([np.ravel(r[name]) for r in residuals.values()]) ** 2))
        )
        for name in names
    }
