"""recommendation.md: the recommended model in words, then its outer folds."""

from __future__ import annotations

from thermaxis.method.nested import Recommendation, summary_of
from thermaxis.tables import markdown_table

__all__ = ["recommendation_markdown"]


def recommendation_markdown(recommendation: Recommendation, statement: str) -> str:
    """recommendation.md: the answer first, then the folds."""
    s = summary_of(recommendation)
    f = recommendation.folds
    c = recommendation.combination
    final = ", ".join(f"{m} {w:.3f}" for m, w in zip(c.members, c.final, strict=True))
    how = (
        "the weights fitted on every run's held-out predictions"
        if c.final_fitted
        else "equal weights (every run's held-out prediction is a fit on a single run)"
    )
    head = (
        f"# Recommended model\n\n{statement}\n\n"
        f"Recommended: the **{recommendation.final}**, the convex combination of {len(c.members)} "
        f"linear candidates with {how} ({final}). "
        f"Weighted fold by fold without the held-out run, it leaves a mean held-out RMSE of "
        f"{s['rmse_um']:.2f} µm and a mean largest |residual| of {s['max_abs_um']:.2f} µm, "
        f"against {s['paper_rmse_um']:.2f} and {s['paper_max_abs_um']:.2f} µm for the paper's "
        f"configuration on the same folds.\n\n"
    )
    if c.equal_folds:
        # A member fitted on a single run has seen one condition: its predictions weigh
        # nothing (thermaxis.method.nested.MIN_WEIGHING_RUNS).
        head += (
            f"Fold(s) {', '.join(c.equal_folds)} had fewer than three training runs, so no "
            "inner fit on two runs or more to weigh the members on: they weight them equally."
            "\n\n"
        )
    return head + markdown_table(f, "%.3f")
