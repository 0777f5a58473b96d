"""Fit the configured model on every run and write model.json (the deployable compensation)."""

import json
from dataclasses import replace
from importlib.metadata import version

import pandas as pd

from thermaxis.cleaning.run import model_inputs
from thermaxis.compensation import heldout
from thermaxis.compensation import model as comp_model
from thermaxis.config import (
    CompensationSettings,
    DecouplingSettings,
    ModelSettings,
    SelectionSettings,
)
from thermaxis.method.folds import select_for_fold
from thermaxis.pipeline.runner import run_script, write_text


def main(snakemake):
    p = snakemake.params
    sections = p.sections
    decoupling = DecouplingSettings.from_section(sections["decoupling"])
    settings = CompensationSettings.from_section(sections["compensation"])
    X, Y = model_inputs(
        pd.read_parquet(snakemake.input.errors), pd.read_parquet(snakemake.input.temperatures)
    )
    # The deployed model sees every run, its sensitive points too.
    selection = select_for_fold(
        X,
        Y,
        "all runs",
        replace(SelectionSettings.from_section(sections["selection"]), scope="all"),
        decoupling.degree,
        decoupled=p.approach == "decoupled",
        pointwise=p.approach == "pointwise",
    )
    metrics = pd.read_csv(snakemake.input.metrics)
    record = comp_model.fit_model_record(
        X,
        Y,
        selection,
        p.approach,
        ModelSettings.from_section(sections["models"]),
        decoupling,
        settings,
        **p.about,
        held_out_accuracy=heldout.held_out_accuracy(metrics, p.approach, settings.algorithm),
        provenance={
            "citation": p.citation,
            "packages": {name: version(name) for name in ("thermaxis", "scikit-learn", "numpy")},
            "settings": sections,
        },
    )
    comp_model.validate_model(record, where=snakemake.output.model)
    write_text(json.dumps(record, indent=1) + "\n", snakemake.output.model)


run_script(main, snakemake)
