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

import pandas as pd

from thermaxis.tables import read_table

__all__ = ["answer_of", "answer_sentence", "read_answer", "main"]


def answer_of(folds: pd.DataFrame, deployment: dict) -> dict:
    """The numbers of the answer from recommendation.csv's folds and model.json's deployment."""
    runs = pd.DataFrame(deployment.get("verdict", {}).get("runs", []))
    ok = bool(deployment.get("recommended_for_deployment"))
    deciding, best_gain = None, None
    if len(runs):
        # The run that decides: the largest change of either quantity of the verdict
        # (made worst when refused, helped least when deployed).
        quantities = [q for q in ("largest_abs", "E") if f"{q}_change_um" in runs]
        changes = runs[[f"{q}_change_um" for q in quantities]].to_numpy()
        row, column = divmod(int(changes.argmax()), len(quantities))
        quantity = quantities[column]
        deciding = runs.iloc[row]
        best_gain = float(-changes.min())
    return dict(
        candidate=str(deployment.get("candidate", "")),
        recommended=ok,
        rmse_um=float(folds["rmse_um"].mean()),
        paper_rmse_um=float(folds["paper_rmse_um"].mean()),
        n_folds=int(len(folds)),
        uncompensated_um=float(runs["largest_abs_before_um"].max()) if len(runs) else float("nan"),
        compensated_um=float(runs["largest_abs_after_um"].max()) if len(runs) else float("nan"),
        deciding_run=None if deciding is None else str(deciding["run"]),
        deciding_quantity=None
        if deciding is None
        else {"largest_abs": "largest |deviation|", "E": "E of ISO 230-2"}[quantity],
        deciding_before_um=None if deciding is None else float(deciding[f"{quantity}_before_um"]),
        deciding_after_um=None if deciding is None else float(deciding[f"{quantity}_after_um"]),
        max_worsening_um=deployment.get("verdict", {}).get("max_worsening_um"),
        best_gain_um=best_gain,
    )


def _least_helped(answer: dict) -> str:
    """The deciding run's change in words: a gain, or a loss the verdict tolerates."""
    loss = answer["deciding_after_um"] - answer["deciding_before_um"]
    if loss <= 0:
        return "the smallest gain"
    return (
        f"worse by {loss:.2f} µm, within compensation.max_worsening_um "
        f"{answer['max_worsening_um']:g} µm"
    )


def answer_sentence(answer: dict) -> str:
    """The answer in one paragraph: the model (or none), its error, the verdict and its run."""
    error = (
        f"held-out RMSE {answer['rmse_um']:.2f} µm against {answer['paper_rmse_um']:.2f} µm for "
        f"the paper's configuration (mean over {answer['n_folds']} held-out runs); largest "
        f"|deviation| {answer['compensated_um']:.2f} µm compensated against "
        f"{answer['uncompensated_um']:.2f} µm uncompensated"
    )
    run = answer["deciding_run"]
    if answer["recommended"]:
        decides = (
            f" Held-out run {run} decides it: {answer['deciding_quantity']} "
            f"{answer['deciding_before_um']:.2f} -> "
            f"{answer['deciding_after_um']:.2f} µm, {_least_helped(answer)}."
            if run
            else ""
        )
        return f"Deploy {answer['candidate']}: {error}. Recommended for deployment.{decides}"
    fails = (
        f" it makes held-out run {run} worse ({answer['deciding_quantity']} "
        f"{answer['deciding_before_um']:.2f} -> "
        f"{answer['deciding_after_um']:.2f} µm); it needs more runs like {run}'s condition"
        if run
        else " no held-out run shows it helps; it needs more runs"
    )
    if run and answer.get("best_gain_um") is not None:
        tolerance = answer["max_worsening_um"] or 0.0
        if answer["best_gain_um"] <= tolerance:
            # A run like the others would not help a model that helps none of them: say
            # what the runs show instead (a stable axis, or temperatures that miss the drift).
            fails = (
                f" it helps no held-out run by more than {tolerance:g} µm (compensation."
                f"max_worsening_um) and makes {run} worse ({answer['deciding_quantity']} "
                f"{answer['deciding_before_um']:.2f} -> {answer['deciding_after_um']:.2f} µm); "
                "nothing here shows that the temperatures predict this axis's drift"
            )
    return (
        f"Do not compensate with any candidate. Closest: {answer['candidate']}, {error}; but"
        f"{fails}."
    )


def read_answer(results: Path | str) -> dict:
    """The answer of ``results/<dataset>`` from its recommendation.csv and model.json."""
    results = Path(results)
    folds = read_table(results / "tables" / "recommendation.csv", comment="#")
    with open(results / "compensation" / "model.json", encoding="utf-8") as fh:
        deployment = json.load(fh)["deployment"]
    return answer_of(folds, deployment)


def main(argv: list[str] | None = None) -> int:
    """``python -m thermaxis.reports.answer results/<dataset> ...``: one line per dataset."""
    for folder in argv if argv is not None else sys.argv[1:]:
        path = Path(folder)
        if not (path / "compensation" / "model.json").is_file():
            print(f"{path.name}: no answer yet ({path / 'compensation' / 'model.json'} is missing)")
            continue
        print(f"{path.name}: {answer_sentence(read_answer(path))} See {path / 'index.html'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
