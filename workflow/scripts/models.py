"""Every fold's sensitive points and models in one job: the selection on the fold's
training runs, each approach x algorithm fitted and its held-out run predicted, and the
folds' tables collected with their intervals (tables/*.csv)."""

import io
import json
import logging

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
from thermaxis.method.folds import (
    SORT_KEYS,
    evaluate_configuration,
    select_for_fold,
    selection_from_dict,
    selection_table,
    selection_to_dict,
)
from thermaxis.pipeline.runner import csv_text, run_script, write_texts
from thermaxis.statistics import measurement_sums, metric_intervals, with_intervals


def selection_of(X, Y, fold, p, where):
    """The fold's sensitive points as their JSON record."""
    settings = SelectionSettings.from_section(p.selection)
    degree = DecouplingSettings.from_section(p.decoupling).degree
    try:
        selection = select_for_fold(X, Y, fold, settings, degree, decoupled=p.decoupled)
    except DataError as exc:
        # The fold's training temperatures are what the message is about: name their file.
        if not str(exc).startswith(f"fold {fold}:"):
            raise
        raise DataError(f"{where}: {exc}") from None
    return selection


def fold_models(X, Y, fold, selection, p) -> dict[str, pd.DataFrame]:
    """Every approach x algorithm of one fold, its tables sorted."""
    models = ModelSettings.from_section(p.models)
    degree = DecouplingSettings.from_section(p.decoupling).degree
    results = []
    for approach in p.approaches:
        for algorithm in p.algorithms:
            logging.getLogger("thermaxis").info("fold %s: %s %s", fold, approach, algorithm)
            results.append(
                evaluate_configuration(X, Y, fold, approach, algorithm, selection, models, degree)
            )
    return {
        name: sort_naturally(
            pd.concat([getattr(r, name) for r in results], ignore_index=True), SORT_KEYS[name]
        )
        for name in p.tables
    }


def main(snakemake):
    p, inputs, output = snakemake.params, snakemake.input, snakemake.output
    errors = pd.read_parquet(inputs.errors)
    temperatures = pd.read_parquet(inputs.temperatures)
    # The selection reads the temperatures only; the models the signals too.
    X_select, Y = model_inputs(errors, temperatures)
    X, Y = model_inputs(errors, temperatures, signals=pd.read_parquet(inputs.signals))
    texts, tables = {}, {name: [] for name in SORT_KEYS}
    for i, fold in enumerate(p.folds):
        selection = selection_of(X_select, Y, fold, p, inputs.temperatures)
        record = json.dumps(selection_to_dict(selection), indent=1, sort_keys=True) + "\n"
        texts[output.selections[i]] = record
        texts[output.selection_tables[i]] = table = csv_text(
            selection_table(selection), float_format="%.6f"
        )
        tables["selection"].append(table)
        frames = fold_models(X, Y, fold, selection_from_dict(json.loads(record)), p)
        for name, frame in frames.items():
            texts[output[f"fold_{name}"][i]] = text = csv_text(frame, float_format="%.6f")
            tables[name].append(text)
    # The collected tables are what a reader of the folds' files gets back.
    frames = {
        name: sort_naturally(
            pd.concat([pd.read_csv(io.StringIO(t)) for t in tables[name]], ignore_index=True),
            keys,
        )
        for name, keys in SORT_KEYS.items()
    }
    sums = measurement_sums(frames["kb_predictions"], frames["error_predictions"])
    intervals = metric_intervals(sums, StatisticsSettings.from_section(p.statistics))
    frames["metrics"] = with_intervals(frames["metrics"], intervals)
    for name, frame in frames.items():
        texts[output[name]] = csv_text(frame, float_format="%.6f")
    write_texts(texts)


run_script(main, snakemake)
