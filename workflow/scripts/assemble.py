import pandas as pd

from thermaxis.guard import check_same_targets
from thermaxis.runner import run_script, write_csv, write_parquet


def main(snakemake):
    def concat(paths, reader):
        return pd.concat([reader(p) for p in paths], ignore_index=True)

    errors = concat(snakemake.input.errors, pd.read_parquet)
    temperatures = concat(snakemake.input.temperatures, pd.read_parquet)
    qc = concat(snakemake.input.qc, pd.read_csv)
    check_same_targets(errors, snakemake.params.dataset)
    write_parquet(errors.sort_values(["run", "measurement", "position_mm"], ignore_index=True), snakemake.output.errors)
    write_parquet(
        temperatures.sort_values(["run", "measurement", "sensor"], ignore_index=True), snakemake.output.temperatures
    )
    write_csv(qc.sort_values(["run", "sensor"], ignore_index=True), snakemake.output.qc)


run_script(main, snakemake)
