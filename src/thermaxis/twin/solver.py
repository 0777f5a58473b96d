"""The calibration's solver: scipy's least squares over the stages, on one core or many.

Each stage (:data:`thermaxis.twin.stages.STAGES`) minimises the scaled residuals of
:mod:`thermaxis.twin.problem` plus the priors over (twin parameters, eta_k, eta_b);
the Jacobian's columns are spread over a pool of forked workers, each computed the same
way whatever their number.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from thermaxis.paper.equations import published_targets

from . import conditions as cond
from . import model as mdl
from .problem import (
    RunObservables,
    _Bases,
    _bases,
    _Problem,
    _problem,
    _runs_from_bases,
    acceptance_bounds,
    result_residuals,
    rms_by_target,
    target_residuals,
)
from .results import result_targets
from .stages import STAGES, Stage, resume_index

__all__ = ["FitResult", "calibrate", "worker_pool"]


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
    lower, upper = _bounds(runs)
    x, todo = _start(runs, lower, upper, resume)
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


def _start(runs, lower: np.ndarray, upper: np.ndarray, resume) -> tuple[np.ndarray, tuple]:
    """The starting vector and the stages still to run: the priors' centres (initial
    offsets 0) and every stage, or the resumed parameters and the stages after theirs."""
    x = np.array(
        [p.prior if np.isfinite(p.prior_width) else 0.0 for p in mdl.GLOBAL_PARAMETERS.values()]
        + [p.prior for _ in runs for p in mdl.INITIAL_PARAMETERS.values()]
        + [_ETA_START, _ETA_START]
    )
    x = np.clip(x, lower, upper)
    if resume is None:
        return x, STAGES
    params, after = resume
    return np.concatenate([params.vector(runs), x[-2:]]), STAGES[resume_index(after) :]


def _set_stage(args) -> None:
    _WORKER.stage, _WORKER.full, _WORKER.index, _WORKER.correction = args
