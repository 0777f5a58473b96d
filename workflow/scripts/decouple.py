import pandas as pd

from thermaxis.method.decouple import decouple_table
from thermaxis.paper.table5 import table5_markdown
from thermaxis.pipeline.runner import run_script, write_csv, write_text


def main(snakemake):
    errors = pd.read_parquet(snakemake.input.errors)
    kb, coefficients = decouple_table(errors, degree=snakemake.params.degree)
    write_csv(kb, snakemake.output.table, float_format="%.4f")
    write_csv(coefficients, snakemake.output.coefficients, float_format="%.6g")
    paper_dir = snakemake.params.paper_dir if snakemake.params.paper else None
    markdown = table5_markdown(kb, snakemake.params.statement, paper_dir=paper_dir)
    write_text(markdown, snakemake.output.markdown)


run_script(main, snakemake)
