"""Every run's cleaned tables assembled (the unzeroed errors and the temperatures of every
measurement), the cleaning's QC and events, the dataset summary, with an ambient sensor
Table 1's ambient ranges and series, and with more than one target position the slope k
and intercept b of every measurement (Table 5)."""

import pandas as pd

from thermaxis.cleaning.run import cleaning_events
from thermaxis.dataset.plausibility import check_same_targets
from thermaxis.dataset.reader import load_dataset
from thermaxis.dataset.summary import ambient_ranges, dataset_summary
from thermaxis.labels import sort_naturally
from thermaxis.method.decouple import decouple_table
from thermaxis.paper.table5 import table5_markdown
from thermaxis.pipeline.runner import csv_text, run_script, write_parquet, write_texts
from thermaxis.tables import read_table


def main(snakemake):
    p, inputs, output = snakemake.params, snakemake.input, snakemake.output

    def concat(paths, reader, keys):
        return sort_naturally(pd.concat([reader(p) for p in paths], ignore_index=True), keys)

    errors = concat(inputs.errors, pd.read_parquet, ["run", "measurement", "position_mm"])
    check_same_targets(errors, p.dataset)
    frames = {
        "errors": errors,
        "temperatures": concat(
            inputs.temperatures, pd.read_parquet, ["run", "measurement", "sensor"]
        ),
        "signals": concat(inputs.signals, pd.read_parquet, ["run", "measurement", "signal"]),
        "inputs": concat(inputs.inputs, pd.read_parquet, ["run", "measurement", "input"]),
    }
    qc = concat(inputs.qc, read_table, ["run", "sensor"])
    windows = {
        run: read_table(path, parse_dates=["start", "end"])
        for run, path in zip(p.runs, inputs.windows, strict=True)
    }
    summary = dataset_summary(load_dataset(p.dataset), {run: len(w) for run, w in windows.items()})
    texts = {
        output.qc: csv_text(qc),
        output.events: csv_text(cleaning_events(qc)),
        output.summary: csv_text(summary),
    }
    if p.ambient:
        series = {
            run: pd.read_parquet(path, columns=["time", "elapsed_min", p.ambient])
            for run, path in zip(p.runs, inputs.series, strict=True)
        }
        ranges, frames["ambient_series"] = ambient_ranges(
            p.ambient, {run: (series[run], windows[run]) for run in p.runs}
        )
        texts[output.ambient] = csv_text(ranges, float_format="%.3f")
    if p.decoupled:
        kb, polynomials = decouple_table(errors, degree=p.degree)
        texts[output.kb] = csv_text(kb, float_format="%.4f")
        texts[output.polynomials] = csv_text(polynomials, float_format="%.6g")
        texts[output.kb_markdown] = table5_markdown(
            kb, p.statement, paper_dir=p.paper_dir if p.paper else None
        )
    for name, frame in frames.items():
        write_parquet(frame, output[name])
    write_texts(texts)


run_script(main, snakemake)
