"""Every held-out comparison with its uncertainty (docs/statistics.md).

Intervals of the held-out metrics (a block bootstrap of whole measurements within each
fold), paired comparisons of models on the same measurements, the paper's claims tested
per dataset, the sweep's ranking with Friedman and a post-hoc test, and the stability of
the sensitive points. Settings: config ``statistics`` (:class:`thermaxis.config.StatisticsSettings`).

The names below are imported on first use: a job that needs one module (the models'
intervals, the index's fold-mean interval) does not import scipy.stats and the claims'
selection with the rest.
"""

from importlib import import_module

_PUBLIC = {
    "CLAIM_COLUMNS": "claims",
    "CLAIMS": "claims",
    "claim_results": "claims",
    "claims_markdown": "claims",
    "claims_table": "claims",
    "COMPARISON_COLUMNS": "comparisons",
    "compare_models": "comparisons",
    "compare_recommendation": "comparisons",
    "comparison_table": "comparisons",
    "fold_means": "comparisons",
    "model_sums": "comparisons",
    "measurement_sums": "intervals",
    "metric_intervals": "intervals",
    "with_intervals": "intervals",
    "holm": "paired",
    "paired_comparison": "paired",
    "verdict": "paired",
    "with_uncertainty": "ranking",
    "STABILITY_COLUMNS": "stability",
    "selection_stability": "stability",
}

__all__ = sorted(_PUBLIC)


def __getattr__(name):
    if name in _PUBLIC:
        return getattr(import_module(f"{__name__}.{_PUBLIC[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted([*globals(), *_PUBLIC])
