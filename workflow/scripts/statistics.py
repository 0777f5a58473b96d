"""Every comparison with its uncertainty: comparisons.csv and the paper's claims
(claims.csv, claims.md) from the held-out predictions, how often each sensor is chosen
when one of a fold's training runs is left out (selection_stability.csv) and, for a
dataset that reproduces the paper, every published value beside the reproduced one
(paper_comparison.csv) and the twin's faithfulness (faithfulness.csv)."""

import pandas as pd

from thermaxis.cleaning.run import model_inputs
from thermaxis.config import DecouplingSettings, SelectionSettings, StatisticsSettings
from thermaxis.errors import SelectionWarning
from thermaxis.paper.audit import ReproducedTables, comparison_markdown, paper_comparison
from thermaxis.paper.equations import published_targets
from thermaxis.paper.faithfulness import faithfulness, faithfulness_markdown
from thermaxis.paper.published import published_values
from thermaxis.pipeline.runner import csv_text, log_only, run_script, write_texts
from thermaxis.statistics import (
    claim_results,
    claims_markdown,
    claims_table,
    compare_models,
    compare_recommendation,
    comparison_table,
    measurement_sums,
    model_sums,
    selection_stability,
)
from thermaxis.tables import read_table


def audit_texts(inputs, p, output, errors, temperatures, error_predictions) -> dict:
    """paper_comparison and faithfulness (CSV and Markdown), from the reproduced tables."""
    tables = ReproducedTables(
        runs=read_table(inputs.summary),
        ambient=read_table(inputs.ambient[0]),
        # A single-position dataset has no decoupled k and b: the Table 5 items stay empty.
        kb=(
            read_table(inputs.kb[0])
            if inputs.kb
            else pd.DataFrame(columns=["run", "measurement", "k_um_per_m", "b_um"])
        ),
        metrics=read_table(inputs.metrics),
        coefficients=read_table(inputs.coefficients),
        sensitive_points=read_table(inputs.selection),
        error_predictions=error_predictions,
        errors=errors,
        paper_fold=p.paper_fold,
    )
    comparison = paper_comparison(
        published_values(p.paper_dir), tables, p.dataset_name, p.simulated
    )
    faithful = faithfulness(
        comparison,
        tables.sensitive_points,
        temperatures,
        tables.kb,
        published_targets(p.paper_dir),
        p.paper_fold,
    )
    return {
        output.paper_csv: csv_text(comparison, float_format="%.4f"),
        output.paper_markdown: comparison_markdown(
            comparison, p.dataset_name, p.simulated, p.paper_fold
        ),
        output.faithfulness: csv_text(faithful),
        output.faithfulness_markdown: faithfulness_markdown(faithful, p.statement),
    }


def main(snakemake):
    # The models job reports the selection's warnings; this one selects again on the same
    # folds, so its copies go to its log only.
    with log_only(SelectionWarning):
        p, inputs, output = snakemake.params, snakemake.input, snakemake.output
        settings = StatisticsSettings.from_section(p.statistics)
        selection = SelectionSettings.from_section(p.selection)
        error_predictions = read_table(inputs.error_predictions)
        sums = measurement_sums(read_table(inputs.kb_predictions), error_predictions)
        models = model_sums(sums)
        recommendation = compare_recommendation(read_table(inputs.recommendation), settings)
        comparisons = comparison_table(compare_models(models, settings), recommendation)
        errors = pd.read_parquet(inputs.errors)
        temperatures = pd.read_parquet(inputs.temperatures)
        X, Y = model_inputs(errors, temperatures)
        claims = claims_table(
            p.dataset_name,
            claim_results(models, X, Y, errors, p.folds, selection, settings),
            settings,
        )
        degree = DecouplingSettings.from_section(p.decoupling).degree if p.decoupled else None
        stability = selection_stability(
            X, Y, p.folds, selection, degree, p.decoupled, settings.stability_subsets
        )
        texts = {
            output.comparisons: csv_text(comparisons, float_format="%.6f"),
            output.claims: csv_text(claims, float_format="%.6f"),
            output.markdown: claims_markdown(claims, p.statement, settings),
            output.stability: csv_text(stability, float_format="%.6f"),
        }
        if p.paper:
            texts.update(audit_texts(inputs, p, output, errors, temperatures, error_predictions))
        write_texts(texts)


run_script(main, snakemake)
