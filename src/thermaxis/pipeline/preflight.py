"""Every check the workflow makes while Snakemake parses it: the one parse-time gate.

``workflow/rules/common.smk`` calls :func:`check_before_jobs` before anything else, and
the bad-input tests call the same functions in-process. A bad config value, dataset
sheet, run folder or first data file raises ONE ``ValueError`` (a
:class:`~thermaxis.errors.DataError` for the data) whose message the workflow prints as
``thermaxis error: <message>`` (:func:`one_line`). Nothing is written.

The config is validated here once per parse: :func:`check_before_jobs` fills the
schema's defaults with :func:`thermaxis.config.validate_config`, and the same dict
gives the settings and, copied into Snakemake's ``config``, what the rules read.

Two checks belong to this gate but cannot run when :func:`check_before_jobs` does:

* :func:`sweep_plan`, the sweep's units and batches, is computed only when a sweep job
  is in the DAG (the first time a sweep rule's input asks for it), so ``make results``
  never plans a sweep; it refuses a grid of which no selection setting fits the dataset;
* :func:`check_rules` runs once every rule is defined (the Snakefile's last statement):
  every output, log and benchmark stays in the dataset's folders.
"""

from __future__ import annotations

import os
import sys
from contextlib import contextmanager
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

from thermaxis.config import Settings, validate_config
from thermaxis.dataset import plausibility, safety
from thermaxis.dataset.reader import Dataset, load_dataset, read_first_measurement
from thermaxis.errors import DataError
from thermaxis.sweep import plan

__all__ = [
    "Checked",
    "SweepPlan",
    "check_before_jobs",
    "check_writable",
    "sweep_plan",
    "check_rules",
    "one_line",
]


@dataclass(frozen=True)
class Checked:
    """What the gate found: the validated config, the settings, the dataset and its folders."""

    config: dict  # validated once, defaults filled: what the rules read as `config`
    settings: Settings  # from the same dict
    dataset: Dataset
    out: str  # results/<dataset name>, checked to stay inside results/
    n_positions: int  # targets of the first run's first measurement
    ambient: str | None  # config ambient_sensor, else the dataset's

    @property
    def logs(self) -> str:
        return f"logs/{self.dataset.name}"

    @property
    def bench(self) -> str:
        return f"benchmarks/{self.dataset.name}"

    @property
    def runs(self) -> list[str]:
        return list(self.dataset.run_ids)

    @property
    def folds(self) -> list[str]:
        """Held-out runs of the main workflow (config ``folds``, empty = every run)."""
        return list(self.config["folds"]) or self.runs

    @property
    def sweep_folds(self) -> list[str]:
        return list(self.settings.sweep.folds) or self.runs


@dataclass(frozen=True)
class SweepPlan:
    """The sweep's (fold x selection setting) units and how they are split into batch jobs."""

    units: list
    skipped: list[str]  # notes on the selection settings left out
    batches: int
    unit_sizes: list[int] = field(repr=False)  # evaluations (configuration x fold) per unit

    @cached_property
    def evaluations(self) -> int:
        return sum(self.unit_sizes)


def check_before_jobs(config: dict) -> Checked:
    """Validate the config, the dataset and its first data file; raise ValueError with one line.

    Paths are relative to the working directory (the workflow's folder).
    """
    config = validate_config(config)
    settings = Settings.from_validated(config)
    dataset = load_dataset(config["dataset"])
    plausibility.check_dataset_shape(dataset)
    runs = list(dataset.run_ids)
    out = str(safety.check_inside(f"results/{dataset.name}", "results", what="results folder"))
    for folder in (out, f"logs/{dataset.name}", f"benchmarks/{dataset.name}"):
        check_writable(folder)
    # The one data file read before any job: size-checked, regular and fully validated.
    n_positions = read_first_measurement(dataset, runs[0])["position_mm"].nunique()
    runs_sheet, sheet = dataset.root / "runs.tsv", dataset.root / "dataset.yaml"
    for fold in config["folds"]:
        if fold not in runs:
            raise DataError(f"config folds: {fold!r} is not a run of {runs_sheet}")
    fig_run = config["figures"]["run"] or runs[0]
    if fig_run not in runs:
        raise DataError(f"config figures.run: {fig_run!r} is not a run of {runs_sheet}")
    if dataset.reproduces == "xu2023" and config["paper_fold"] not in runs:
        raise DataError(
            f"config paper_fold: {config['paper_fold']!r} is not a run of {runs_sheet} "
            f"(the paper's held-out run; expected one of {', '.join(runs)})"
        )
    ambient = config.get("ambient_sensor") or dataset.ambient_sensor
    if ambient is not None and ambient not in dataset.sensors:
        raise DataError(
            f"config ambient_sensor: {ambient!r} is not a sensor of {sheet} "
            f"(expected one of {', '.join(dataset.sensors)})"
        )
    signals = list(dataset.signals)
    for signal in config["models"]["signals"]:
        if signal not in signals:
            raise DataError(
                f"config models.signals: {signal!r} is not an operating signal of {sheet} "
                f"(it declares {', '.join(signals) or 'none'})"
            )
    algorithms, compensated = settings.models.algorithms, settings.compensation.algorithm
    if compensated not in algorithms:
        raise DataError(
            f"config compensation.algorithm: {compensated!r} is not one of models.algorithms "
            f"({', '.join(algorithms)}); its held-out metrics go into model.json"
        )
    for fold in settings.sweep.folds:
        if fold not in runs:
            raise DataError(f"config sweep.folds: {fold!r} is not a run of {runs_sheet}")
    return Checked(
        config=config,
        settings=settings,
        dataset=dataset,
        out=out,
        n_positions=int(n_positions),
        ambient=ambient,
    )


def check_writable(folder) -> None:
    """``folder``, or the nearest folder above it that exists, can be written; else one line.

    Before any job: otherwise every job would fail on its own, after minutes of work.
    ``os.access`` answers for root too on a read-only mount or an immutable folder,
    where permission bits mean nothing, and it writes nothing.
    """
    path = Path(folder).absolute()
    existing = next(p for p in (path, *path.parents) if p.exists())
    if os.access(existing, os.W_OK | os.X_OK):
        return
    cause = (
        "is on a read-only file system"
        if os.statvfs(existing).f_flag & os.ST_RDONLY
        else "cannot be written (permissions or an immutable flag)"
    )
    where = folder if existing == path else f"{folder} (its folder {existing})"
    raise DataError(
        f"{where}: {cause}; expected a results folder the workflow can write: make it writable, "
        "or run from a writable copy of the checkout"
    )


def sweep_plan(checked: Checked, cores: int | None, on_cluster: bool) -> SweepPlan:
    """The sweep's units and batch count; raise ValueError with one line if nothing fits.

    Locally there is one batch per core given (``cores`` None: one batch); on a cluster
    one per ``sweep.cluster_batch_size`` evaluations (config ``sweep.batches`` overrides
    both). A cluster job parses the workflow again and finds the same plan: the units
    depend only on the grid, the folds and the sensors.
    """
    sweep = checked.settings.sweep
    units, skipped = plan.plan_units(sweep.grid, checked.sweep_folds, checked.dataset.sensors)
    if not units:
        raise DataError(
            f"config sweep: no selection setting fits the dataset ({'; '.join(skipped)})"
        )
    decoupled = checked.n_positions >= 2
    sizes = [len(sweep.grid.unit_configurations(u.selection, decoupled)) for u in units]
    if on_cluster:
        batches = plan.cluster_batch_count(sweep.batches, sizes, sweep.cluster_batch_size)
    else:
        batches = plan.batch_count(sweep.batches, cores, len(units))
    return SweepPlan(units=units, skipped=skipped, batches=batches, unit_sizes=sizes)


def check_rules(rules, checked: Checked) -> None:
    """Every output, log and benchmark pattern of every rule stays in the dataset's folders.

    Names are checked too, but a rule edited later must not be able to write elsewhere either.
    """
    safety.check_rule_outputs(rules, (checked.out, checked.logs, checked.bench))


@contextmanager
def one_line():
    """A ValueError (DataError included) inside ends the parse: ``thermaxis error: <message>``."""
    try:
        yield
    except ValueError as exc:
        sys.exit(f"thermaxis error: {exc}")
