"""Collect the folds' compensation tables, each file with its header of signs, units and sources."""

import json

import pandas as pd

from thermaxis.compensation.exports import file_header
from thermaxis.pipeline.runner import run_script, write_text

SORT = ["fold", "measurement"]


def main(snakemake):
    with open(snakemake.input.model, encoding="utf-8") as fh:
        deployment = json.load(fh)["deployment"]
    # Every export says in words which model it holds and whether it is recommended.
    statement = f"{snakemake.params.statement}\n# Deployment: {deployment['sentence']}"
    for name in snakemake.params.tables:
        frame = pd.concat(
            [pd.read_csv(p, keep_default_na=False, na_values=[""]) for p in snakemake.input[name]],
            ignore_index=True,
        )
        frame = frame.sort_values(SORT, kind="stable", ignore_index=True)
        body = frame.to_csv(index=False, float_format="%.10g", lineterminator="\n")
        write_text(file_header(name, statement) + body, snakemake.output[name])


run_script(main, snakemake)
