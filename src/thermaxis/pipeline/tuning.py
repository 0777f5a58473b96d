"""What each rule asks of the machine: memory and runtime, priority, threads.

Memory (MB) and runtime (minutes) of a rule's first attempt; a retry (--retries) asks
for attempt x both. Rules not listed get the floors of the requests that
`python -m thermaxis.pipeline.resources benchmarks/<dataset>` derives from a run's
benchmarks; the sweep's batches get a runtime from their share of the grid.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

from thermaxis.pipeline.resources import MIN_MEMORY_MB, MIN_RUNTIME_MIN, per_attempt, request
from thermaxis.sweep.plan import Unit, batch_units
from thermaxis.sweep_grid import SweepGrid

REPORT_RULES = (
    "dataset_report",
    "condition_report",
    "conditions_report",
    "model_report",
    "paper_report",
    "sweep_report",
)

# Of the jobs ready at once, Snakemake starts the set with the largest sum of priorities
# that fits the cores. A rule ranks by the longest chain of work from its start to the end
# of the run, in the jobs' times of the twin and fl_thermal (benchmarks/): the fits feed
# every later stage; the prediction figures, the largest job, feed the model pages; the
# compensation feeds the results figures and three reports. Left to its ties, Snakemake
# gave the core the prediction figures waited for to a report that only the index needs.
# The recommendation's chain is the longest and grows fastest with the runs: above any
# two other priorities together, it never waits for both cores behind two one-core jobs,
# as it did for 49 s on a 12-run record (docs/performance.md).
PRIORITY = {
    "recommend": 20,
    "models": 9,
    "fig_predictions": 8,
    "compensation": 7,
    "statistics": 6,
    "fig_results": 5,
    "fig_data": 4,
    "condition_report": 4,
    "conditions_report": 4,
    "model_report": 3,
    "paper_report": 2,
    "dataset_report": 1,
}


def resource_table(n_runs: int, n_folds: int, sweep_minutes: Callable) -> dict:
    """Per rule (memory MB, runtime minutes or a function of the wildcards); "default" for the rest."""
    return {
        "default": (MIN_MEMORY_MB, MIN_RUNTIME_MIN),
        **{name: (750, MIN_RUNTIME_MIN) for name in REPORT_RULES},
        "compensation": (1000, MIN_RUNTIME_MIN),
        # Every run in one job, two workers at most locally: 0.49 GB peak at 43 and 86 runs
        # (benchmarks of the scale bench), about 0.3 s a run.
        "clean": (1000, max(MIN_RUNTIME_MIN, n_runs // 20)),
        # Every candidate on every inner split of every fold: the heaviest job of a run.
        "recommend": (1000, max(30, 10 * n_folds)),
        "sweep_batch": (MIN_MEMORY_MB, sweep_minutes),
    }


def rule_resources(table: dict, name: str) -> dict:
    """The ``resources:`` of rule ``name`` in ``table`` (:func:`resource_table`)."""
    return per_attempt(*table.get(name, table["default"]))


def rule_priority(name: str) -> int:
    """The ``priority:`` of rule ``name`` (PRIORITY; 0 for a rule not listed)."""
    return PRIORITY.get(name, 0)


def batch_minutes(
    grid: SweepGrid,
    units: Sequence[Unit],
    n_batches: int,
    batch: int,
    seconds_per_evaluation: float,
    decoupled: bool = True,
) -> int:
    """Time limit (minutes) of one batch job: its evaluations at the given cost, with the
    headroom :func:`thermaxis.pipeline.resources.request` gives every rule."""
    evaluations = sum(
        len(grid.unit_configurations(u.selection, decoupled))
        for u in batch_units(units, n_batches, batch)
    )
    return request(evaluations * seconds_per_evaluation, 0.0)[1]
