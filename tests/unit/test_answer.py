"""The one answer per dataset (thermaxis.reports.answer), from hand-made tables."""

from __future__ import annotations

import pandas as pd

from helpers.builders import held_out_summary
from thermaxis.compensation.verdict import deployment_verdict, verdict_sentence
from thermaxis.reports.answer import answer_of, answer_sentence


def _folds():
    return pd.DataFrame(
        {
            "fold": ["R1", "R2"],
            "chosen": ["a", "a"],
            "rmse_um": [1.0, 2.0],
            "paper_rmse_um": [3.0, 5.0],
        }  # fmt: skip
    )


def _deployment(changes):
    """A deployment whose verdict the real verdict function wrote, from runs R1.. whose
    largest |deviation| goes from 6 um by ``changes`` (E alike)."""
    frame = held_out_summary(
        [(f"R{i}", 1, 6.0, 6.0 + c, 2.0, 2.0 + c / 3) for i, c in enumerate(changes, 1)]
    )
    verdict = deployment_verdict(frame, tolerance=0.1, significance=0.05)
    return {"candidate": "pointwise-mlr-all", "verdict": verdict}


def test_each_outcome_opens_the_answer_and_the_verdict_follows_in_its_own_words():
    # 8 runs, 7 improve: p = 9/256 <= 0.05, recommended.
    for changes, lead in (
        ([-4.0] * 7 + [1.5], "Deploy pointwise-mlr-all: held-out RMSE 1.50 µm against 4.00 µm"),
        ([-4.0, -4.0, -4.0, 1.5], "Not yet: pointwise-mlr-all, held-out RMSE 1.50 µm"),
        ([-4.0, 1.5, 2.0, 0.0], "Do not compensate with any candidate. Closest: pointwise-mlr-all"),
    ):
        deployment = _deployment(changes)
        answer = answer_of(_folds(), deployment)
        text = answer_sentence(answer)
        assert text.startswith(lead), text
        assert text.endswith(verdict_sentence(deployment["verdict"], unit="µm"))
        assert "best" not in text


def test_the_numbers_of_the_answer_by_hand():
    answer = answer_of(_folds(), _deployment([-4.0, -1.0, 1.5]))
    # Means (1 + 2) / 2 = 1.5 and (3 + 5) / 2 = 4; worst run before 6, after max(2, 5, 7.5).
    assert (answer["rmse_um"], answer["paper_rmse_um"]) == (1.5, 4.0)
    assert (answer["uncompensated_um"], answer["compensated_um"]) == (6.0, 7.5)
    assert answer["outcome"] == "not_established" and answer["recommended"] is False
