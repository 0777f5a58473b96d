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
    head = (
        f"# Recommended model\n\n{statement}\n\n"
        f"Recommended: the **{recommendation.final}**, the convex combination of {len(c.members)} "
        f"linear candidates with the weights fitted on every run's held-out predictions ({final}). "
        f"Weighted fold by fold without the held-out run, it leaves a mean held-out RMSE of "
        f"{s['rmse_um']:.2f} µm and a mean largest |residual| of {s['max_abs_um']:.2f} µm, "
        f"against {s['paper_rmse_um']:.2f} and {s['paper_max_abs_um']:.2f} µm for the paper's "
        f"configuration on the same folds.\n\n"
    )
    unweighted = [fold for fold in f["fold"].astype(str) if not _has_inner(recommendation, fold)]
    if unweighted:
        # One training run leaves nothing to hold out inside the fold (combine).
        head += (
            f"Fold(s) {', '.join(unweighted)} had a single training run, so no inner predictions "
            "to fit weights on: they weight the members equally.\n\n"
        )
    return head + markdown_table(f, "%.3f")


def _has_inner(recommendation: Recommendation, fold: str) -> bool:
    inner = recommendation.inner
    return bool(len(inner)) and bool((inner["fold"].astype(str) == fold).any())
