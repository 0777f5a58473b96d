import pandas as pd

from thermaxis.dataset.reader import load_dataset
from thermaxis.dataset.summary import dataset_summary
from thermaxis.pipeline.runner import run_script, write_csv


def main(snakemake):
    dataset = load_dataset(snakemake.params.dataset)
    counts = {
        run: len(pd.read_csv(path))
        for run, path in zip(snakemake.params.runs, snakemake.input.windows, strict=False)
    }
    write_csv(dataset_summary(dataset, counts), snakemake.output.table)


run_script(main, snakemake)
