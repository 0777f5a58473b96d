import json

import pandas as pd

from thermaxis.cleaning.run import model_inputs
from thermaxis.config import DecouplingSettings, SelectionSettings
from thermaxis.errors import DataError
from thermaxis.method.folds import select_for_fold, selection_table, selection_to_dict
from thermaxis.pipeline.runner import run_script, write_csv, write_text


def main(snakemake):
    X, Y = model_inputs(
        pd.read_parquet(snakemake.input.errors), pd.read_parquet(snakemake.input.temperatures)
    )
    p = snakemake.params
    settings = SelectionSettings.from_section(p.selection)
    degree = DecouplingSettings.from_section(p.decoupling).degree
    fold = snakemake.wildcards.fold
    try:
        selection = select_for_fold(X, Y, fold, settings, degree, decoupled=p.decoupled)
    except DataError as exc:
        # The fold's training temperatures are what the message is about: name their file.
        if not str(exc).startswith(f"fold {fold}:"):
            raise
        raise DataError(f"{snakemake.input.temperatures}: {exc}") from None
    write_text(
        json.dumps(selection_to_dict(selection), indent=1, sort_keys=True) + "\n",
        snakemake.output.selection,
    )
    write_csv(selection_table(selection), snakemake.output.table, float_format="%.6f")


run_script(main, snakemake)
