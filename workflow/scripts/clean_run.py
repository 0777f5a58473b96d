import logging

from thermaxis.cleaning.run import clean_and_assemble_run, derived_inputs
from thermaxis.config import CleaningSettings
from thermaxis.dataset.plausibility import check_run_plausibility
from thermaxis.dataset.reader import load_dataset, read_run
from thermaxis.pipeline.runner import run_script, write_csv, write_parquet


def main(snakemake):
    cleaning = CleaningSettings.from_sections(
        snakemake.params.temperatures, snakemake.params.errors
    )
    dataset = load_dataset(snakemake.params.dataset)
    raw = read_run(dataset, snakemake.wildcards.run)
    log = logging.getLogger("thermaxis")
    # Before cleaning, which may stop on what these warnings explain (°F or kelvin readings).
    for note in check_run_plausibility(dataset, raw, cleaning):
        log.warning(note)
    tables = clean_and_assemble_run(dataset, raw, cleaning)
    for note in tables.notes:
        log.warning(note)
    out = snakemake.output
    write_parquet(tables.series, out.series)
    write_csv(tables.qc, out.qc)
    write_csv(tables.gaps, out.gaps)
    write_parquet(tables.errors, out.errors)
    write_parquet(tables.temperatures, out.temperatures)
    write_csv(tables.windows, out.windows)
    write_parquet(tables.signals, out.signals)
    write_parquet(tables.signal_series, out.signal_series)
    # The time-aware inputs of the recommendation's candidates (recommend.lags_min and the baseline's).
    write_parquet(derived_inputs(tables, snakemake.params.lags_min, []), out.inputs)


run_script(main, snakemake)
