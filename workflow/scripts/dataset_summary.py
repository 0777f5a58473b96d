from thermaxis.io import load_dataset
from thermaxis.runner import run_script, write_csv
from thermaxis.summary import dataset_summary


def main(snakemake):
    dataset = load_dataset(snakemake.params.dataset)
    write_csv(dataset_summary(dataset), snakemake.output.table)


run_script(main, snakemake)
