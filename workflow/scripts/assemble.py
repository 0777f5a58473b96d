import pandas as pd

from thermaxis.cleaning.run import cleaning_events
from thermaxis.dataset.plausibility import check_same_targets
from thermaxis.labels import sort_naturally
from thermaxis.pipeline.runner import run_script, write_csv, write_parquet


def main(snakemake):
    def concat(paths, reader):
        return pd.concat([reader(p) for p in paths], ignore_index=True)

    errors = concat(snakemake.input.errors, pd.read_parquet)
    check_same_targets(errors, snakemake.params.dataset)
    temperatures = concat(snakemake.input.temperatures, pd.read_parquet)
    signals = concat(snakemake.input.signals, pd.read_parquet)
    qc = concat(snakemake.input.qc, pd.read_csv)
    inputs = concat(snakemake.input.inputs, pd.read_parquet)
    write_parquet(sort_naturally(inputs, ["run", "measurement", "input"]), snakemake.output.inputs)
    write_parquet(
        sort_naturally(errors, ["run", "measurement", "position_mm"]), snakemake.output.errors
    )
    write_parquet(
        sort_naturally(temperatures, ["run", "measurement", "sensor"]),
        snakemake.output.temperatures,
    )
    write_parquet(
        sort_naturally(signals, ["run", "measurement", "signal"]), snakemake.output.signals
    )
    qc = sort_naturally(qc, ["run", "sensor"])
    write_csv(qc, snakemake.output.qc)
    write_csv(cleaning_events(qc), snakemake.output.events)


run_script(main, snakemake)
