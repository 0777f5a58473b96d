"""One held-out run: its fold's model as the controller would run it, the exports and the error left."""

import json
import logging
from dataclasses import replace

import pandas as pd

from thermaxis.cleaning.run import logged_series, model_inputs
from thermaxis.compensation import heldout, runtime
from thermaxis.compensation import model as comp_model
from thermaxis.config import (
    CompensationSettings,
    DecouplingSettings,
    ModelSettings,
    SelectionSettings,
)
from thermaxis.dataset.reader import load_dataset, read_run
from thermaxis.method import recommend
from thermaxis.method.folds import select_for_fold, selection_from_dict
from thermaxis.pipeline.runner import run_script, write_csv, write_text


def main(snakemake):
    p = snakemake.params
    fold = snakemake.wildcards.fold
    X, Y = model_inputs(
        pd.read_parquet(snakemake.input.errors),
        pd.read_parquet(snakemake.input.temperatures),
        signals=pd.read_parquet(snakemake.input.signals),
        inputs=pd.read_parquet(snakemake.input.inputs),
    )
    decoupling = DecouplingSettings.from_section(p.sections["decoupling"])
    settings = CompensationSettings.from_section(p.sections["compensation"])
    with open(snakemake.input.choice, encoding="utf-8") as fh:
        # The model the procedure would have deployed without this run (its fold's choice).
        chosen = recommend.deployed_record(settings.model, json.load(fh), fold)
    setup = recommend.deployed_setup(
        chosen,
        X,
        p.approach,
        SelectionSettings.from_section(p.sections["selection"]),
        ModelSettings.from_section(p.sections["models"]),
        settings,
        p.signals,
    )
    # The final model may read inputs this fold's does not (a signal): it replays on all of X.
    everything, X, approach = X, setup.view, setup.approach
    if chosen is None:
        # The configured model's selection of this fold, as the models rule made it.
        with open(snakemake.input.selection, encoding="utf-8") as fh:
            selection = selection_from_dict(json.load(fh))
    else:
        selection = select_for_fold(
            X[setup.selectable],
            Y,
            fold,
            replace(setup.selection, scope="training"),
            decoupling.degree,
            decoupled=approach == "decoupled",
            pointwise=approach == "pointwise",
        )
    train = (X["run"] != fold).to_numpy()
    record = comp_model.fit_model_record(
        X.loc[train].reset_index(drop=True),
        Y.loc[train].reset_index(drop=True),
        selection,
        approach,
        setup.models,
        decoupling,
        setup.settings,
        **p.about,
    )
    text = json.dumps(record, indent=1) + "\n"
    write_text(text, snakemake.output.model)
    # The controller side reads the exported numbers, not the fitted estimator.
    model = runtime.Compensator(json.loads(text))
    final = runtime.Compensator.from_json(snakemake.input.final)
    X_run = X.loc[~train]
    cycles = None
    if model.derived or final.derived:
        sensors = list(dict.fromkeys([*model.sensors, *final.sensors]))
        cycles = heldout.measurement_cycles(
            logged_series(
                pd.read_parquet(snakemake.input.series),
                pd.read_parquet(snakemake.input.signal_series),
            ),
            pd.read_csv(snakemake.input.windows),
            sensors,
        )
    steps, _ = heldout.replay(model, X_run, cycles)
    _, final_values = heldout.replay(final, everything.loc[~train], cycles)
    for line in heldout.fallback_summary(fold, steps):
        logging.getLogger("thermaxis").warning(line)
    raw = read_run(load_dataset(p.dataset), fold)
    deviations = heldout.pass_deviations(raw, list(Y.columns), p.max_missing_fraction)
    time_min = X_run.sort_values("measurement")["time_min"].tolist()
    tables = heldout.held_out_tables(
        fold, steps, time_min, deviations, list(Y.columns), final_values
    )
    for name, frame in tables.items():
        write_csv(frame, snakemake.output[name], float_format="%.10g")


run_script(main, snakemake)
