"""One batch of the sweep: its share of (fold x selection setting) units, every approach and algorithm."""

import pandas as pd
import sklearn

from thermaxis.cleaning.run import model_inputs
from thermaxis.config import ModelSettings, SelectionSettings, SweepSettings
from thermaxis.pipeline.runner import run_script, write_parquet
from thermaxis.sweep import plan as sweep_plan
from thermaxis.sweep import run as sweep_run


def main(snakemake):
    p = snakemake.params
    models = ModelSettings.from_section(p.models)
    settings = SweepSettings.from_section(p.sweep, models)
    grid = settings.grid
    units, _ = sweep_plan.plan_units(grid, p.folds, p.sensors)
    batch = int(snakemake.wildcards.batch)
    mine = sweep_plan.batch_units(units, p.n_batches, batch)
    X, Y = model_inputs(
        pd.read_parquet(snakemake.input.errors), pd.read_parquet(snakemake.input.temperatures)
    )
    total = sum(len(grid.unit_configurations(u.selection, p.decoupled)) for u in mine)
    progress = sweep_run.Progress(total, f"sweep batch {batch + 1}/{p.n_batches}")
    # One thread: run_script holds BLAS and OpenMP to the rule's threads (1), as batches
    # already occupy every core. The inputs were validated when assembled;
    # scikit-learn's per-call re-checks cost ~20% of a point-by-point SVR evaluation and
    # change no number.
    with sklearn.config_context(assume_finite=True, skip_parameter_validation=True):
        rows = sweep_run.run_batch(
            X,
            Y,
            mine,
            grid,
            SelectionSettings.from_section(p.selection),
            settings.models(models),
            p.decoupled,
            progress,
        )
    write_parquet(rows, snakemake.output[0])


run_script(main, snakemake)
