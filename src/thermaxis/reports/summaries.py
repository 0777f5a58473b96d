"""Data summaries the report notebooks show: cleaning repairs, temperature and error overviews, the audit."""

from __future__ import annotations

import pandas as pd

from thermaxis.cleaning.temperatures import QC_COLUMNS
from thermaxis.labels import sort_naturally
from thermaxis.reports.html import table_html

__all__ = [
    "audit_summary",
    "audit_html",
    "cleaning_repairs",
    "temperature_overview",
    "error_overview",
    "fitting_summary",
]


# --------------------------------------------------------------------------- overviews

# The QC table's counts of repaired samples: every n_ column but the raw count.
_REPAIR_COLUMNS = tuple(c for c in QC_COLUMNS if c.startswith("n_") and c != "n_raw")


def cleaning_repairs(qc: pd.DataFrame) -> pd.DataFrame:
    """The rows of a cleaning QC table where something was repaired, with their total.

    Parameters
    ----------
    qc : pandas.DataFrame
        ``tables/cleaning_qc.csv`` (one row per run and sensor).

    Returns
    -------
    pandas.DataFrame
        run, sensor, source, the repair counts and ``repaired`` (their sum), only rows
        with ``repaired > 0``, sorted by run and sensor.
    """
    missing = [c for c in ("run", "sensor", "source", *_REPAIR_COLUMNS) if c not in qc.columns]
    if missing:
        raise ValueError(
            f"cleaning QC table lacks column(s) {', '.join(missing)}; expected the columns of tables/cleaning_qc.csv"
        )
    table = qc[["run", "sensor", "source", *_REPAIR_COLUMNS]].copy()
    table["repaired"] = table[list(_REPAIR_COLUMNS)].sum(axis=1)
    return sort_naturally(table[table["repaired"] > 0], ["run", "sensor"])


def temperature_overview(temperatures: pd.DataFrame) -> pd.DataFrame:
    """Per run and sensor: absolute temperature at the first and last measurement, range, largest rise.

    ``temperatures`` is ``assembled/temperatures.parquet`` (or a run's
    ``measurement_temperatures.parquet``): run, measurement, sensor, absolute_c, relative_c.
    """
    t = sort_naturally(temperatures, ["run", "sensor", "measurement"])
    grouped = t.groupby(["run", "sensor"], sort=True)
    return (
        pd.DataFrame(
            {
                "first_c": grouped["absolute_c"].first(),
                "last_c": grouped["absolute_c"].last(),
                "min_c": grouped["absolute_c"].min(),
                "max_c": grouped["absolute_c"].max(),
                "max_rise_c": grouped["relative_c"].max(),
            }
        )
        .reset_index()
        .pipe(sort_naturally, ["run", "sensor"])
    )


def error_overview(errors: pd.DataFrame) -> pd.DataFrame:
    """Per run: measurements, targets, range of the unzeroed error and of the re-zeroed error.

    ``errors`` is ``assembled/errors.parquet``: run, measurement, position_mm, error_um, rezeroed_um.
    """
    grouped = errors.groupby("run", sort=True)
    return pd.DataFrame(
        {
            "measurements": grouped["measurement"].nunique(),
            "positions": grouped["position_mm"].nunique(),
            "error_min_um": grouped["error_um"].min(),
            "error_max_um": grouped["error_um"].max(),
            "rezeroed_min_um": grouped["rezeroed_um"].min(),
            "rezeroed_max_um": grouped["rezeroed_um"].max(),
        }
    ).reset_index()


_AUDIT_COLUMNS = ["item", "quantity", "unit", "published", "reproduced", "difference", "note"]


def audit_summary(comparison: pd.DataFrame) -> pd.DataFrame:
    """Per table of the paper: how many numbers, how many reproduced, mean and largest |difference|.

    ``comparison`` is ``tables/paper_comparison.csv``.
    """
    table = comparison.assign(abs_difference=comparison["difference"].abs())
    grouped = table.groupby("table", sort=True)
    return pd.DataFrame(
        {
            "items": grouped["item"].size(),
            "reproduced": grouped["reproduced"].count(),
            "mean_abs_difference": grouped["abs_difference"].mean(),
            "max_abs_difference": grouped["abs_difference"].max(),
        }
    ).reset_index()


def audit_html(
    comparison: pd.DataFrame, *tables: str, caption: str | None = None, max_rows: int | None = None
) -> str:
    """The audit rows of some tables of the paper (``"table4"``, ``"eq9"``, ...): published beside reproduced."""
    rows = comparison[comparison["table"].isin(tables)][_AUDIT_COLUMNS]
    if rows.empty:
        return f'<p class="tx-note">The audit has no number of {", ".join(tables)}.</p>'
    return table_html(
        rows,
        "%.3f",
        caption=caption or f"Audit of {', '.join(tables)}: published and reproduced",
        max_rows=max_rows,
    )


def fitting_summary(fitting: pd.DataFrame) -> pd.DataFrame:
    """The model report's "How each model was fitted": one row per searched or subsampled model.

    ``fitting`` is a fold's ``models/<fold>/fitting.csv`` (one row per regression: target,
    position, inner search, chosen parameters, training rows, rows fitted). Regressions of
    one model that were fitted alike (the positions of a point-by-point model) share a row;
    its ``regressions`` column counts them. Models fitted once on every row are left out.
    """
    columns = ["approach", "algorithm", "inner_search", "chosen", "training_rows", "rows_fitted"]
    frame = fitting.assign(
        inner_search=fitting["inner_search"].fillna(""), chosen=fitting["chosen"].fillna("")
    )
    noted = frame[(frame["inner_search"] != "") | (frame["rows_fitted"] < frame["training_rows"])]
    if noted.empty:
        return pd.DataFrame(columns=[*columns, "regressions"])
    grouped = noted.groupby(columns, sort=False, dropna=False)
    return grouped.size().rename("regressions").reset_index()
