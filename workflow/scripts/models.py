"""Every fold's sensitive points and models in one job: the selection on the fold's
training runs, each approach x algorithm fitted and its held-out run predicted, and the
folds' tables collected with their intervals (tables/*.csv). The folds are spread over
the job's threads (thermaxis.pipeline.parallel)."""

import io
from functools import partial

import pandas as pd

from thermaxis.cleaning.run import model_inputs
from thermaxis.config import (
    DecouplingSettings,
    ModelSettings,
    SelectionSettings,
    StatisticsSettings,
)
from thermaxis.errors import DataError
from thermaxis.labels import sort_naturally
from thermaxis.method.folds import SORT_KEYS, fold_models, selection_table
from thermaxis.pipeline.parallel import fold_workers, map_folds
from thermaxis.pipeline.runner import csv_text, run_script, write_texts
from thermaxis.statistics import measurement_sums, metric_intervals, with_intervals
from thermaxis.tables import read_table


def main(snakemake):
    p, inputs, output = snakemake.params, snakemake.input, snakemake.output
    errors = pd.read_parquet(inputs.errors)
    temperatures = pd.read_parquet(inputs.temperatures)
    # The selection reads the temperatures only; the models the signals too.
    X_select, Y = model_inputs(errors, temperatures)
    X, Y = model_inputs(errors, temperatures, signals=pd.read_parquet(inputs.signals))
    one_fold = partial(
        fold_models,
        X_select=X_select,
        X=X,
        Y=Y,
        selection=SelectionSettings.from_section(p.selection),
        models=ModelSettings.from_section(p.models),
        degree=DecouplingSettings.from_section(p.decoupling).degree,
        decoupled=p.decoupled,
        approaches=p.approaches,
        algorithms=p.algorithms,
    )
    try:
        # A bad-input test runs this script without Snakemake's threads: one process.
        workers = fold_workers(getattr(snakemake, "threads", 1), len(p.folds), "models")
        folds = map_folds(one_fold, p.folds, workers)
    except DataError as exc:
        # A fold's training temperatures are what the message is about: name their file.
        if not str(exc).startswith("fold "):
            raise
        raise DataError(f"{inputs.temperatures}: {exc}") from None
    texts, tables = {}, {name: [] for name in SORT_KEYS}
    for i, (selection, record, frames) in enumerate(folds):
        texts[output.selections[i]] = record
        table = csv_text(selection_table(selection), float_format="%.6f")
        texts[output.selection_tables[i]] = table
        tables["selection"].append(table)
        for name, frame in frames.items():
            texts[output[f"fold_{name}"][i]] = text = csv_text(frame, float_format="%.6f")
            tables[name].append(text)
    # The collected tables are what a reader of the folds' files gets back.
    collected = {
        name: sort_naturally(
            pd.concat([read_table(io.StringIO(t)) for t in tables[name]], ignore_index=True),
            keys,
        )
        for name, keys in SORT_KEYS.items()
    }
    sums = measurement_sums(collected["kb_predictions"], collected["error_predictions"])
    intervals = metric_intervals(sums, StatisticsSettings.from_section(p.statistics))
    collected["metrics"] = with_intervals(collected["metrics"], intervals)
    for name, frame in collected.items():
        texts[output[name]] = csv_text(frame, float_format="%.6f")
    write_texts(texts)


run_script(main, snakemake)
