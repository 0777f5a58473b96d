"""Collect the folds' compensation tables, each file with its header of signs, units and sources."""

import pandas as pd

from thermaxis.compensation.exports import file_header
from thermaxis.pipeline.runner import run_script, write_text

SORT = ["fold", "measurement"]


def main(snakemake):
    for name in snakemake.params.tables:
        frame = pd.concat(
            [pd.read_csv(p, keep_default_na=False, na_values=[""]) for p in snakemake.input[name]],
            ignore_index=True,
        )
        frame = frame.sort_values(SORT, kind="stable", ignore_index=True)
        body = frame.to_csv(index=False, float_format="%.10g", lineterminator="\n")
        write_text(file_header(name, snakemake.params.statement) + body, snakemake.output[name])


run_script(main, snakemake)
