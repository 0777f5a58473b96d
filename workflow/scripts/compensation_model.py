"""Fit the deployed model on every run: compensation/fitted_model.json (the verdict comes later).

The deployed model is config compensation.model: the recommendation's choice among the
candidates the controller exports can compute, the paper's configured model, or a
named candidate (thermaxis.method.recommend.deployed_record).
"""

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
from thermaxis.method import recommend
from thermaxis.method.folds import select_for_fold
from thermaxis.pipeline.runner import run_script, write_text


def main(snakemake):
    p = snakemake.params
    sections = p.sections
    decoupling = DecouplingSettings.from_section(sections["decoupling"])
    settings = CompensationSettings.from_section(sections["compensation"])
    X, Y = model_inputs(
        pd.read_parquet(snakemake.input.errors),
        pd.read_parquet(snakemake.input.temperatures),
        signals=pd.read_parquet(snakemake.input.signals),
        inputs=pd.read_parquet(snakemake.input.inputs),
    )
    with open(snakemake.input.choice, encoding="utf-8") as fh:
        record = recommend.deployed_record(settings.model, json.load(fh))
    setup = recommend.deployed_setup(
        record,
        X,
        p.approach,
        SelectionSettings.from_section(sections["selection"]),
        ModelSettings.from_section(sections["models"]),
        settings,
        p.signals,
    )
    approach, settings = setup.approach, setup.settings
    if record is None:
        deployment = {"model": "paper", "candidate": "paper"}
        accuracy = heldout.held_out_accuracy(
            pd.read_csv(snakemake.input.metrics), approach, settings.algorithm
        )
    else:
        deployment = {"model": p.model, "candidate": record["name"]}
        scores = pd.concat(
            [pd.read_csv(path) for path in snakemake.input.scores], ignore_index=True
        )
        accuracy = recommend.held_out_accuracy(scores, record["name"])
    # The deployed model sees every run, its sensitive points too.
    selection = select_for_fold(
        setup.view[setup.selectable],
        Y,
        "all runs",
        replace(setup.selection, scope="all"),
        decoupling.degree,
        decoupled=approach == "decoupled",
        pointwise=approach == "pointwise",
    )
    fitted = comp_model.fit_model_record(
        setup.view,
        Y,
        selection,
        approach,
        setup.models,
        decoupling,
        settings,
        **p.about,
        held_out_accuracy=accuracy,
        deployment={**deployment, "approach": approach, "algorithm": settings.algorithm},
        provenance={
            "citation": p.citation,
            "packages": {name: version(name) for name in ("thermaxis", "scikit-learn", "numpy")},
            "settings": sections,
        },
    )
    comp_model.validate_model(fitted, where=snakemake.output.model)
    write_text(json.dumps(fitted, indent=1) + "\n", snakemake.output.model)


run_script(main, snakemake)
