import json
import logging

import pandas as pd

from thermaxis.cleaning.run import model_inputs
from thermaxis.config import DecouplingSettings, ModelSettings
from thermaxis.labels import sort_naturally
from thermaxis.method.folds import SORT_KEYS, evaluate_configuration, selection_from_dict
from thermaxis.pipeline.runner import run_script, write_csv


def main(snakemake):
    X, Y = model_inputs(
        pd.read_parquet(snakemake.input.errors),
        pd.read_parquet(snakemake.input.temperatures),
        signals=pd.read_parquet(snakemake.input.signals),
    )
    with open(snakemake.input.selection, encoding="utf-8") as fh:
        selection = selection_from_dict(json.load(fh))
    p = snakemake.params
    models = ModelSettings.from_section(p.models)
    degree = DecouplingSettings.from_section(p.decoupling).degree
    fold = snakemake.wildcards.fold
    results = []
    for approach in p.approaches:
        for algorithm in p.algorithms:
            logging.getLogger("thermaxis").info("fold %s: %s %s", fold, approach, algorithm)
            results.append(
                evaluate_configuration(X, Y, fold, approach, algorithm, selection, models, degree)
            )
    for name in ("metrics", "coefficients", "kb_predictions", "error_predictions", "fitting"):
        frame = pd.concat([getattr(r, name) for r in results], ignore_index=True)
        frame = sort_naturally(frame, SORT_KEYS[name])
        write_csv(frame, snakemake.output[name], float_format="%.6f")


run_script(main, snakemake)
