"""The recommendation from every fold's scores: the choice per fold, the final one, the tables."""

import json

import pandas as pd

from thermaxis.config import RecommendSettings, StatisticsSettings
from thermaxis.method.recommend import (
    candidate_record,
    candidate_table,
    collect,
    configured_candidates,
    recommendation_markdown,
)
from thermaxis.pipeline.runner import run_script, write_csv, write_text
from thermaxis.statistics import fold_means


def main(snakemake):
    p = snakemake.params
    recommend = RecommendSettings.from_section(p.recommend)
    candidates = configured_candidates(p)
    scores = pd.concat([pd.read_csv(path) for path in snakemake.input.scores], ignore_index=True)
    result = collect(scores, [c.name for c in candidates], "paper", recommend.score)
    write_csv(result.folds, snakemake.output.table, float_format="%.6f")
    write_text(recommendation_markdown(result, p.statement), snakemake.output.markdown)
    means = fold_means(result.loco, StatisticsSettings.from_section(p.statistics))
    table = candidate_table(candidates).join(means, on="candidate")
    write_csv(table, snakemake.output.candidates, float_format="%.6f")
    by_name = {c.name: c for c in candidates}
    # What the compensation deploys (compensation.model: recommended | paper | <candidate>).
    record = {
        "final": candidate_record(by_name[result.final]),
        "paper": candidate_record(by_name["paper"]),
        "folds": {
            row.fold: candidate_record(by_name[row.chosen]) for row in result.folds.itertuples()
        },
        "score": result.score,
        "candidates": {c.name: candidate_record(c) for c in candidates},
    }
    write_text(json.dumps(record, indent=1, sort_keys=True) + "\n", snakemake.output.choice)


run_script(main, snakemake)
