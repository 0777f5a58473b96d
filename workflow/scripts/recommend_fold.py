"""One outer fold of the recommendation: every candidate's inner scores and its held-out error."""

import logging

import pandas as pd

from thermaxis.cleaning.run import model_inputs
from thermaxis.config import DecouplingSettings, RecommendSettings
from thermaxis.method.recommend import configured_candidates, fold_scores
from thermaxis.pipeline.runner import run_script, write_csv


def main(snakemake):
    p = snakemake.params
    recommend = RecommendSettings.from_section(p.recommend)
    X, Y = model_inputs(
        pd.read_parquet(snakemake.input.errors),
        pd.read_parquet(snakemake.input.temperatures),
        signals=pd.read_parquet(snakemake.input.signals),
        inputs=pd.read_parquet(snakemake.input.inputs),
    )
    candidates = configured_candidates(p)
    log = logging.getLogger("thermaxis")
    scores = fold_scores(
        X,
        Y,
        candidates,
        snakemake.wildcards.fold,
        DecouplingSettings.from_section(p.decoupling).degree,
        recommend.max_loco_runs,
        recommend.group_folds,
        p.signals,
        progress=log.info,
    )
    write_csv(scores, snakemake.output.scores, float_format="%.10g")


run_script(main, snakemake)
