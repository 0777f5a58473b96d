import pandas as pd

from thermaxis.config import StatisticsSettings
from thermaxis.labels import sort_naturally
from thermaxis.method.folds import SORT_KEYS
from thermaxis.pipeline.runner import run_script, write_csv
from thermaxis.statistics import measurement_sums, metric_intervals, with_intervals


def main(snakemake):
    frames = {
        name: sort_naturally(
            pd.concat([pd.read_csv(p) for p in snakemake.input[name]], ignore_index=True), keys
        )
        for name, keys in SORT_KEYS.items()
    }
    sums = measurement_sums(frames["kb_predictions"], frames["error_predictions"])
    intervals = metric_intervals(sums, StatisticsSettings.from_section(snakemake.params.statistics))
    frames["metrics"] = with_intervals(frames["metrics"], intervals)
    for name, frame in frames.items():
        write_csv(frame, snakemake.output[name], float_format="%.6f")


run_script(main, snakemake)
