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


def _model(changes, model="recommended", candidate="pointwise-mlr-all", rmse=(1.0, 2.0)):
    """A model.json whose verdict the real verdict function wrote, from runs R1.. whose
    largest |deviation| goes from 6 um by ``changes`` (E alike), and whose held-out error
    curve has RMSE ``rmse`` on R1 and R2 (rows of other targets around it)."""
    frame = held_out_summary(
        [(f"R{i}", 1, 6.0, 6.0 + c, 2.0, 2.0 + c / 3) for i, c in enumerate(changes, 1)]
    )
    verdict = deployment_verdict(frame, tolerance=0.1, significance=0.05)
    accuracy = [
        {"fold": fold, "target": target, "rmse": value}
        for fold, r in zip(("R1", "R2"), rmse, strict=True)
        for target, value in (("b", 50.0), ("error", r), ("k", 90.0))
    ]
    deployment = {
        "model": model,
        "candidate": candidate,
        "recommended_by_the_evidence": "super learner",
        "verdict": verdict,
    }
    return {"deployment": deployment, "held_out_accuracy": accuracy}


def test_each_outcome_opens_the_answer_and_the_verdict_follows_in_its_own_words():
    # 8 runs, 7 improve: p = 9/256 <= 0.05, recommended.
    for changes, lead in (
        ([-4.0] * 7 + [1.5], "Deploy pointwise-mlr-all: held-out RMSE 1.50 µm against 4.00 µm"),
        ([-4.0, -4.0, -4.0, 1.5], "Not yet: pointwise-mlr-all, held-out RMSE 1.50 µm"),
        ([-4.0, 1.5, 2.0, 0.0], "Do not compensate with any candidate. Closest: pointwise-mlr-all"),
    ):
        model = _model(changes)
        answer = answer_of(_folds(), model)
        text = answer_sentence(answer)
        assert text.startswith(lead), text
        assert text.endswith(verdict_sentence(model["deployment"]["verdict"], unit="µm"))
        assert "best" not in text


def test_the_numbers_of_the_answer_by_hand():
    answer = answer_of(_folds(), _model([-4.0, -1.0, 1.5]))
    # Means (1 + 2) / 2 = 1.5 and (3 + 5) / 2 = 4; worst run before 6, after max(2, 5, 7.5).
    assert (answer["rmse_um"], answer["paper_rmse_um"]) == (1.5, 4.0)
    assert (answer["uncompensated_um"], answer["compensated_um"]) == (6.0, 7.5)
    assert answer["outcome"] == "not_established" and answer["recommended"] is False


def test_a_model_deployed_by_config_quotes_its_own_error_and_the_recommendations():
    # compensation.model: paper. Its error curve's held-out RMSE is (3 + 5) / 2 = 4, as the
    # recommendation table's paper column says; the runs recommend the super learner at
    # (1 + 2) / 2 = 1.5 (recommendation.csv's rmse_um).
    model = _model([-4.0, -1.0, 1.5], model="paper", candidate="paper", rmse=(3.0, 5.0))
    answer = answer_of(_folds(), model)
    assert (answer["rmse_um"], answer["n_folds"]) == (4.0, 2)
    text = answer_sentence(answer)
    assert text.startswith(
        "Not yet: paper, held-out RMSE 4.00 µm against 4.00 µm for the paper's configuration "
        "(mean over 2 held-out runs); largest |deviation| 7.50 µm compensated against 6.00 µm "
        "uncompensated; deployed as config compensation.model says, where the runs recommend "
        "the super learner at 1.50 µm."
    ), text
    # Deployed as recommended, the recommendation is not quoted twice.
    assert "compensation.model" not in answer_sentence(
        answer_of(_folds(), _model([-4.0, -1.0, 1.5]))
    )


def test_a_harmful_model_deployed_by_config_is_advised_against_by_name():
    # Three of four runs worsen: not recommended. The runs' own choice is not the one
    # that harmed, so the answer does not advise against every candidate.
    model = _model([-4.0, 1.5, 2.0, 3.0], model="pointwise-svr", candidate="pointwise-svr")
    text = answer_sentence(answer_of(_folds(), model))
    assert model["deployment"]["verdict"]["outcome"] == "not_recommended"
    assert text.startswith("Do not compensate with pointwise-svr: held-out RMSE 1.50 µm"), text
    assert "any candidate" not in text
    recommended = answer_sentence(answer_of(_folds(), _model([-4.0, 1.5, 2.0, 3.0])))
    assert recommended.startswith(
        "Do not compensate with any candidate. Closest: pointwise-mlr-all"
    )
