import pandas as pd

from thermaxis.runner import run_script, write_csv


def main(snakemake):
    sensor = snakemake.params.sensor
    rows = []
    for run, series_path, windows_path in zip(snakemake.params.runs, snakemake.input.series, snakemake.input.windows):
        series = pd.read_parquet(series_path)
        if sensor not in series.columns:
            raise ValueError(f"config ambient_sensor: {sensor!r} is not a sensor of run {run} (expected one of {', '.join(series.columns[2:])})")
        windows = pd.read_csv(windows_path, parse_dates=["start", "end"])
        during = series[(series["time"] >= windows["start"].min()) & (series["time"] <= windows["end"].max())]
        rows.append((run, sensor, float(during[sensor].min()), float(during[sensor].max())))
    write_csv(pd.DataFrame(rows, columns=["run", "sensor", "ambient_min_c", "ambient_max_c"]), snakemake.output.table, float_format="%.3f")


run_script(main, snakemake)
