"""Table 5 of the paper (slope and intercept of each measurement) as Markdown beside the reproduction."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from thermaxis.tables import markdown_table

__all__ = [
    "table5_markdown",
]


def table5_markdown(kb: pd.DataFrame, statement: str, paper_dir=None) -> str:
    """Table 5 as Markdown, under the data statement; ``paper_dir`` (a dataset that
    reproduces the paper) puts the paper's published k and b beside it."""
    lines = ["# Table 5: slope k and intercept b of every measurement", "", statement, ""]
    table = kb[["run", "measurement", "time_min", "k_um_per_m", "b_um", "r2", "rms_um"]].copy()
    paper_file = Path(paper_dir) / "table5_slope_intercept.csv" if paper_dir else None
    if paper_file is not None and paper_file.is_file():
        paper = pd.read_csv(paper_file).rename(columns={"k_um_per_m": "paper_k", "b_um": "paper_b"})
        table = table.merge(
            paper[["run", "measurement", "paper_k", "paper_b"]],
            on=["run", "measurement"],
            how="left",
        )
        table["diff_k"] = table["k_um_per_m"] - table["paper_k"]
        table["diff_b"] = table["b_um"] - table["paper_b"]
        lines.append(
            "The paper's Table 5 is shown beside this dataset's values ("
            f"RMS difference k {np.sqrt(np.nanmean(table['diff_k'] ** 2)):.2f} um/m, "
            f"b {np.sqrt(np.nanmean(table['diff_b'] ** 2)):.2f} um)."
        )
        lines.append("")
    lines.append(
        "k in um/m, b in um (at the first target), r2 and rms_um of the least-squares line."
    )
    lines.append("")
    lines.append(markdown_table(table, float_format="%.2f"))
    return "\n".join(lines)
