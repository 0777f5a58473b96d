import pandas as pd

from thermaxis.pipeline.runner import run_script, write_csv, write_parquet


def main(snakemake):
    """Table 1's ambient range per run, and the ambient series every run logged (Fig. 3)."""
    sensor = snakemake.params.sensor
    rows, series_rows = [], []
    for run, series_path, windows_path in zip(
        snakemake.params.runs, snakemake.input.series, snakemake.input.windows, strict=False
    ):
        series = pd.read_parquet(series_path, columns=["time", "elapsed_min", sensor])
        windows = pd.read_csv(windows_path, parse_dates=["start", "end"])
        during = series[
            (series["time"] >= windows["start"].min()) & (series["time"] <= windows["end"].max())
        ]
        rows.append((run, sensor, float(during[sensor].min()), float(during[sensor].max())))
        series_rows.append(
            pd.DataFrame(
                {"run": run, "elapsed_min": series["elapsed_min"], "temperature_c": series[sensor]}
            )
        )
    ranges = pd.DataFrame(rows, columns=["run", "sensor", "ambient_min_c", "ambient_max_c"])
    write_csv(ranges, snakemake.output.table, float_format="%.3f")
    write_parquet(pd.concat(series_rows, ignore_index=True), snakemake.output.series)


run_script(main, snakemake)
