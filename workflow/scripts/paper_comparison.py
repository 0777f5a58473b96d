import pandas as pd

from thermaxis.paper.audit import ReproducedTables, comparison_markdown, paper_comparison
from thermaxis.paper.equations import published_targets
from thermaxis.paper.faithfulness import faithfulness, faithfulness_markdown
from thermaxis.paper.published import published_values
from thermaxis.pipeline.runner import run_script, write_csv, write_text


def main(snakemake):
    i, p = snakemake.input, snakemake.params
    tables = ReproducedTables(
        runs=pd.read_csv(i.summary),
        ambient=pd.read_csv(i.ambient),
        # A single-position dataset has no decoupled k and b: the Table 5 items stay empty.
        kb=(
            pd.read_csv(i.kb[0])
            if i.kb
            else pd.DataFrame(columns=["run", "measurement", "k_um_per_m", "b_um"])
        ),
        metrics=pd.read_csv(i.metrics),
        coefficients=pd.read_csv(i.coefficients),
        sensitive_points=pd.read_csv(i.selection),
        error_predictions=pd.read_csv(i.predictions),
        errors=pd.read_parquet(i.errors),
        paper_fold=p.paper_fold,
    )
    comparison = paper_comparison(
        published_values(p.paper_dir), tables, p.dataset_name, p.simulated
    )
    write_csv(comparison, snakemake.output.csv, float_format="%.4f")
    write_text(
        comparison_markdown(comparison, p.dataset_name, p.simulated, p.paper_fold),
        snakemake.output.markdown,
    )
    faithful = faithfulness(
        comparison,
        tables.sensitive_points,
        pd.read_parquet(i.temperatures),
        tables.kb,
        published_targets(p.paper_dir),
        p.paper_fold,
    )
    write_csv(faithful, snakemake.output.faithfulness)
    write_text(faithfulness_markdown(faithful, p.statement), snakemake.output.faithfulness_markdown)


run_script(main, snakemake)
