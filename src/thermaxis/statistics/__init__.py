"""Every held-out comparison with its uncertainty (docs/statistics.md).

Intervals of the held-out metrics (a block bootstrap of whole measurements within each
fold), paired comparisons of models on the same measurements, the paper's claims tested
per dataset, the sweep's ranking with Friedman and a post-hoc test, and the stability of
the sensitive points. Settings: config ``statistics`` (:class:`thermaxis.config.StatisticsSettings`).

The names below are imported on first use: a job that needs one module (the models'
intervals, the index's fold-mean interval) does not import scipy.stats and the claims'
selection with the rest.
"""

from thermaxis.lazy import lazy_names

_PUBLIC = {
    "CLAIM_COLUMNS": "thermaxis.statistics.claims",
    "CLAIMS": "thermaxis.statistics.claims",
    "claim_results": "thermaxis.statistics.claims",
    "claims_markdown": "thermaxis.statistics.claims",
    "claims_table": "thermaxis.statistics.claims",
    "COMPARISON_COLUMNS": "thermaxis.statistics.comparisons",
    "compare_models": "thermaxis.statistics.comparisons",
    "compare_recommendation": "thermaxis.statistics.comparisons",
    "comparison_table": "thermaxis.statistics.comparisons",
    "fold_means": "thermaxis.statistics.comparisons",
    "model_sums": "thermaxis.statistics.comparisons",
    "measurement_sums": "thermaxis.statistics.intervals",
    "metric_intervals": "thermaxis.statistics.intervals",
    "with_intervals": "thermaxis.statistics.intervals",
    "holm": "thermaxis.statistics.paired",
    "paired_comparison": "thermaxis.statistics.paired",
    "verdict": "thermaxis.statistics.paired",
    "with_uncertainty": "thermaxis.statistics.ranking",
    "STABILITY_COLUMNS": "thermaxis.statistics.stability",
    "selection_stability": "thermaxis.statistics.stability",
}

__all__ = sorted(_PUBLIC)


__getattr__, __dir__ = lazy_names(__name__, _PUBLIC)
