"""Held-out error across datasets: one row per dataset x approach x algorithm.

Each dataset's workflow run writes its metrics table (thermaxis.pipeline.paths.METRICS, one row
per fold x approach x algorithm x target, see :data:`thermaxis.method.metrics.METRICS_CSV_COLUMNS`).
This module reads the tables of the datasets it is asked for (by default every dataset
whose results are under ``results/``: each folder holding the workflow's
``provenance.json``, whichever command built it) and summarises the error curves'
held-out residuals (target ``error``) over the leave-one-condition-out folds:
mean RMSE, mean and worst max |residual|.  Whether a dataset is simulated comes from
its own ``dataset.yaml`` (found through ``provenance.json``), so the summary says so
for every row.

A dataset whose folder cannot be read (broken, or asked for by name before it was
built) is left out with a warning naming it; other folders under ``results/`` (a
user's own dataset run for one target, with no ``provenance.json`` yet, say) are not
looked at.

Command line (writes ``summary.csv``, ``summary.md`` and the figure table's ``heldout_error``
in every format, ``heldout_error.{png,pdf}`` by default, and the page across datasets,
``<results>/index.html``, which links each dataset's ``index.html``)::

    python -m thermaxis.reports.crossdataset --results results --out results/_datasets [--datasets NAME ...]
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Iterable, Mapping
from contextlib import ExitStack
from pathlib import Path

import numpy as np
import pandas as pd
import yaml

from thermaxis.config import StatisticsSettings, load_config, validate_config
from thermaxis.errors import DataError, shown
from thermaxis.figures import registry
from thermaxis.pipeline import paths
from thermaxis.statistics.resampling import fold_mean_interval
from thermaxis.tables import read_table

# The figure table's entry of the one figure this command draws.
FIGURE = registry.entry("heldout_error")

__all__ = [
    "SUMMARY_COLUMNS",
    "read_metrics",
    "dataset_kind",
    "summarise",
    "model_ranking",
    "to_markdown",
    "datasets_under",
    "main",
]

_METRICS_COLUMNS = ("fold", "approach", "algorithm", "target", "rmse", "max_abs")
SUMMARY_COLUMNS = (
    "dataset",
    "data",
    "approach",
    "algorithm",
    "n_folds",
    "mean_rmse_um",
    "mean_rmse_um_lo",
    "mean_rmse_um_hi",
    "mean_max_abs_um",
    "mean_max_abs_um_lo",
    "mean_max_abs_um_hi",
    "worst_max_abs_um",
)
_APPROACH_ORDER = ("decoupled", "pointwise")
_ALGORITHM_ORDER = ("mlr", "svr", "ridge", "pls", "gpr")


def read_metrics(path) -> pd.DataFrame:
    """One dataset's metrics table, checked for the columns the summary needs."""
    path = Path(path)
    try:
        frame = read_table(
            path, keep_default_na=False, na_values=[""]
        )  # "n/a" is an error, not a gap
    except (OSError, pd.errors.ParserError, pd.errors.EmptyDataError) as exc:
        raise DataError(f"{path}: cannot be read as CSV ({str(exc).splitlines()[0]})") from exc
    missing = [c for c in _METRICS_COLUMNS if c not in frame.columns]
    if missing:
        raise DataError(
            f"{path}: column {missing[0]!r} missing; expected {', '.join(_METRICS_COLUMNS)}"
        )
    for column in ("rmse", "max_abs"):
        values = pd.to_numeric(frame[column], errors="coerce")
        bad = values.isna() & frame[column].notna()
        if bad.any():
            row = int(np.flatnonzero(bad.to_numpy())[0]) + 2  # header is line 1
            raise DataError(
                f"{path}: line {row}, column {column!r}: expected a number, got {shown(frame[column].iloc[row - 2])}"
            )
        frame[column] = values
    return frame


def dataset_kind(result_dir) -> str:
    """'simulated' or 'measured', from the dataset.yaml that provenance.json names."""
    result_dir = Path(result_dir)
    provenance = result_dir / "provenance.json"
    try:
        root = Path(json.loads(provenance.read_text(encoding="utf-8"))["data"]["root"])
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise DataError(
            f"{provenance}: expected the workflow's provenance record with data.root ({exc})"
        ) from exc
    sheet = root / "dataset.yaml"
    try:
        kind = yaml.safe_load(sheet.read_text(encoding="utf-8"))["provenance"]["kind"]
    except (OSError, yaml.YAMLError, KeyError, TypeError) as exc:
        raise DataError(
            f"{sheet}: expected provenance.kind (simulated or measured) ({exc})"
        ) from exc
    if kind not in ("simulated", "measured"):
        raise DataError(
            f"{sheet}: provenance.kind: expected 'simulated' or 'measured', got {kind!r}"
        )
    return kind


def _order(values: Iterable[str], preferred: tuple[str, ...]) -> list[str]:
    rank = {v: i for i, v in enumerate(preferred)}
    return sorted(set(values), key=lambda v: (rank.get(v, len(rank)), v))


def summarise(
    metrics: Mapping[str, pd.DataFrame],
    kinds: Mapping[str, str],
    statistics: StatisticsSettings | None = None,
) -> pd.DataFrame:
    """Held-out error of the whole error curve per dataset x approach x algorithm.

    Parameters
    ----------
    metrics : mapping of dataset name to DataFrame
        Each dataset's metrics table (:func:`read_metrics`).
    kinds : mapping of dataset name to str
        'simulated' or 'measured' (:func:`dataset_kind`).
    statistics : StatisticsSettings, optional
        Level, bootstrap size and seed of the means' intervals (config ``statistics``);
        default the schema's.

    Returns
    -------
    DataFrame
        :data:`SUMMARY_COLUMNS`; means and the worst case are over the folds, a mean's
        ``_lo`` and ``_hi`` its interval with the folds resampled.  Sorted by dataset,
        then approach and algorithm in the paper's order.
    """
    if statistics is None:
        statistics = StatisticsSettings.from_section(validate_config({})["statistics"])

    rows = [
        row
        for name in sorted(metrics)
        for row in _dataset_rows(name, metrics[name], kinds[name], statistics)
    ]
    if not rows:
        raise DataError(
            f"no dataset results could be read; expected results/<dataset>/{paths.METRICS} "
            "for the datasets of config datasets"
        )
    return pd.DataFrame(rows, columns=list(SUMMARY_COLUMNS))


def _dataset_rows(
    name: str, metrics: pd.DataFrame, kind: str, statistics: StatisticsSettings
) -> list[dict]:
    """One dataset's summary rows, approach and algorithm in the paper's order."""

    def interval(values) -> tuple[float, float]:
        return fold_mean_interval(values, statistics.level, statistics.n_resamples, statistics.seed)

    rows = []
    errors = metrics[metrics["target"] == "error"]
    if errors.empty:
        raise DataError(
            f"dataset {name}: metrics hold no row with target 'error'; expected held-out error curves"
        )
    for approach in _order(errors["approach"], _APPROACH_ORDER):
        for algorithm in _order(
            errors.loc[errors["approach"] == approach, "algorithm"], _ALGORITHM_ORDER
        ):
            group = errors[(errors["approach"] == approach) & (errors["algorithm"] == algorithm)]
            rmse_lo, rmse_hi = interval(group["rmse"])
            max_lo, max_hi = interval(group["max_abs"])
            rows.append(
                {
                    "dataset": name,
                    "data": kind,
                    "approach": approach,
                    "algorithm": algorithm,
                    "n_folds": int(group["fold"].nunique()),
                    "mean_rmse_um": float(group["rmse"].mean()),
                    "mean_rmse_um_lo": rmse_lo,
                    "mean_rmse_um_hi": rmse_hi,
                    "mean_max_abs_um": float(group["max_abs"].mean()),
                    "mean_max_abs_um_lo": max_lo,
                    "mean_max_abs_um_hi": max_hi,
                    "worst_max_abs_um": float(group["max_abs"].max()),
                }
            )
    return rows


def model_ranking(metrics: pd.DataFrame) -> pd.DataFrame:
    """Held-out error of each approach x algorithm over the folds (target ``error``), best first.

    The same summary as the cross-dataset table (:func:`summarise`), ordered by mean RMSE,
    then mean largest |residual|.
    """
    summary = summarise({"dataset": metrics}, {"dataset": ""})
    ranked = summary.drop(columns=["dataset", "data"]).sort_values(
        ["mean_rmse_um", "mean_max_abs_um", "approach", "algorithm"], kind="stable"
    )
    return ranked.reset_index(drop=True)


def to_markdown(summary: pd.DataFrame) -> str:
    """The summary as a Markdown table, with a line on which datasets are simulated."""
    from thermaxis.tables import markdown_table

    simulated = sorted(summary.loc[summary["data"] == "simulated", "dataset"].unique())
    lines = ["# Held-out error per dataset, approach and algorithm", ""]
    if simulated:
        lines += [f"SIMULATED data: {', '.join(simulated)} (not measurements).", ""]
    lines += [
        "Error curves of each held-out condition (leave-one-condition-out); means and worst case over the folds, µm; "
        "a mean's _lo and _hi: its bootstrap interval with the folds resampled (config statistics).",
        "",
        markdown_table(summary, float_format="%.3f"),
    ]
    return "\n".join(lines)


def datasets_under(results: Path) -> list[str]:
    """Names of the folders of ``results`` that hold a dataset's run of the workflow.

    ``provenance.json`` marks one: the workflow writes it for every whole run
    (target ``all``); a run of one target does not, nor do ``_datasets``, ``_benchmarks``
    or ``bench``.
    """
    return sorted(path.parent.name for path in Path(results).glob("*/provenance.json"))


def _warn(message: str) -> None:
    print(f"thermaxis warning: {message}", file=sys.stderr)


def _readable(results: Path, names: Iterable[str]) -> tuple[dict, dict]:
    """Metrics and kind of every dataset that can be read; the others are named and left out."""
    metrics, kinds = {}, {}
    for name in names:
        folder = results / name
        try:
            metrics[name] = read_metrics(folder / paths.METRICS)
            kinds[name] = dataset_kind(folder)
        except DataError as exc:
            metrics.pop(name, None)
            _warn(f"{folder} left out of the cross-dataset summary: {exc}")
    return metrics, kinds


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m thermaxis.reports.crossdataset", description=__doc__.splitlines()[0]
    )
    parser.add_argument(
        "--results", default="results", help="folder holding results/<dataset>/ (default: results)"
    )
    parser.add_argument("--out", default=None, help="output folder (default: <results>/_datasets)")
    parser.add_argument(
        "--datasets",
        nargs="+",
        default=None,
        help="names of the datasets to compare (default: every dataset under --results)",
    )
    parser.add_argument(
        "--formats", nargs="+", default=["png", "pdf"], help="figure formats (default: png pdf)"
    )
    parser.add_argument(
        "--config",
        default="config/config.yaml",
        help="the config whose `statistics` sets the intervals (default: config/config.yaml)",
    )
    args = parser.parse_args(argv)
    results = Path(args.results)
    out = Path(args.out) if args.out else results / "_datasets"
    try:
        config = load_config(args.config)
        names = args.datasets if args.datasets is not None else datasets_under(results)
        metrics, kinds = _readable(results, names)
        statistics = StatisticsSettings.from_section(config["statistics"])
        summary = summarise(metrics, kinds, statistics)
        fig = registry.function(FIGURE.draw)(summary)
    except (DataError, ValueError, OSError) as exc:
        print(f"thermaxis error: {str(exc).splitlines()[0]}", file=sys.stderr)
        return 1
    _write(summary, fig, out, args.formats)
    _write_page(summary, results, out, args.formats)
    print(
        f"thermaxis: held-out error of {len(metrics)} dataset(s) -> {out}/summary.csv",
        file=sys.stderr,
    )
    return 0


def _write(summary: pd.DataFrame, fig, out: Path, formats) -> None:
    """Every output under a temporary name first, then all moved into place."""
    from thermaxis.figures.style import save_figure
    from thermaxis.pipeline.runner import atomic_path

    with ExitStack() as stack:
        table = stack.enter_context(atomic_path(out / "summary.csv"))
        markdown = stack.enter_context(atomic_path(out / "summary.md"))
        figures = [stack.enter_context(atomic_path(out / f"{FIGURE.id}.{ext}")) for ext in formats]
        summary.to_csv(table, index=False, float_format="%.6f", lineterminator="\n")
        markdown.write_text(to_markdown(summary), encoding="utf-8")
        save_figure(fig, figures)


def _write_page(summary: pd.DataFrame, results: Path, out: Path, formats) -> None:
    """``results/index.html``: the summary with a link to each dataset's own page."""
    import os

    from thermaxis.pipeline.runner import write_text
    from thermaxis.reports.index import render_results_index

    pages = {
        name: f"{name}/index.html"
        for name in summary["dataset"].unique()
        if (results / name / "index.html").is_file()
    }
    figure = (
        os.path.relpath(out / f"{FIGURE.id}.png", results).replace(os.sep, "/")
        if "png" in formats
        else None
    )
    from thermaxis.reports.answer import read_answer

    answers = {
        name: read_answer(results / name)
        for name in summary["dataset"].unique()
        if (results / name / "compensation" / "model.json").is_file()
    }
    write_text(render_results_index(summary, pages, figure, answers), results / "index.html")


if __name__ == "__main__":
    sys.exit(main())
