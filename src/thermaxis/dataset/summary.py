"""Small summaries and Markdown renderings of the tables (no plotting, no models)."""

from __future__ import annotations

import pandas as pd

from thermaxis.dataset.reader import Dataset
from thermaxis.labels import sort_naturally

__all__ = [
    "dataset_summary",
    "data_statement",
]


def data_statement(
    dataset_name: str, simulated: bool, citation: str = "", reproduces_paper: bool = True
) -> str:
    """The sentence every report and caption carries about where the numbers come from.

    Only a simulated dataset that reproduces the paper (``reproduces: xu2023``, the
    twin) is said to be calibrated to it; any other simulated dataset is named as
    simulated with its own source.
    """
    source = f" Source: {citation.strip()}" if citation.strip() else ""
    if simulated and reproduces_paper:
        return (
            f"Dataset `{dataset_name}`: SIMULATED data (thermal twin calibrated to the paper's Table 5), "
            "not the paper's measurements."
        )
    if simulated:
        return f"Dataset `{dataset_name}`: SIMULATED data, not measurements of a machine.{source}"
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
