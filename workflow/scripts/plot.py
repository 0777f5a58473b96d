"""One family of figures per job: each figure of the rule's table entries drawn from its
tables and saved (thermaxis.figures.family), over the job's threads."""

from thermaxis.figures.family import draw_family, family_workers
from thermaxis.pipeline.runner import run_script


def main(snakemake):
    figures = snakemake.params.figures
    # A bad-input test runs this script without Snakemake's threads: one process.
    workers = family_workers(getattr(snakemake, "threads", 1), len(figures))
    draw_family(figures, snakemake.params.stamp, snakemake.params.dpi, workers)


run_script(main, snakemake)
