"""comparisons.csv and the paper's claims (claims.csv, claims.md) from the held-out predictions."""

import pandas as pd

from thermaxis.cleaning.run import model_inputs
from thermaxis.config import SelectionSettings, StatisticsSettings
from thermaxis.pipeline.runner import run_script, write_csv, write_text
from thermaxis.statistics import (
    claim_results,
    claims_markdown,
    claims_table,
    compare_models,
    compare_recommendation,
    comparison_table,
    measurement_sums,
    model_sums,
)


def main(snakemake):
    p = snakemake.params
    settings = StatisticsSettings.from_section(p.statistics)
    sums = measurement_sums(
        pd.read_csv(snakemake.input.kb_predictions), pd.read_csv(snakemake.input.error_predictions)
    )
    models = model_sums(sums)
    recommendation = compare_recommendation(pd.read_csv(snakemake.input.recommendation), settings)
    comparisons = comparison_table(compare_models(models, settings), recommendation)
    errors = pd.read_parquet(snakemake.input.errors)
    X, Y = model_inputs(errors, pd.read_parquet(snakemake.input.temperatures))
    results = claim_results(
        models, X, Y, errors, p.folds, SelectionSettings.from_section(p.selection), settings
    )
    claims = claims_table(p.dataset_name, results, settings)
    write_csv(comparisons, snakemake.output.comparisons, float_format="%.6f")
    write_csv(claims, snakemake.output.claims, float_format="%.6f")
    write_text(claims_markdown(claims, p.statement, settings), snakemake.output.markdown)


run_script(main, snakemake)
