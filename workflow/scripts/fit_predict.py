import json
import logging

import pandas as pd

from thermaxis.assemble import model_inputs
from thermaxis.experiment import evaluate_configuration, selection_from_dict, settings_from_config
from thermaxis.runner import run_script, write_csv


def main(snakemake):
    X, Y = model_inputs(pd.read_parquet(snakemake.input.errors), pd.read_parquet(snakemake.input.temperatures))
    with open(snakemake.input.selection, encoding="utf-8") as fh:
        selection = selection_from_dict(json.load(fh))
    p = snakemake.params
    selection_settings, model_settings = settings_from_config(
        {"selection": p.selection, "decoupling": p.decoupling, "models": p.models}
    )
    fold = snakemake.wildcards.fold
    results = []
    for approach in p.approaches:
        for algorithm in p.algorithms:
            logging.getLogger("thermaxis").info("fold %s: %s %s", fold, approach, algorithm)
            results.append(
                evaluate_configuration(
                    X, Y, fold, approach, algorithm, selection, model_settings, degree=selection_settings.degree
                )
            )
    order = {
        "metrics": ["fold", "approach", "algorithm", "target"],
        "coefficients": ["fold", "approach", "algorithm", "target", "position_mm", "temperature", "term"],
        "kb_predictions": ["fold", "approach", "algorithm", "target", "measurement"],
        "error_predictions": ["fold", "approach", "algorithm", "measurement", "position_mm"],
    }
    out = snakemake.output
    paths = {"metrics": out.metrics, "coefficients": out.coefficients, "kb_predictions": out.kb, "error_predictions": out.errors}
    for name, path in paths.items():
        frame = pd.concat([getattr(r, name) for r in results], ignore_index=True)
        write_csv(frame.sort_values(order[name], kind="stable", ignore_index=True), path, float_format="%.6f")


run_script(main, snakemake)
