"""Every result file of a dataset, named once, relative to ``results/<dataset>/``.

The rules, the figure table, the reports, the compensation and the command line spell a
result file through these names. ``{run}``, ``{fold}``, ``{table}``, ``{ext}``,
``{n_batches}`` and ``{batch}`` are Snakemake wildcards or filled by :func:`under`. This module imports
nothing of thermaxis, so every layer may import it.
"""

from __future__ import annotations

# The dataset's raw files hashed once (the jobs that read raw files depend on it) and
# what the index job writes.
DATA_MANIFEST = "data_manifest.sha256"
PROVENANCE = "provenance.json"
INDEX = "index.html"
# Snakemake's own report (`make report`, `thermaxis report --zip`).
REPORT_ZIP = "report.zip"

# Cleaning, one of each per run.
CLEAN_SERIES = "clean/{run}/temperatures.parquet"
CLEAN_QC = "clean/{run}/qc.csv"
CLEAN_GAPS = "clean/{run}/gaps.csv"
CLEAN_ERRORS = "clean/{run}/errors.parquet"
CLEAN_TEMPERATURES = "clean/{run}/measurement_temperatures.parquet"
CLEAN_WINDOWS = "clean/{run}/windows.csv"
CLEAN_SIGNALS = "clean/{run}/measurement_signals.parquet"
CLEAN_SIGNAL_SERIES = "clean/{run}/signals.parquet"
CLEAN_INPUTS = "clean/{run}/measurement_inputs.parquet"

# The runs assembled.
ASSEMBLED_ERRORS = "assembled/errors.parquet"
ASSEMBLED_TEMPERATURES = "assembled/temperatures.parquet"
ASSEMBLED_SIGNALS = "assembled/signals.parquet"
ASSEMBLED_INPUTS = "assembled/inputs.parquet"
DATASET_SUMMARY = "tables/dataset_summary.csv"
CLEANING_QC = "tables/cleaning_qc.csv"
CLEANING_EVENTS = "tables/cleaning_events.csv"
AMBIENT_RANGES = "tables/ambient_ranges.csv"
AMBIENT_SERIES = "tables/ambient_series.parquet"
TABLE5 = "tables/table5_slope_intercept.csv"
TABLE5_MARKDOWN = "tables/table5_slope_intercept.md"
POLYNOMIALS = "decoupled/polynomial_coefficients.csv"

# Sensitive points and models: per fold, and collected.
SELECTION = "selection/{fold}.json"
SELECTION_TABLE = "selection/{fold}.csv"
FOLD_TABLE = "models/{fold}/{table}.csv"
METRICS = "tables/metrics.csv"
COEFFICIENTS = "tables/coefficients.csv"
KB_PREDICTIONS = "tables/kb_predictions.csv"
ERROR_PREDICTIONS = "tables/error_predictions.csv"
FITTING = "tables/fitting.csv"
SENSITIVE_POINTS = "tables/sensitive_points.csv"

# The recommendation.
FOLD_SCORES = "recommend/folds/{fold}.csv"
RECOMMENDATION = "tables/recommendation.csv"
RECOMMENDATION_MARKDOWN = "tables/recommendation.md"
CANDIDATES = "recommend/candidates.csv"
CHOICE = "recommend/choice.json"

# The compensation: the deployed model and its exports, and per held-out run its fold's.
COMPENSATION_TABLE = "compensation/{table}.csv"
FOLD_COMPENSATION = "compensation/folds/{fold}/{table}.csv"
FOLD_MODEL = "compensation/folds/{fold}/model.json"
FITTED_MODEL = "compensation/fitted_model.json"
DEPLOYED_MODEL = "compensation/model.json"
STRUCTURED_TEXT = "compensation/ThermalCompensation.st"

# Statistics and the audit against the paper.
COMPARISONS = "tables/comparisons.csv"
CLAIMS = "tables/claims.csv"
CLAIMS_MARKDOWN = "tables/claims.md"
SELECTION_STABILITY = "tables/selection_stability.csv"
PAPER_COMPARISON = "tables/paper_comparison.csv"
PAPER_COMPARISON_MARKDOWN = "tables/paper_comparison.md"
FAITHFULNESS = "tables/faithfulness.csv"
FAITHFULNESS_MARKDOWN = "tables/faithfulness.md"

# Reports: the executed notebook (ext ipynb) and its page (ext html).
PAPER_REPORT = "reports/paper_report.{ext}"
DATASET_REPORT = "reports/dataset_report.{ext}"
CONDITIONS_REPORT = "reports/conditions.{ext}"
CONDITION_REPORT = "reports/condition_{run}.{ext}"
MODEL_REPORT = "reports/model_{fold}.{ext}"

# The sweep (not part of `rule all`).
SWEEP_BATCH = "sweep/batches/{n_batches}/{batch}.parquet"
SWEEP_SUMMARY = "sweep/summary.csv"
SWEEP_RANKING = "sweep/ranking.csv"
SWEEP_EFFECTS = "sweep/factor_effects.csv"
SWEEP_REPORT = "sweep/sweep_report.{ext}"


def under(root, path: str, **wildcards) -> str:
    """``path`` below ``root`` (a dataset's results folder), its ``wildcards`` filled."""
    return f"{root}/{path.format(**wildcards) if wildcards else path}"
