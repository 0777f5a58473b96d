"""The one answer per dataset: what to deploy, how good it is, and whether.

Worded once, here, from the workflow's own files: ``tables/recommendation.csv`` (the
nested choice's held-out error beside the paper's configuration, fold by fold) and
``compensation/model.json`` (the deployed candidate and its verdict over the held-out
runs).  The index's answer box, ``thermaxis report``, the dataset report and the last
lines of ``make results`` all print :func:`answer_sentence`.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from thermaxis.compensation.verdict import verdict_sentence
from thermaxis.pipeline import paths
from thermaxis.tables import read_table

__all__ = ["LEADS", "answer_of", "answer_sentence", "read_answer", "main"]


def answer_of(folds: pd.DataFrame, model: dict) -> dict:
    """The numbers of the answer from recommendation.csv's folds and model.json.

    The error quoted is the deployed model's own over its held-out runs (model.json's
    ``held_out_accuracy``): the recommendation's, unless config ``compensation.model``
    deploys the paper's configuration or a named candidate; then the recommendation's is
    quoted beside it.
    """
    deployment = model["deployment"]
    verdict = deployment["verdict"]
    runs = pd.DataFrame(verdict["runs"])
    curve = [row["rmse"] for row in model["held_out_accuracy"] if row["target"] == "error"]
    return dict(
        candidate=str(deployment.get("candidate", "")),
        outcome=verdict["outcome"],
        recommended=verdict["outcome"] == "recommended",
        rmse_um=float(np.mean(curve)),
        paper_rmse_um=float(folds["paper_rmse_um"].mean()),
        n_folds=len(curve),
        uncompensated_um=float(runs["largest_abs_before_um"].max()),
        compensated_um=float(runs["largest_abs_after_um"].max()),
        verdict=verdict,
        by_config=deployment["model"] != "recommended",
        evidence=str(deployment["recommended_by_the_evidence"]),
        evidence_rmse_um=float(folds["rmse_um"].mean()),
    )


# How the answer opens, per outcome of the verdict; the verdict's own words follow. The
# recommendation is the candidate the runs favour, so when it harms none is advised; a model
# deployed by config speaks for itself alone.
LEADS = {
    "recommended": "Deploy {candidate}: {error}.",
    "not_established": "Not yet: {candidate}, {error}.",
    "not_recommended": "Do not compensate with any candidate. Closest: {candidate}, {error}.",
    "not_recommended_by_config": "Do not compensate with {candidate}: {error}.",
}


def answer_sentence(answer: dict) -> str:
    """The answer in one paragraph: the model (or none), its error, and the verdict in the
    words of :func:`thermaxis.compensation.verdict.verdict_sentence`."""
    error = (
        f"held-out RMSE {answer['rmse_um']:.2f} µm against {answer['paper_rmse_um']:.2f} µm for "
        f"the paper's configuration (mean over {answer['n_folds']} held-out runs); largest "
        f"|deviation| {answer['compensated_um']:.2f} µm compensated against "
        f"{answer['uncompensated_um']:.2f} µm uncompensated"
    )
    if answer["by_config"]:
        error += (
            f"; deployed as config compensation.model says, where the runs recommend the "
            f"{answer['evidence']} at {answer['evidence_rmse_um']:.2f} µm"
        )
    outcome = answer["outcome"]
    if answer["by_config"] and outcome == "not_recommended":
        outcome = "not_recommended_by_config"
    lead = LEADS[outcome].format(candidate=answer["candidate"], error=error)
    return f"{lead} {verdict_sentence(answer['verdict'], unit='µm')}"


def read_answer(results: Path | str) -> dict:
    """The answer of ``results/<dataset>`` from its recommendation.csv and model.json."""
    results = Path(results)
    folds = read_table(results / paths.RECOMMENDATION, comment="#")
    with open(results / paths.DEPLOYED_MODEL, encoding="utf-8") as fh:
        return answer_of(folds, json.load(fh))


def main(argv: list[str] | None = None) -> int:
    """``python -m thermaxis.reports.answer results/<dataset> ...``: one line per dataset."""
    for folder in argv if argv is not None else sys.argv[1:]:
        path = Path(folder)
        if not (path / paths.DEPLOYED_MODEL).is_file():
            print(f"{path.name}: no answer yet ({path / paths.DEPLOYED_MODEL} is missing)")
            continue
        print(f"{path.name}: {answer_sentence(read_answer(path))} See {path / 'index.html'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
