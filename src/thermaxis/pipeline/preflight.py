"""Everything the workflow checks while Snakemake parses it, in one call.

``workflow/rules/common.smk`` calls :func:`check_before_jobs` before any rule is
defined, and the bad-input tests call the same function in-process: a bad config
value, dataset sheet, run folder or first data file raises ONE ``ValueError``
(a :class:`~thermaxis.errors.DataError` for the data) whose message the workflow prints
as ``thermaxis error: <message>``. Nothing is written.
"""

from __future__ import annotations

from dataclasses import dataclass

from thermaxis.dataset import plausibility
from thermaxis.dataset import safety
from thermaxis.config import validate_config
from thermaxis.errors import DataError
from thermaxis.dataset.reader import Dataset, load_dataset, read_first_measurement

__all__ = ["Checked", "check_before_jobs"]


@dataclass(frozen=True)
class Checked:
    config: dict  # validated, defaults filled
    dataset: Dataset
    out: str  # results/<dataset name>, checked to stay inside results/
    n_positions: int  # targets of the first run's first measurement
    ambient: str | None  # config ambient_sensor, else the dataset's


def check_before_jobs(config: dict) -> Checked:
    """Validate the config, the dataset and its first data file; raise ValueError with one line.

    Paths are relative to the working directory (the workflow's folder).
    """
    config = validate_config(config)
    dataset = load_dataset(config["dataset"])
    plausibility.check_dataset_shape(dataset, config)
    runs = list(dataset.run_ids)
    out = str(safety.check_inside(f"results/{dataset.name}", "results", what="results folder"))
    # The one data file read before any job: size-checked, regular and fully validated.
    n_positions = read_first_measurement(dataset, runs[0])["position_mm"].nunique()
    runs_sheet = dataset.root / "runs.tsv"
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
            f"config ambient_sensor: {ambient!r} is not a sensor of {dataset.root / 'dataset.yaml'} "
            f"(expected one of {', '.join(dataset.sensors)})"
        )
    signals = list(dataset.signals)
    for signal in config["models"]["signals"]:
        if signal not in signals:
            raise DataError(
                f"config models.signals: {signal!r} is not an operating signal of {dataset.root / 'dataset.yaml'} "
                f"(it declares {', '.join(signals) or 'none'})"
            )
    return Checked(config=config, dataset=dataset, out=out, n_positions=int(n_positions), ambient=ambient)
