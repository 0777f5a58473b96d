"""Every held-out comparison with its uncertainty (docs/statistics.md).

Intervals of the held-out metrics (a block bootstrap of whole measurements within each
fold), paired comparisons of models on the same measurements, the paper's claims tested
per dataset, the sweep's ranking with Friedman and a post-hoc test, and the stability of
the sensitive points. Settings: config ``statistics`` (:class:`thermaxis.config.StatisticsSettings`).
"""

from thermaxis.statistics.claims import (
    CLAIM_COLUMNS,
    CLAIMS,
    claim_results,
    claims_markdown,
    claims_table,
)
from thermaxis.statistics.comparisons import (
    COMPARISON_COLUMNS,
    compare_models,
    compare_recommendation,
    comparison_table,
    fold_means,
    model_sums,
)
from thermaxis.statistics.intervals import measurement_sums, metric_intervals, with_intervals
from thermaxis.statistics.paired import holm, paired_comparison, verdict
from thermaxis.statistics.ranking import with_uncertainty
from thermaxis.statistics.stability import STABILITY_COLUMNS, selection_stability

__all__ = [
    "CLAIM_COLUMNS",
    "CLAIMS",
    "COMPARISON_COLUMNS",
    "STABILITY_COLUMNS",
    "claim_results",
    "claims_markdown",
    "claims_table",
    "compare_models",
    "compare_recommendation",
    "comparison_table",
    "fold_means",
    "holm",
    "measurement_sums",
    "metric_intervals",
    "model_sums",
    "paired_comparison",
    "selection_stability",
    "verdict",
    "with_intervals",
    "with_uncertainty",
]
