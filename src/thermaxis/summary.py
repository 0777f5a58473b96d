"""Small summaries and Markdown renderings of the tables (no plotting, no models)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from .io import Dataset
from .formatting import markdown_table
from .naming import sort_naturally

__all__ = ["dataset_summary", "table5_markdown", "data_statement"]


def data_statement(dataset_name: str, simulated: bool, citation: str = "") -> str:
    """The sentence every report and caption carries about where the numbers come from."""
    if simulated:
        return (
            f"Dataset `{dataset_name}`: SIMULATED data (thermal twin calibrated to the paper's Table 5), "
            "not the paper's measurements."
        )
    source = f" Source: {citation.strip()}" if citation.strip() else ""
    return f"Dataset `{dataset_name}`: MEASURED data.{source}"


def dataset_summary(dataset: Dataset, n_measurements: dict[str, int]) -> pd.DataFrame:
    """One row per run: condition, operating descriptors, and how many measurements and sensors it has."""
    rows = []
    for _, run in dataset.runs.iterrows():
        rows.append(
            {
                "dataset": dataset.name,
                "provenance": dataset.meta["provenance"]["kind"],
                "run": run["run"],
                "condition": str(run["condition"]),
                **{column: float(run[column]) for column in dataset.descriptors},
                "n_measurements": int(n_measurements[run["run"]]),
                "n_sensors": len(dataset.sensors),
                "n_signals": len(dataset.signals),
                "n_sources": len(dataset.sources),
                "temperature_kind": dataset.temperature_kind,
                "description": run["description"],
            }
        )
    return sort_naturally(pd.DataFrame(rows), ["run"])


def table5_markdown(kb: pd.DataFrame, statement: str, paper_dir=None) -> str:
    """Table 5 as Markdown, under the data statement; ``paper_dir`` (a dataset that
    reproduces the paper) puts the paper's published k and b beside it."""
    lines = ["# Table 5: slope k and intercept b of every measurement", "", statement, ""]
    table = kb[["run", "measurement", "time_min", "k_um_per_m", "b_um", "r2", "rms_um"]].copy()
    paper_file = Path(paper_dir) / "table5_slope_intercept.csv" if paper_dir else None
    if paper_file is not None and paper_file.is_file():
        paper = pd.read_csv(paper_file).rename(columns={"k_um_per_m": "paper_k", "b_um": "paper_b"})
        table = table.merge(paper[["run", "measurement", "paper_k", "paper_b"]], on=["run", "measurement"], how="left")
        table["diff_k"] = table["k_um_per_m"] - table["paper_k"]
        table["diff_b"] = table["b_um"] - table["paper_b"]
        lines.append(
            "The paper's Table 5 is shown beside this dataset's values ("
            f"RMS difference k {np.sqrt(np.nanmean(table['diff_k'] ** 2)):.2f} um/m, "
            f"b {np.sqrt(np.nanmean(table['diff_b'] ** 2)):.2f} um)."
        )
        lines.append("")
    lines.append("k in um/m, b in um (at the first target), r2 and rms_um of the least-squares line.")
    lines.append("")
    lines.append(markdown_table(table, float_format="%.2f"))
    return "\n".join(lines)
