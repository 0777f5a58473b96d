"""The values published in Xu et al. (tables, Eq. 8-9, numbers in the text), as data.

The CSV files under ``thermaxis/paper/values/`` are hand transcriptions of the paper (see
``thermaxis/paper/values/README.md``).  This module only reads them: :func:`load_table` returns one
file as a typed DataFrame, and :func:`published_values` flattens every published number
into one long table with a stable key per number, so that the audit stage can join the
reproduction against the paper by ``item``.
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd

__all__ = [
    "PAPER_DIR",
    "TABLE_NAMES",
    "PUBLISHED_COLUMNS",
    "load_table",
    "published_values",
]

PAPER_DIR = Path(__file__).resolve().parent / "values"

# File stem -> {column: dtype}.  The dtypes double as the expected header, so a file
# edited by hand with a renamed or missing column fails loudly instead of joining
# silently to nothing in the audit.
_SCHEMAS: dict[str, dict[str, str]] = {
    "table1_conditions": {
        "experiment": "int64",
        "run": "str",
        "feed_mm_min": "float64",
        "measurements": "int64",
        "ambient_min_c": "float64",
        "ambient_max_c": "float64",
    },
    "table2_sensors": {
        "sensor": "str",
        "location": "str",
        "acquisition": "str",
        "location_zh": "str",
    },
    "table3_pointwise_sensitive_points": {"position_mm": "int64", "sensor": "str"},
    "prediction_metrics": {
        "table": "int64",
        "approach": "str",
        "algorithm": "str",
        "target": "str",
        "unit": "str",
        "rmse": "float64",
        "max_abs": "float64",
        "mae": "float64",
    },
    "residual_ranges": {
        "table": "int64",
        "figure": "int64",
        "approach": "str",
        "algorithm": "str",
        "target": "str",
        "unit": "str",
        "residual_min": "float64",
        "residual_max": "float64",
    },
    "table5_slope_intercept": {
        "run": "str",
        "measurement": "int64",
        "k_um_per_m": "float64",
        "b_um": "float64",
    },
    "table6_kb_sensitive_points": {
        "target": "str",
        "cluster": "int64",
        "sensor": "str",
        "selected": "bool",
    },
    "eq8_pointwise_mlr": {
        "equation_row": "int64",
        "position_mm": "int64",
        "term": "str",
        "temperature": "str",
        "unit": "str",
        "value": "float64",
    },
    "eq9_decoupled_mlr": {
        "target": "str",
        "term": "str",
        "temperature": "str",
        "unit": "str",
        "value": "float64",
    },
    "text_values": {
        "section": "str",
        "quantity": "str",
        "approach": "str",
        "algorithm": "str",
        "target": "str",
        "run": "str",
        "position_mm": "Int64",
        "unit": "str",
        "value": "float64",
    },
}

TABLE_NAMES: tuple[str, ...] = tuple(_SCHEMAS)

PUBLISHED_COLUMNS: tuple[str, ...] = (
    "item",
    "table",
    "approach",
    "algorithm",
    "target",
    "run",
    "measurement",
    "position_mm",
    "term",
    "quantity",
    "value",
    "unit",
)

_METRICS = ("rmse", "max_abs", "mae")
_DIMENSIONLESS = "1"


def _resolve_name(name: str) -> str:
    """Accept a file stem, a file name, or a short alias such as ``table5`` / ``eq9``."""
    stem = name.removesuffix(".csv")
    if stem in _SCHEMAS:
        return stem
    matches = [s for s in _SCHEMAS if s.split("_")[0] == stem]
    if len(matches) == 1:
        return matches[0]
    raise ValueError(f"unknown paper table {name!r}; expected one of {', '.join(TABLE_NAMES)}")


def load_table(name: str, paper_dir: str | Path | None = None) -> pd.DataFrame:
    """Read one transcribed table of the paper.

    Parameters
    ----------
    name : str
        File stem (``"table5_slope_intercept"``), file name, or the short alias before
        the first underscore (``"table5"``, ``"eq9"``; Tables 4, 7 and 8 live together in
        ``"prediction_metrics"``).
    paper_dir : str or Path, optional
        Folder holding the CSV files; defaults to :data:`PAPER_DIR`.

    Returns
    -------
    pandas.DataFrame
        The file's rows in file order, with the columns and dtypes of its schema.

    Raises
    ------
    ValueError
        If the name is unknown or the file's header differs from the expected columns.
    """
    stem = _resolve_name(name)
    schema = _SCHEMAS[stem]
    path = Path(paper_dir if paper_dir is not None else PAPER_DIR) / f"{stem}.csv"
    # Read everything as text first so that the header check sees the file as written
    # and "T10" or "E1" can never be coerced into something else.
    raw = pd.read_csv(path, dtype=str, keep_default_na=False)
    if list(raw.columns) != list(schema):
        raise ValueError(
            f"{path.name}: columns {list(raw.columns)} do not match the expected {list(schema)}"
        )
    return pd.DataFrame(
        {col: _convert(raw[col], dtype, path.name) for col, dtype in schema.items()}
    )


def _convert(column: pd.Series, dtype: str, file_name: str) -> pd.Series:
    if dtype == "str":
        # An empty cell means "does not apply" (e.g. no algorithm for a measured value).
        return column.replace("", None).astype("str")
    if dtype == "bool":
        lowered = column.str.lower()
        if not lowered.isin(["true", "false"]).all():
            raise ValueError(f"{file_name}: column {column.name!r} must hold only true/false")
        return lowered.eq("true")
    if dtype == "Int64":
        return pd.to_numeric(column.replace("", None)).astype("Int64")
    return pd.to_numeric(column).astype(dtype)


def _row(item: str, table: str, quantity: str, value: float, unit: str, **keys) -> dict:
    return {
        "item": item,
        "table": table,
        "quantity": quantity,
        "value": float(value),
        "unit": unit,
        **keys,
    }


def _table1_rows(df: pd.DataFrame) -> list[dict]:
    rows = []
    for r in df.itertuples(index=False):
        for quantity, value, unit in (
            ("feed", r.feed_mm_min, "mm/min"),
            ("measurements", r.measurements, "1"),
            ("ambient_min", r.ambient_min_c, "degC"),
            ("ambient_max", r.ambient_max_c, "degC"),
        ):
            rows.append(
                _row(f"table1/{r.run}/{quantity}", "table1", quantity, value, unit, run=r.run)
            )
    return rows


def _table3_rows(df: pd.DataFrame) -> list[dict]:
    return [
        _row(
            f"table3/{r.position_mm}mm/{r.sensor}",
            "table3",
            "sensitive_point",
            1,
            _DIMENSIONLESS,
            approach="pointwise",
            target="error",
            position_mm=r.position_mm,
            term=r.sensor,
        )
        for r in df.itertuples(index=False)
    ]


def _metric_rows(df: pd.DataFrame) -> list[dict]:
    rows = []
    for r in df.itertuples(index=False):
        table = f"table{r.table}"
        for metric in _METRICS:
            rows.append(
                _row(
                    f"{table}/{r.target}/{metric}",
                    table,
                    metric,
                    getattr(r, metric),
                    r.unit,
                    approach=r.approach,
                    algorithm=r.algorithm,
                    target=r.target,
                    run="E4",
                )
            )
    return rows


def _table5_rows(df: pd.DataFrame) -> list[dict]:
    rows = []
    for r in df.itertuples(index=False):
        for target, value, unit in (("k", r.k_um_per_m, "um/m"), ("b", r.b_um, "um")):
            rows.append(
                _row(
                    f"table5/{r.run}/m{r.measurement}/{target}",
                    "table5",
                    target,
                    value,
                    unit,
                    approach="decoupled",
                    target=target,
                    run=r.run,
                    measurement=r.measurement,
                )
            )
    return rows


def _table6_rows(df: pd.DataFrame) -> list[dict]:
    rows = []
    for r in df.itertuples(index=False):
        prefix = f"table6/{r.target}/{r.sensor}"
        keys = {"approach": "decoupled", "target": r.target, "term": r.sensor}
        rows.append(
            _row(f"{prefix}/cluster", "table6", "cluster", r.cluster, _DIMENSIONLESS, **keys)
        )
        if r.selected:
            rows.append(
                _row(
                    f"{prefix}/sensitive_point",
                    "table6",
                    "sensitive_point",
                    1,
                    _DIMENSIONLESS,
                    **keys,
                )
            )
    return rows


def _eq8_rows(df: pd.DataFrame) -> list[dict]:
    return [
        _row(
            f"eq8/dx{r.equation_row}/{r.term}",
            "eq8",
            "coefficient",
            r.value,
            r.unit,
            approach="pointwise",
            algorithm="mlr",
            target="error",
            position_mm=r.position_mm,
            term=r.term,
        )
        for r in df.itertuples(index=False)
    ]


def _eq9_rows(df: pd.DataFrame) -> list[dict]:
    return [
        _row(
            f"eq9/{r.target}/{r.term}",
            "eq9",
            "coefficient",
            r.value,
            r.unit,
            approach="decoupled",
            algorithm="mlr",
            target=r.target,
            term=r.term,
        )
        for r in df.itertuples(index=False)
    ]


def _residual_range_rows(df: pd.DataFrame) -> list[dict]:
    rows = []
    for r in df.itertuples(index=False):
        for quantity in ("residual_min", "residual_max"):
            rows.append(
                _row(
                    f"text/{_model_key(r.approach, r.algorithm)}/{r.target}/{quantity}",
                    "text",
                    quantity,
                    getattr(r, quantity),
                    r.unit,
                    approach=r.approach,
                    algorithm=r.algorithm,
                    target=r.target,
                    run="E4",
                )
            )
    return rows


def _model_key(approach: str, algorithm) -> str:
    return approach if pd.isna(algorithm) else f"{approach}_{algorithm}"


def _text_rows(df: pd.DataFrame) -> list[dict]:
    rows = []
    for r in df.itertuples(index=False):
        position = None if pd.isna(r.position_mm) else int(r.position_mm)
        where = "" if position is None else f"{position}mm/"
        rows.append(
            _row(
                f"text/{_model_key(r.approach, r.algorithm)}/{r.target}/{where}{r.quantity}",
                "text",
                r.quantity,
                r.value,
                r.unit,
                approach=r.approach,
                algorithm=r.algorithm,
                target=r.target,
                run=r.run,
                position_mm=position,
            )
        )
    return rows


def published_values(paper_dir: str | Path | None = None) -> pd.DataFrame:
    """Every number the paper publishes in Tables 1, 3-8, Eq. 8-9 and the text, one per row.

    Encoding (``item`` is the join key; the other columns describe it):

    * Tables 1, 4, 5, 7, 8, Eq. 8, Eq. 9 and text numbers: ``value`` is the number as printed.
      Eq. 8 and Eq. 9 have ``quantity="coefficient"`` with ``term`` "const" or a sensor id;
      Eq. 8 and the b-part of Eq. 9 use temperatures relative to the run start, the
      k-part absolute temperatures (see ``load_table("eq9")["temperature"]``).
    * Tables 3 and 6, sensor sets: ``quantity="sensitive_point"`` with ``value=1`` for every
      sensitive point (sensor in ``term``); Table 6 also has ``quantity="cluster"`` for every
      clustered sensor with ``value`` the cluster number, clusters numbered by their
      lowest-numbered sensor (which is also the printed order).  Sensors a table does not
      list have no row (T7 is absent from the k clustering as printed).

    Parameters
    ----------
    paper_dir : str or Path, optional
        Folder holding the CSV files; defaults to :data:`PAPER_DIR`.

    Returns
    -------
    pandas.DataFrame
        Columns :data:`PUBLISHED_COLUMNS`; rows in paper order (Table 1, 3, 4, 5, 6, 7, 8,
        Eq. 8, Eq. 9, text), each table in its file's sorted order.  ``run``,
        ``measurement``, ``position_mm``, ``term`` etc. are missing where they do not apply.

    Raises
    ------
    ValueError
        If a file does not match its schema or two numbers would share one ``item``.
    """
    metrics = load_table("prediction_metrics", paper_dir)
    rows = (
        _table1_rows(load_table("table1", paper_dir))
        + _table3_rows(load_table("table3", paper_dir))
        + _metric_rows(metrics[metrics["table"] == 4])
        + _table5_rows(load_table("table5", paper_dir))
        + _table6_rows(load_table("table6", paper_dir))
        + _metric_rows(metrics[metrics["table"] > 4])
        + _eq8_rows(load_table("eq8", paper_dir))
        + _eq9_rows(load_table("eq9", paper_dir))
        + _residual_range_rows(load_table("residual_ranges", paper_dir))
        + _text_rows(load_table("text_values", paper_dir))
    )
    out = pd.DataFrame(rows).reindex(columns=list(PUBLISHED_COLUMNS))
    duplicated = out["item"][out["item"].duplicated()]
    if not duplicated.empty:
        raise ValueError(
            f"published values: item keys must be unique, repeated: {sorted(set(duplicated))}"
        )
    return _typed(out)


def _typed(out: pd.DataFrame) -> pd.DataFrame:
    """Whole numbers as nullable integers, labels as text, whatever rows gave them."""
    for col in ("measurement", "position_mm"):
        out[col] = out[col].astype("Int64")
    for col in (
        "item",
        "table",
        "approach",
        "algorithm",
        "target",
        "run",
        "term",
        "quantity",
        "unit",
    ):
        out[col] = out[col].astype("str")
    return out
