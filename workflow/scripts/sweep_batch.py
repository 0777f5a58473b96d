"""One batch of the sweep: its share of (fold x selection setting) units, every approach and algorithm."""

import pandas as pd
import sklearn
from threadpoolctl import threadpool_limits

from thermaxis import sweep
from thermaxis.assemble import model_inputs
from thermaxis.experiment import settings_from_config
from thermaxis.runner import run_script, write_parquet


def main(snakemake):
    p = snakemake.params
    grid = sweep.grid_from_config(p.sweep)
    units, _ = sweep.plan_units(grid, p.folds, p.sensors)
    batch = int(snakemake.wildcards.batch)
    mine = sweep.batch_units(units, p.n_batches, batch)
    models = {**p.models, "svr_grid": sweep.svr_grid_for_sweep(p.sweep, p.models)}
    selection, model = settings_from_config({"selection": p.selection, "decoupling": p.decoupling, "models": models})
    X, Y = model_inputs(pd.read_parquet(snakemake.input.errors), pd.read_parquet(snakemake.input.temperatures))
    total = sum(len(grid.unit_configurations(u.selection, p.decoupled)) for u in mine)
    progress = sweep.Progress(total, f"sweep batch {batch + 1}/{p.n_batches}")
    # Batches already occupy every core: BLAS threads would only compete with them.
    # The inputs were validated when assembled; scikit-learn's per-call re-checks cost
    # ~20% of a point-by-point SVR evaluation and change no number.
    with threadpool_limits(limits=1), sklearn.config_context(assume_finite=True, skip_parameter_validation=True):
        rows = sweep.run_batch(X, Y, mine, grid, selection, model, decoupled=p.decoupled, progress=progress)
    write_parquet(rows, snakemake.output[0])


run_script(main, snakemake)
