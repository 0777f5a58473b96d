"""Small summaries and Markdown renderings of the tables (no plotting, no models)."""

from __future__ import annotations

import pandas as pd

from thermaxis.dataset.reader import Dataset
from thermaxis.labels import sort_naturally

__all__ = [
    "AMBIENT_COLUMNS",
    "ambient_ranges",
    "dataset_summary",
    "data_statement",
]

AMBIENT_COLUMNS = ["run", "sensor", "ambient_min_c", "ambient_max_c"]


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
            f"Dataset `{dataset_name}`: SIMULATED data (thermal twin calibrated to the paper's fits and results), "
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


def ambient_ranges(
    sensor: str, runs: dict[str, tuple[pd.DataFrame, pd.DataFrame]]
) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Table 1's ambient range per run, and the ambient series every run logged (Fig. 3).

    ``runs`` maps a run to its cleaned series (``time``, ``elapsed_min`` and the sensor)
    and its measurement windows (``start``, ``end``); the range is over the measurements,
    from the first window's start to the last one's end.
    """
    rows, series_rows = [], []
    for run, (series, windows) in runs.items():
        during = series[
            (series["time"] >= windows["start"].min()) & (series["time"] <= windows["end"].max())
        ]
        rows.append((run, sensor, float(during[sensor].min()), float(during[sensor].max())))
        series_rows.append(
            pd.DataFrame(
                {"run": run, "elapsed_min": series["elapsed_min"], "temperature_c": series[sensor]}
            )
        )
    return pd.DataFrame(rows, columns=AMBIENT_COLUMNS), pd.concat(series_rows, ignore_index=True)
