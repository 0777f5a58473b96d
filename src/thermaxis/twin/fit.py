"""Calibration of the twin's free parameters against the paper's published fits and results.

The fit works on the NOISE-FREE model: for each of the 32 measurements it forms the
pass-mean error curve (with the deterministic reversal error, without noise) relative
to the datum and decouples it by least squares (the paper's Eq. 6), and it forms each
sensor's temperature during the measurement (mounting mix, lag, offset; mean over the
measurement's readings, as the pipeline's window mean).  The targets:

* the published fits -- Table 5 (k and b of the 32 measurements, accepted at
  :data:`TOLERANCE_K`, :data:`TOLERANCE_B`); Eq. 9 applied to the twin's sensor
  temperatures against the twin's own k and b (accepted at the paper's Table 7 RMSE of
  its decoupled MLR, 2.6 um/m and 0.5 um); Eq. 8 at the printed positions -- each
  residual divided by its acceptance bound times :data:`OBJECTIVE_FACTOR`;
* the published results on fold E4 (:mod:`thermaxis.twin.results`): Table 6's
  partitions and points, Table 3's per-position points, the largest |residual| and
  the RMSE of decoupled and point-by-point MLR (Tables 7 and 4), Table 7's RMSE of
  the held-out slope k, the heated parts' warming -- margins divided by
  :data:`RESULT_TOLERANCE`;
* weak priors (:class:`thermaxis.twin.model.FreeParameter`) that keep the parameters the
  targets leave loose near physical values.

Table 1's ambient ranges are met by construction (:mod:`thermaxis.twin.conditions`).

Through the pipeline: the later stages (:data:`STAGES`) apply a defect correction.  At
the stage's start the raw files of the current parameters are written and run through
the pipeline's own cleaning, assembly and decoupling
(:func:`thermaxis.twin.calibration.pipeline_observables`); the
difference from the noise-free model (the noise, the faults, the clocks, the cleaning)
is held, so the objective there is computed on what the pipeline assembles, and nearby
on that plus the model's change.  The selections and models inside the objective are
the pipeline's own functions.

Speed: the network is linear, so a run's node temperatures are a sum of basis responses
(ambient, one per node's initial offset, one per heat input) weighted by the initial
offsets and heat coefficients; sensor temperatures are linear in those too.  All bases
of all runs are integrated together in one loop; only the capacity and conductance
factors force a new integration, cached per Jacobian.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from thermaxis.method.selection import common_points
from thermaxis.paper.equations import PublishedTargets, published_targets

from . import conditions as cond
from . import model as mdl
from .network import NODES, discretise
from .observe import INTERFEROMETER, SENSORS, calibrated_sensors, lagged
from .results import (
    HEATED_RISE_K,
    FoldData,
    ResultTargets,
    grades,
    heldout_max_residuals,
    heldout_slope_rmse,
    partition_margins,
    point_margins,
    result_targets,
)

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
    "STAGES",
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
    # Table 3 is selected within the b partition (same relative temperatures).
    b_option = options["b"]
    table3, hits, chosen, total = [], 0, [], np.zeros(len(data.sensors))
    for j, x in enumerate(data.positions_mm):
        g = grades(data.curves[:, j], data.relative)
        aimed = [col[p] for p in targets.switch_targets[float(x)]]
        table3.append(point_margins(g, b_option, aimed, TABLE3_DELTA)[0])
        winners = [data.sensors[int(max(members, key=lambda m: g[m]))] for members in b_option]
        hits += sum(p in winners for p in targets.per_position[float(x)])
        chosen.append(winners)
        total += g
    out["table3_points"] = np.concatenate(table3)
    summary["table3_hits"] = hits
    # The point-by-point inputs as the pipeline picks them from these selections.
    pointwise = common_points(
        chosen, 3, order=data.sensors, scores=dict(zip(data.sensors, total, strict=True))
    )
    heldout = heldout_max_residuals(data, targets, pointwise)
    out["heldout"] = np.array(
        [value - targets.max_residual_um[model] for model, (value, _) in heldout.items()]
    )
    out["heldout_rmse"] = np.array(
        [rmse - targets.rmse_um[model] for model, (_, rmse) in heldout.items()]
    )
    slope_rmse = heldout_slope_rmse(data, targets)
    out["heldout_slope"] = np.array([slope_rmse - targets.slope_rmse_um_per_m])
    summary["decoupled_mlr_k_rmse"] = slope_rmse
    for (approach, algorithm), (value, rmse) in heldout.items():
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


@dataclass(frozen=True)
class Stage:
    """One step of the staged calibration: which targets enter, and its budget."""

    name: str
    results: tuple[str, ...]  # which of RESULT_TOLERANCE's terms enter
    max_evaluations: int  # Jacobian evaluations (least-squares iterations)
    published: bool = True  # Table 5, Eq. 8 and Eq. 9 enter
    through_pipeline: bool = False  # corrected to what the pipeline makes of the raw files
    # Overrides of RESULT_TOLERANCE and OBJECTIVE_FACTOR for this stage, (name, value).
    tolerance: tuple[tuple[str, float], ...] = ()
    factors: tuple[tuple[str, float], ...] = ()
    # Start from the parameters as twin_params.json writes them, and the thresholds from
    # their start: the calibration can be resumed from the file at any such stage.
    restart: bool = False

    def result_tolerance(self, name: str) -> float:
        return dict(self.tolerance).get(name, RESULT_TOLERANCE[name])

    def weight(self, name: str, bound: float) -> float:
        return bound * dict(self.factors).get(name, OBJECTIVE_FACTOR[name])


#: The terms of the stages before the held-out RMSEs joined (Tables 4 and 7's RMSE).
_RESULTS = ("table6_classes", "table6_points", "table3_points", "heldout", "rise")
#: Table 6 held loosely: the published fits, pushed away by the Table 6 stage, come back.
_LOOSE = (("table6_classes", 0.01), ("table6_points", 0.003))


def _restart(
    name: str, evaluations: int, tolerance: dict[str, float], factors: dict[str, float]
) -> Stage:
    """A restart stage through the pipeline: every result term, plus each term given a
    tolerance that the stages before the held-out RMSEs did not have."""
    extra = tuple(term for term in tolerance if term not in _RESULTS)
    return Stage(
        f"{name}, pipeline",
        results=_RESULTS + extra,
        max_evaluations=evaluations,
        through_pipeline=True,
        restart=True,
        tolerance=tuple(tolerance.items()),
        factors=tuple(factors.items()),
    )


#: The published fits first (from the priors); then Table 6 alone, whose partitions are
#: far from the priors' field and need the whole network to move; then everything
#: through the pipeline, twice with Table 6 held loosely, once at full weight with
#: Table 5's intercepts tighter (the results pull them most), and twice with the kept
#: targets tighter still (Table 5, then Table 5 and Eq. 9), so that they hold on the
#: pipeline's k, b and temperatures.  The results' margins are
#: piecewise linear, so each stage starts where the last one met its own targets.
#: Every stage has all the twin's parameters free.
STAGES: tuple[Stage, ...] = (
    (
        Stage("published fits", results=(), max_evaluations=60),
        Stage(
            "Table 6",
            results=("table6_classes", "table6_points", "rise"),
            max_evaluations=60,
            published=False,
            tolerance=(("table6_points", 0.003),),
        ),
        Stage(
            "results, pipeline, loose 1",
            results=_RESULTS,
            max_evaluations=60,
            through_pipeline=True,
            tolerance=_LOOSE,
        ),
        Stage(
            "results, pipeline, loose 2",
            results=_RESULTS,
            max_evaluations=60,
            through_pipeline=True,
            tolerance=_LOOSE,
        ),
        Stage(
            "results, pipeline",
            results=_RESULTS,
            max_evaluations=60,
            through_pipeline=True,
            factors=(("table5_b", 0.35),),
        ),
        Stage(
            "kept targets, pipeline",
            results=_RESULTS,
            max_evaluations=40,
            through_pipeline=True,
            factors=(("table5_k", 0.5), ("table5_b", 0.25)),
        ),
        Stage(
            "kept targets with Eq. 9, pipeline",
            results=_RESULTS,
            max_evaluations=40,
            through_pipeline=True,
            factors=(("table5_k", 0.5), ("table5_b", 0.25), ("eq9_k", 0.8), ("eq9_b", 0.6)),
        ),
    )
    + tuple(
        # Table 3 refined by restarts: the single-switch targets' margins are a grade apart
        # (0.001-0.01), so each restart corrects to the pipeline afresh, with Table 3 held
        # tighter and Eq. 9's intercepts brought back under their bound as Table 3 pushes
        # them up; the held-out errors first tight (their bounds are the narrowest), then at
        # their tolerance.  A schedule found by trial on these targets (docs/datasets.md).
        _restart(
            f"Table 3 restart {i}",
            evaluations,
            {"table3_points": table3, **({} if heldout is None else {"heldout": heldout})},
            {"table5_k": 0.5, "table5_b": 0.25, "eq9_k": 0.8, "eq9_b": eq9_b},
        )
        for i, (evaluations, table3, heldout, eq9_b) in enumerate(
            (
                (15, 0.002, None, 0.6),
                (30, 0.002, 0.1, 0.5),
                (20, 0.002, 0.1, 0.5),
                (25, 0.001, 0.2, 0.45),
                (25, 0.001, 0.2, 0.4),
                (25, 0.001, 0.2, 0.25),
            ),
            start=1,
        )
    )
    + tuple(
        # The held-out RMSEs (Tables 4 and 7's error RMSE, then Table 7's slope RMSE) join
        # at restarts, tightened in turn while Table 5 is held tighter; then Eq. 9's slopes
        # brought back under their bound, the largest residuals held tighter, and Table 3's
        # margins last.  Also a schedule found by trial on these targets (docs/datasets.md).
        _restart(
            f"held-out RMSE restart {i}",
            evaluations,
            {"table3_points": table3, "heldout": heldout, "heldout_rmse": rmse}
            | ({"heldout_slope": slope} if slope else {}),
            {"table5_k": table5_k, "table5_b": table5_b, "eq9_k": eq9_k, "eq9_b": 0.3},
        )
        for i, (evaluations, table3, heldout, rmse, slope, table5_k, table5_b, eq9_k) in enumerate(
            (
                (30, 0.001, 0.2, 0.05, None, 0.5, 0.25, 0.8),
                (30, 0.001, 0.2, 0.05, 0.2, 0.5, 0.25, 0.8),
                (30, 0.001, 0.2, 0.05, 0.1, 0.4, 0.2, 0.8),
                (30, 0.001, 0.2, 0.05, 0.05, 0.4, 0.2, 0.8),
                (30, 0.001, 0.2, 0.05, 0.05, 0.4, 0.2, 0.8),
                (30, 0.001, 0.2, 0.1, 0.1, 0.4, 0.2, 0.6),
                (15, 0.001, 0.2, 0.1, 0.1, 0.4, 0.2, 0.5),
                (15, 0.001, 0.2, 0.1, 0.1, 0.4, 0.2, 0.5),
                (15, 0.001, 0.1, 0.1, 0.1, 0.4, 0.2, 0.6),
                (15, 0.001, 0.1, 0.1, 0.1, 0.4, 0.2, 0.6),
                (20, 0.0005, 0.1, 0.1, 0.1, 0.4, 0.2, 0.6),
            ),
            start=1,
        )
    )
)


def _difference(a: RunObservables, b: RunObservables) -> RunObservables:
    return RunObservables(
        k=a.k - b.k,
        b=a.b - b.b,
        curve=a.curve - b.curve,
        temperatures={s: a.temperatures[s] - b.temperatures[s] for s in b.temperatures},
    )


@dataclass(frozen=True)
class FitResult:
    params: mdl.TwinParams
    rms: dict[str, float]  # target -> RMS difference over the 32 measurements
    summary: dict[str, float]  # the results' margins, points and held-out residuals
    cost: float
    evaluations: int
    stages: tuple[dict, ...]  # per stage: name, iterations, evaluations, seconds


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


class _Objective:
    """The scaled residual vector of one stage over (twin parameters, eta_k, eta_b).

    Network integrations are cached by the network parameters (capacities and
    conductances): the other columns of a finite-difference Jacobian reuse them.
    """

    def __init__(self, problem: _Problem, step_s: float):
        self.problem = problem
        self.step_s = step_s
        self.targets = published_targets()
        self.results = result_targets()
        self.bounds = acceptance_bounds(self.targets)
        self.stage = STAGES[0]
        self._cache: dict[tuple, _Bases] = {}
        n = len(mdl.GLOBAL_PARAMETERS)
        self._network = [
            i for i, name in enumerate(mdl.GLOBAL_PARAMETERS) if name in mdl.NETWORK_PARAMETERS
        ]
        self._n_twin = n + len(problem.runs) * len(mdl.INITIAL_PARAMETERS)
        self.full = np.zeros(self._n_twin + 2)  # the held values of the current stage
        self.index = np.arange(self._n_twin + 2)  # its free variables
        self.correction: dict[str, RunObservables] = {}  # model minus pipeline, per run

    def free(self, stage: Stage) -> np.ndarray:
        """Indices of the stage's free variables: the etas (last) only with the results."""
        return np.arange(self._n_twin + (2 if stage.results else 0))

    def params(self, x: np.ndarray) -> mdl.TwinParams:
        return mdl.TwinParams.from_vector(x[: self._n_twin], self.problem.runs)

    def observables(self, x: np.ndarray) -> dict[str, RunObservables]:
        """The noise-free model, plus the stage's correction towards the pipeline."""
        params = self.params(x)
        key = tuple(np.round(x[self._network], 12))
        if key not in self._cache:
            if len(self._cache) > 2 * len(self._network) + 2:
                self._cache.pop(next(iter(self._cache)))
            self._cache[key] = _bases(self.problem, params.values, self.step_s)
        runs = _runs_from_bases(params, self.problem, self._cache[key])
        if not self.correction:
            return runs
        return {run: _difference(o, self.correction[run]) for run, o in runs.items()}

    def correct_to_pipeline(self, x: np.ndarray, pipeline) -> None:
        """Defect correction: hold the pipeline's departure from the noise-free model at x.

        Afterwards the objective at x is computed on exactly what the pipeline assembles
        from the raw files of x, and near x on that plus the model's change.
        """
        self.correction = {}
        model = self.observables(x)
        assembled = pipeline(self.params(x))
        self.correction = {run: _difference(model[run], assembled[run]) for run in model}

    def __call__(self, z: np.ndarray) -> np.ndarray:
        x = self.full.copy()
        x[self.index] = z
        runs = self.observables(x)
        scaled = []
        if self.stage.published:
            diff = target_residuals(runs, self.targets)
            scaled += [
                np.ravel(diff[run][name]) / self.stage.weight(name, bound)
                for name, bound in self.bounds.items()
                for run in self.problem.runs
            ]
        if self.stage.results:
            residuals, _ = result_residuals(runs, self.results, (x[-2], x[-1]))
            scaled += [
                residuals[name] / self.stage.result_tolerance(name) for name in self.stage.results
            ]
        return np.concatenate(scaled + [_prior_residuals(x[: self._n_twin], self.problem.runs)])


_WORKER: _Objective | None = None


def _column(args) -> np.ndarray:
    # Each task carries the stage and its held values: a pool gives no way to reach
    # every worker once, so nothing of a stage is left in a worker between tasks.
    x, i, h, stage = args
    _set_stage(stage)
    step = x.copy()
    step[i] += h
    return _WORKER(step)


def _jacobian(objective: _Objective, pool, lower: np.ndarray, upper: np.ndarray):
    """Forward differences (scipy's '2-point' step), columns spread over the pool's workers.

    Every column is computed the same way whatever the number of workers, so the fit is
    the same on one core or many.
    """

    def jac(x: np.ndarray, f0: np.ndarray | None = None) -> np.ndarray:
        f0 = objective(x) if f0 is None else f0
        h = np.sqrt(np.finfo(float).eps) * np.maximum(1.0, np.abs(x))
        h = np.where(x + h > upper, -h, h)
        stage = (objective.stage, objective.full, objective.index, objective.correction)
        tasks = [(x, i, h[i], stage) for i in range(x.size)]
        columns = pool.map(_column, tasks, chunksize=4) if pool else map(_column, tasks)
        return np.column_stack([(c - f0) / hi for c, hi in zip(columns, h, strict=True)])

    return jac


# The lambda-cut thresholds' start and range (free variables of the optimiser only).
_ETA_START, _ETA_RANGE = 0.85, (0.5, 0.99)


def _bounds(runs: tuple[str, ...]) -> tuple[np.ndarray, np.ndarray]:
    """Bounds of (twin parameters, eta_k, eta_b): the physical ones, then the etas'."""
    twin_lower, twin_upper = mdl.parameter_bounds(runs)
    low, high = _ETA_RANGE
    return np.concatenate([twin_lower, [low, low]]), np.concatenate([twin_upper, [high, high]])


def worker_pool(workers: int):
    import multiprocessing

    return multiprocessing.get_context("fork").Pool(workers) if workers > 1 else None


def _solve(objective: _Objective, pool, x, stage: Stage, lower, upper, pipeline):
    """One stage of least squares from ``x``: the new x, scipy's solution, and its record."""
    import time

    start = time.perf_counter()
    index = objective.free(stage)
    if stage.through_pipeline:
        objective.correct_to_pipeline(x, pipeline)
    _set_stage((stage, x, index, objective.correction))
    solution = least_squares(
        objective,
        x[index],
        jac=_jacobian(objective, pool, lower[index], upper[index]),
        bounds=(lower[index], upper[index]),
        x_scale="jac",
        max_nfev=stage.max_evaluations,
        xtol=1e-10,
        ftol=1e-10,
    )
    x = x.copy()
    x[index] = solution.x
    record = dict(
        name=stage.name,
        iterations=int(solution.njev),
        evaluations=int(solution.nfev) + int(solution.njev) * index.size,
        seconds=round(time.perf_counter() - start, 1),
    )
    return x, solution, record


def _restarted(x: np.ndarray, objective: _Objective, lower, upper) -> np.ndarray:
    """``x`` as a restart from the written file sees it: rounded as saved, thresholds anew."""
    twin = [round(float(v), mdl.PARAMS_DECIMALS) for v in x[: objective._n_twin]]
    return np.clip(np.array(twin + [_ETA_START, _ETA_START]), lower, upper)


def _resume_index(after: str) -> int:
    """Index of the stage after the one named ``after``; it must start afresh (a restart).

    After the last stage only the polish (:mod:`thermaxis.twin.polish`) is left.
    """
    names = [stage.name for stage in STAGES]
    if after == "polish":
        raise ValueError(
            "cannot resume after stage 'polish': the calibration is complete (resume from "
            "the file its least-squares stages wrote, twin_params.heldout_restarts.json)"
        )
    if after not in names:
        raise ValueError(f"cannot resume after stage {after!r}: not a stage of STAGES")
    index = names.index(after) + 1
    if index < len(STAGES) and not STAGES[index].restart:
        raise ValueError(f"cannot resume after stage {after!r}: the next stage is no restart")
    return index


def calibrate(
    pipeline,
    step_s: float = cond.STEP_S,
    workers: int = 2,
    resume: tuple[mdl.TwinParams, str] | None = None,
    polish: Callable[[mdl.TwinParams], tuple[mdl.TwinParams, dict]] | None = None,
) -> FitResult:
    """Fit the free parameters to the paper's published fits and results, stage by stage.

    ``pipeline(params)`` gives what the pipeline makes of the raw files of ``params``
    (:func:`thermaxis.twin.calibration.pipeline_observables`; passed in, so this module
    needs neither the files' writer nor the pipeline).

    Deterministic on one machine: a fixed start (the priors' centres, initial offsets
    0), scipy's trust-region least squares with a fixed budget per stage
    (:data:`STAGES`), and forward-difference Jacobians computed the same way on any
    number of ``workers``.  (Another CPU may take other BLAS kernels, whose last bits a
    least-squares path amplifies: hence the resume points.)

    ``resume``: (parameters, the name of the last stage they went through); the
    calibration goes on at the next stage, which must be a restart, as the whole run
    does there.  ``polish(params)``: the last leg after the stages
    (:func:`thermaxis.twin.polish.polish`), giving the parameters and its record.
    """
    global _WORKER
    problem = _problem(step_s)
    runs = problem.runs
    objective = _Objective(problem, step_s)
    x = np.array(
        [p.prior if np.isfinite(p.prior_width) else 0.0 for p in mdl.GLOBAL_PARAMETERS.values()]
        + [p.prior for _ in runs for p in mdl.INITIAL_PARAMETERS.values()]
        + [_ETA_START, _ETA_START]
    )
    lower, upper = _bounds(runs)
    x = np.clip(x, lower, upper)
    todo = STAGES
    if resume is not None:
        params, after = resume
        todo = STAGES[_resume_index(after) :]
        x = np.concatenate([params.vector(runs), x[-2:]])
    _WORKER = objective
    pool = worker_pool(workers)
    stages, evaluations, solution = [], 0, None
    try:
        for stage in todo:
            if stage.restart:
                x = _restarted(x, objective, lower, upper)
            x, solution, record = _solve(objective, pool, x, stage, lower, upper, pipeline)
            evaluations += record["evaluations"]
            stages.append(record)
    finally:
        if pool is not None:
            pool.close()
            pool.join()
    if polish is not None:
        polished, record = polish(objective.params(x))
        x = np.concatenate([polished.vector(runs), x[-2:]])
        evaluations += record["evaluations"]
        stages.append(record)
    observed = objective.observables(x)
    _, summary = result_residuals(observed, objective.results, (x[-2], x[-1]))
    return FitResult(
        params=objective.params(x),
        rms=rms_by_target(target_residuals(observed, objective.targets)),
        summary=summary,
        cost=float(solution.cost) if solution is not None else float("nan"),
        evaluations=evaluations,
        stages=tuple(stages),
    )


def _set_stage(args) -> None:
    _WORKER.stage, _WORKER.full, _WORKER.index, _WORKER.correction = args
