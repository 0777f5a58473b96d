"""The recommendation in one job: every outer fold's candidate scores (inner
leave-one-condition-out on its training runs, and the held-out run), the super learner's
weights per fold and on all runs, and the tables."""

import io
import json
import logging

import pandas as pd

from thermaxis.cleaning.run import model_inputs
from thermaxis.config import DecouplingSettings, RecommendSettings, StatisticsSettings
from thermaxis.errors import SelectionWarning
from thermaxis.method.candidates import candidate_record, candidate_table, configured_candidates
from thermaxis.method.folds import run_groups
from thermaxis.method.nested import collect, fold_scores
from thermaxis.pipeline.parallel import fold_workers, map_folds
from thermaxis.pipeline.runner import csv_text, log_only, run_script, write_texts
from thermaxis.reports.recommendation import recommendation_markdown
from thermaxis.statistics import fold_means
from thermaxis.tables import read_table


def choice_record(result, candidates) -> dict:
    """What the compensation deploys (compensation.model: recommended | paper | <candidate>):
    the super learner's members with their final and per-fold weights, and every candidate."""
    c = result.combination
    return {
        "final": {"name": result.final, "weights": dict(zip(c.members, c.final, strict=True))},
        "folds": {fold: dict(zip(c.members, w, strict=True)) for fold, w in c.folds.items()},
        "candidates": {c.name: candidate_record(c) for c in candidates},
    }


def main(snakemake):
    # The models job reports the selection's warnings; this one selects again on the same
    # folds, so its copies go to its log only.
    with log_only(SelectionWarning):
        p, inputs, output = snakemake.params, snakemake.input, snakemake.output
        recommend = RecommendSettings.from_section(p.recommend)
        X, Y = model_inputs(
            pd.read_parquet(inputs.errors),
            pd.read_parquet(inputs.temperatures),
            signals=pd.read_parquet(inputs.signals),
            inputs=pd.read_parquet(inputs.inputs),
        )
        candidates = configured_candidates(p)
        degree = DecouplingSettings.from_section(p.decoupling).degree
        log = logging.getLogger("thermaxis")
        # Above recommend.max_loco_runs runs the outer loop holds out groups of runs.
        outer = run_groups(p.folds, recommend.max_loco_runs, recommend.group_folds)
        # A bad-input test runs this script without Snakemake's threads: one process. The
        # work grows with the runs, however they are grouped.
        workers = fold_workers(getattr(snakemake, "threads", 1), len(p.folds), "recommend")
        by_fold, combination = fold_scores(
            X,
            Y,
            candidates,
            outer,
            degree=degree,
            signals=p.signals,
            # Workers start without this job's logging: only one process says its progress.
            progress=log.info if workers == 1 else None,
            map_sets=lambda one_set, sets: map_folds(one_set, sets, min(workers, len(sets))),
            members=recommend.combine,
            weighting=recommend.weighting,
        )
        by_run = pd.concat(by_fold, ignore_index=True)
        texts = {
            path: csv_text(
                by_run.loc[by_run["fold"] == fold].reset_index(drop=True), float_format="%.10g"
            )
            for path, fold in zip(output.scores, p.folds, strict=True)
        }
        # The choice reads the scores as a reader of the folds' files gets them back.
        scores = pd.concat(
            [read_table(io.StringIO(texts[path])) for path in output.scores], ignore_index=True
        )
        names = [c.name for c in candidates]
        result = collect(scores, names, "paper", combination)
        means = fold_means(result.loco, StatisticsSettings.from_section(p.statistics))
        table = candidate_table(candidates).join(means, on="candidate")
        record = choice_record(result, candidates)
        texts.update(
            {
                output.table: csv_text(result.folds, float_format="%.6f"),
                output.markdown: recommendation_markdown(result, p.statement),
                output.candidates: csv_text(table, float_format="%.6f"),
                output.choice: json.dumps(record, indent=1, sort_keys=True) + "\n",
            }
        )
        write_texts(texts)


run_script(main, snakemake)
