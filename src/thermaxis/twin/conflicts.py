"""Which of the paper's targets the twin can meet together: the optimiser's best per pair.

``make twin-conflicts`` (``python -m thermaxis.twin conflicts``). The calibration
(:mod:`thermaxis.twin.solver`) meets Table 6, Table 5, Eq. 9 and the decoupled and
point-by-point MLR residuals, but not Table 3's 34 of 42 per-position points. Whether
that is the optimiser's failure or a conflict between targets is measured here, not
argued:

* every **group** of targets (Table 3; the held-out MLR residuals of Tables 7 and 4;
  Table 5; Eq. 9) is optimised **alone**, and every **pair** of groups together, each
  time with Table 6 (partitions and points) and the heated parts' warming held, the
  priors and every physical bound of :mod:`thermaxis.twin.model` in force;
* each optimisation starts from the committed calibration, runs :data:`BUDGET`
  evaluations of the same least squares as the calibration's stages, with the same
  defect correction towards the pipeline (:meth:`~thermaxis.twin.solver._Objective.correct_to_pipeline`);
* at its end the twin's raw files are written and run through the pipeline again, and
  every target is read from what the pipeline assembles.

Two groups conflict when optimising them together leaves either worse than optimising
it alone. The table says by how much. The committed calibration is the compromise, by
this rule: Table 6 first, always; then the kept targets (Table 5, Eq. 9, Table 1's
ambient) within their acceptance; then the results, weighted by their tolerances
(:data:`thermaxis.twin.stages.STAGES`).
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import combinations

import numpy as np

from . import conditions as cond
from . import model as mdl
from . import solver
from .problem import (
    PARTITION_DELTA,
    _problem,
    fold_data,
    result_residuals,
    rms_by_target,
    target_residuals,
)
from .results import partition_margins
from .stages import Stage

__all__ = ["GROUPS", "BUDGET", "Experiment", "conflicts", "conflicts_markdown"]

#: Each group: the result terms (thermaxis.twin.problem.RESULT_TOLERANCE) and published fits it adds.
GROUPS: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "Table 3": (("table3_points",), ()),
    "held-out MLR": (("heldout",), ()),
    "Table 5": ((), ("table5_k", "table5_b")),
    "Eq. 9": ((), ("eq9_k", "eq9_b")),
}
#: Held in every experiment.
ALWAYS = ("table6_classes", "table6_points", "rise")
#: Least-squares evaluations per experiment (a calibration stage has 40 to 60).
BUDGET = 20
# A published fit left out of an experiment: its residuals divided by this vanish.
_OFF = 1e9
_PUBLISHED = ("table5_k", "table5_b", "eq9_k", "eq9_b", "eq8")


@dataclass(frozen=True)
class Experiment:
    """One optimisation: the groups optimised, and every target read through the pipeline."""

    groups: tuple[str, ...]
    values: dict[str, float]


def _stage(groups: tuple[str, ...]) -> Stage:
    results = ALWAYS + tuple(r for g in groups for r in GROUPS[g][0])
    published = {p for g in groups for p in GROUPS[g][1]}
    return Stage(
        " + ".join(groups),
        results=results,
        max_evaluations=BUDGET,
        published=bool(published),
        through_pipeline=True,
        factors=tuple((p, _OFF) for p in _PUBLISHED if p not in published),
    )


def _best_etas(objective: solver._Objective, x: np.ndarray) -> np.ndarray:
    """The lambda-cut thresholds at which the committed twin's partitions hold best."""
    runs = objective.observables(x)
    data = fold_data(runs, objective.results.fold)
    grid = np.round(np.arange(solver._ETA_RANGE[0], solver._ETA_RANGE[1] + 1e-9, 0.005), 3)
    x = x.copy()
    for j, (values, classes) in enumerate(
        ((data.absolute, objective.results.k_classes), (data.relative, objective.results.b_classes))
    ):
        margins = [partition_margins(values, data.sensors, classes, eta, PARTITION_DELTA)[2]
                   for eta in grid]  # fmt: skip
        x[-2 + j] = grid[int(np.argmax(margins))]
    return x


def _read(objective: solver._Objective, x: np.ndarray, pipeline) -> dict[str, float]:
    """Every target at x, from what the pipeline assembles of the raw files of x."""
    objective.correct_to_pipeline(x, pipeline)
    runs = objective.observables(x)
    _, summary = result_residuals(runs, objective.results, (x[-2], x[-1]))
    rms = rms_by_target(target_residuals(runs, objective.targets))
    table6 = (
        summary["k_partition_margin"] >= 0
        and summary["b_partition_margin"] >= 0
        and summary["k_points"] == 3
        and summary["b_points"] == 3
    )
    return {
        "table6_holds": float(table6),
        "table3_hits": summary["table3_hits"],
        "decoupled_mlr_max_abs": summary["decoupled_mlr_max_abs"],
        "pointwise_mlr_max_abs": summary["pointwise_mlr_max_abs"],
        "table5_k_rms": rms["table5_k"],
        "table5_b_rms": rms["table5_b"],
        "eq9_k_rms": rms["eq9_k"],
        "eq9_b_rms": rms["eq9_b"],
    }


def conflicts(pipeline, workers: int = 2, progress=print) -> list[Experiment]:
    """The committed calibration, every group alone and every pair of groups (module docstring)."""
    problem = _problem(cond.STEP_S)
    objective = solver._Objective(problem, cond.STEP_S)
    committed = mdl.load_params()
    x0 = np.concatenate([committed.vector(problem.runs), [solver._ETA_START, solver._ETA_START]])
    lower, upper = solver._bounds(problem.runs)
    x0 = _best_etas(objective, np.clip(x0, lower, upper))
    solver._WORKER = objective
    pool = solver.worker_pool(workers)
    out = [Experiment((), _read(objective, x0, pipeline))]
    try:
        for size in (1, 2):
            for groups in combinations(GROUPS, size):
                x, _, record = solver._solve(
                    objective, pool, x0, _stage(groups), lower, upper, pipeline
                )
                out.append(Experiment(groups, _read(objective, x, pipeline)))
                progress(f"twin conflicts: {record['name']}: {record['seconds']:.0f} s")
    finally:
        if pool is not None:
            pool.close()
            pool.join()
    return out


# Each group's own figures, and which way is better.
_FIGURES: dict[str, tuple[tuple[str, int], ...]] = {
    "Table 3": (("table3_hits", +1),),
    "held-out MLR": (("decoupled_mlr_max_abs", -1), ("pointwise_mlr_max_abs", -1)),
    "Table 5": (("table5_k_rms", -1), ("table5_b_rms", -1)),
    "Eq. 9": (("eq9_k_rms", -1), ("eq9_b_rms", -1)),
}


def pair_costs(experiments: list[Experiment]) -> list[dict]:
    """Per pair of groups: how much worse each figure ends together than alone (0 = no conflict)."""
    by_groups = {e.groups: e.values for e in experiments}
    rows = []
    for a, b in combinations(GROUPS, 2):
        together = by_groups[(a, b)]
        for group in (a, b):
            alone = by_groups[(group,)]
            for name, better in _FIGURES[group]:
                rows.append(
                    {
                        "pair": f"{a} + {b}",
                        "figure": name,
                        "alone": alone[name],
                        "together": together[name],
                        "cost": max(0.0, better * (alone[name] - together[name])),
                    }
                )
    return rows


_COLUMNS = ("table6_holds", "table3_hits", "decoupled_mlr_max_abs", "pointwise_mlr_max_abs",
            "table5_k_rms", "table5_b_rms", "eq9_k_rms", "eq9_b_rms")  # fmt: skip


def conflicts_markdown(experiments: list[Experiment]) -> str:
    """docs/twin-conflicts.md: every experiment's targets, then the cost of each pair."""
    head = "| optimised (with Table 6) | " + " | ".join(_COLUMNS) + " |"
    lines = [
        "# Which targets the twin meets together",
        "",
        "SIMULATED: the thermal twin. Written by `make twin-conflicts` "
        "(`python -m thermaxis.twin conflicts`, thermaxis.twin.conflicts); every figure is read "
        "through the pipeline at the optimisation's end. Acceptance: Table 3 >= 34 hits, decoupled "
        "MLR 1.6 ± 0.3 µm, point-by-point MLR 4.3 ± 0.5 µm, Table 5 RMS k <= 0.5, b <= 0.3, Eq. 9 "
        "RMS k <= 2.6, b <= 0.5.",
        "",
        f"Each row is one least-squares run of {BUDGET} evaluations from the committed calibration, "
        "Table 6 and the heated parts' warming held, every physical bound in force: a local best "
        "within that budget, not a global one. A group left out is not held, so it may drift far.",
        "",
        head,
        "|" + "---|" * (len(_COLUMNS) + 1),
    ]
    for e in experiments:
        name = " + ".join(e.groups) if e.groups else "committed calibration"
        cells = [
            ("yes" if e.values[c] else "no") if c == "table6_holds" else f"{e.values[c]:.3g}"
            for c in _COLUMNS
        ]
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    lines += [
        "",
        "Cost of each pair: how much worse a group's figure ends when optimised with the other "
        "group than alone (0: they do not conflict within the budget).",
        "",
        "| pair | figure | alone | together | cost |",
        "|---|---|---|---|---|",
    ]
    lines += [
        f"| {r['pair']} | {r['figure']} | {r['alone']:.3g} | {r['together']:.3g} | {r['cost']:.3g} |"
        for r in pair_costs(experiments)
    ]
    return "\n".join(lines) + "\n"
