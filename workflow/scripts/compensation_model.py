"""Fit the configured model on every run and write model.json (the deployable compensation)."""

import json
from dataclasses import replace
from importlib.metadata import version

import pandas as pd

from thermaxis import compensation
from thermaxis.assemble import model_inputs
from thermaxis.experiment import select_for_fold, settings_from_config
from thermaxis.runner import run_script, write_text


def main(snakemake):
    p = snakemake.params
    X, Y = model_inputs(pd.read_parquet(snakemake.input.errors), pd.read_parquet(snakemake.input.temperatures))
    selection_settings, model_settings = settings_from_config(
        {"selection": p.selection, "decoupling": p.decoupling, "models": p.models}
    )
    settings = compensation.settings_from_config({"compensation": p.compensation})
    # The deployed model sees every run, its sensitive points too.
    selection = select_for_fold(
        X,
        Y,
        "all runs",
        replace(selection_settings, scope="all"),
        decoupled=p.approach == "decoupled",
        pointwise=p.approach == "pointwise",
    )
    estimator = compensation.fit_axis_model(
        X, Y, p.approach, settings.algorithm, selection, model_settings, selection_settings.degree
    )
    record = compensation.model_record(
        estimator,
        p.approach,
        settings.algorithm,
        X,
        settings.fallback,
        dataset=p.dataset_name,
        simulated=bool(p.simulated),
        statement=p.statement,
        trained_on=sorted(X["run"].unique().tolist()),
        held_out_accuracy=compensation.held_out_accuracy(pd.read_csv(snakemake.input.metrics), p.approach, settings.algorithm),
        provenance={
            "citation": p.citation,
            "packages": {name: version(name) for name in ("thermaxis", "scikit-learn", "numpy")},
            "settings": {"selection": p.selection, "decoupling": p.decoupling, "models": p.models, "compensation": p.compensation},
        },
    )
    compensation.validate_model(record, where=snakemake.output.model)
    write_text(json.dumps(record, indent=1) + "\n", snakemake.output.model)


run_script(main, snakemake)
