"""Every run's cleaning in one job (thermaxis.cleaning.run.clean_run per run, over the
job's threads); each run's tables in its own folder. Warnings are logged in run order, and
the first run that fails stops the job before anything is written."""

import logging
from functools import partial

from thermaxis.cleaning.run import clean_run
from thermaxis.config import CleaningSettings
from thermaxis.pipeline.parallel import fold_workers, map_folds
from thermaxis.pipeline.runner import run_script, write_csv, write_parquet

# Each run's outputs: the rule's named output lists, in the order of params.runs.
PARQUET = ("series", "errors", "temperatures", "signals", "signal_series", "inputs")
CSV = ("qc", "gaps", "windows")


def main(snakemake):
    p, out = snakemake.params, snakemake.output
    cleaning = CleaningSettings.from_sections(p.temperatures, p.errors)
    # A bad-input test runs this script without Snakemake's threads: one process.
    workers = fold_workers(getattr(snakemake, "threads", 1), len(p.runs), "clean")
    one_run = partial(clean_run, p.dataset, cleaning=cleaning, lags_min=p.lags_min)
    cleaned = map_folds(one_run, p.runs, workers)
    log = logging.getLogger("thermaxis")
    for run in cleaned:
        for note in run.warnings:
            log.warning(note)
        if run.error is not None:
            raise run.error
    for i, run in enumerate(cleaned):
        tables = {**vars(run.tables), "inputs": run.inputs}
        for name in PARQUET:
            write_parquet(tables[name], out[name][i])
        for name in CSV:
            write_csv(tables[name], out[name][i])


run_script(main, snakemake)
