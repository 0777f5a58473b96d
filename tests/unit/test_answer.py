"""The one answer per dataset (thermaxis.reports.answer), from hand-made tables."""

from __future__ import annotations

import pandas as pd

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


def _deployment(ok: bool, change_r2: float):
    return {
        "candidate": "pointwise-mlr-all",
        "recommended_for_deployment": ok,
        "verdict": {
            "max_worsening_um": 0.1,
            "runs": [
                {
                    "run": "R1",
                    "largest_abs_before_um": 6.0,
                    "largest_abs_after_um": 2.0,
                    "largest_abs_change_um": -4.0,
                },  # fmt: skip
                {
                    "run": "R2",
                    "largest_abs_before_um": 5.0,
                    "largest_abs_after_um": 5.0 + change_r2,
                    "largest_abs_change_um": change_r2,
                },
            ],
        },
    }


def test_a_safe_candidate_is_deployed_and_the_run_helped_least_decides():
    answer = answer_of(_folds(), _deployment(True, -1.0))
    # Means by hand: (1 + 2) / 2 = 1.5 and (3 + 5) / 2 = 4; worst run before 6, after max(2, 4) = 4.
    assert (answer["rmse_um"], answer["paper_rmse_um"]) == (1.5, 4.0)
    assert (answer["uncompensated_um"], answer["compensated_um"]) == (6.0, 4.0)
    text = answer_sentence(answer)
    assert text.startswith("Deploy pointwise-mlr-all: held-out RMSE 1.50 µm against 4.00 µm")
    assert (
        "Recommended for deployment. Held-out run R2 decides it: largest |deviation| 5.00 -> 4.00 µm"
        in text
    )


def test_no_safe_candidate_says_so_and_names_the_run_it_fails_on():
    text = answer_sentence(answer_of(_folds(), _deployment(False, 1.5)))
    assert text.startswith("Do not compensate with any candidate. Closest: pointwise-mlr-all")
    assert (
        "held-out run R2 worse (largest |deviation| 5.00 -> 6.50 µm)" in text
        and "more runs like R2" in text
    )
    assert "best" not in text


def test_a_loss_the_verdict_tolerates_is_called_a_loss_not_a_gain():
    # R2 gets worse by 0.06 µm, under the verdict's 0.1 µm: deployed, and said so.
    text = answer_sentence(answer_of(_folds(), _deployment(True, 0.06)))
    assert (
        "Held-out run R2 decides it: largest |deviation| 5.00 -> 5.06 µm, worse by 0.06 µm, "
        "within compensation.max_worsening_um 0.1 µm." in text
    )
    assert "the smallest gain" not in text


def test_a_candidate_that_helps_no_run_is_not_sent_back_for_more_runs():
    # R1 gains nothing either: by hand its change is +0.05 µm, R2's +0.3 µm, no gain
    # beyond the verdict's 0.1 µm anywhere (an axis that hardly drifts).
    deployment = _deployment(False, 0.3)
    deployment["verdict"]["runs"][0].update(largest_abs_after_um=6.05, largest_abs_change_um=0.05)
    text = answer_sentence(answer_of(_folds(), deployment))
    assert "helps no held-out run by more than 0.1 µm" in text
    assert "makes R2 worse (largest |deviation| 5.00 -> 5.30 µm)" in text
    assert "more runs" not in text
