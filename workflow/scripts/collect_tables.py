import pandas as pd

from thermaxis.labels import sort_naturally
from thermaxis.method.folds import SORT_KEYS
from thermaxis.pipeline.runner import run_script, write_csv


def main(snakemake):
    for name, keys in SORT_KEYS.items():
        frames = [pd.read_csv(p) for p in snakemake.input[name]]
        frame = sort_naturally(pd.concat(frames, ignore_index=True), keys)
        write_csv(frame, snakemake.output[name], float_format="%.6f")


run_script(main, snakemake)
