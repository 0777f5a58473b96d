"""What combining the candidates would give: stacking replayed on the records at hand.

``python -m tools.bench.stacking RESULTS [--doc docs/recommendation.md]`` refits every
candidate of each ``RESULTS/<record>`` (its ``recommend/choice.json`` lists them, its
``assembled/`` tables are the inputs) in both loops of the nested leave-one-condition-out,
keeping the held-out predictions the recommendation's scores are made of, and judges
combinations fixed from the literature before any record was replayed:

* the super learner (van der Laan, Polley and Hubbard 2007; Breiman 1996, "Stacked
  regressions"): non-negative weights fitted by least squares on the candidates' inner
  held-out predictions and scaled to sum to one (the R package SuperLearner's
  ``method.NNLS``), over every candidate;
* the same over the linear candidates only, whose combination is one linear model, so it
  could be exported like one (a kernel model's expansion cannot share an affine block);
* the equal average of the two plain references (the ridge with lags, the evidence ridge);
* the super learner of the two plain references (the default ``recommend.combine``), and
  of the paper's configuration with them (the default until 2026-12-07, second session);
* the two plain references weighted as ``recommend.weighting`` can: the weights of the
  lowest mean RMSE over the inner runs, each run counted once (the default), and all the
  weight on the better of the two by that mean (the discrete super learner).

``--block dev`` writes the table into the development records' block instead: the
simulated records (tools.bench.records.DEV_RECORDS) a change of the rule is judged on
before it meets a scored record; ``--block three-runs`` into the block of the records of
three runs, on which inner fits hold a single run; ``--block measured-cuts`` into the block
of the embedded measured record cut to four and five of its runs.

Each outer fold's weights come from its inner runs alone; the held-out run is predicted
by the candidates fitted on the other runs. Evaluation only: the recommendation deploys
the super learner of ``recommend.combine`` weighted as ``recommend.weighting``
(thermaxis.method.nested.combine), whose figures are the replay's (tools.bench.replay).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from thermaxis.cleaning.run import model_inputs
from thermaxis.config import KERNEL_ALGORITHMS, Settings
from thermaxis.labels import natural_sorted
from thermaxis.method.candidates import BASELINE, EVIDENCE, PAPER, candidate_from_record
from thermaxis.method.nested import (
    MIN_WEIGHING_RUNS,
    WEIGHTINGS,
    held_out_predictions,
    training_sets,
)
from thermaxis.pipeline import paths
from tools.bench.replay import record_scores, table_command

__all__ = ["stacked_rmse", "STACKS"]

BLOCKS = {
    "records": ("<!-- stacking:start -->", "<!-- stacking:end -->"),
    "dev": ("<!-- stacking-dev:start -->", "<!-- stacking-dev:end -->"),
    "three-runs": ("<!-- stacking-three-runs:start -->", "<!-- stacking-three-runs:end -->"),
    "measured-cuts": (
        "<!-- stacking-measured-cuts:start -->",
        "<!-- stacking-measured-cuts:end -->",
    ),
}


def _record_inputs(folder: Path):
    """X, Y, the candidates and the declared signals of one bench record's results."""
    signals = pd.read_parquet(folder / paths.ASSEMBLED_SIGNALS)
    X, Y = model_inputs(
        pd.read_parquet(folder / paths.ASSEMBLED_ERRORS),
        pd.read_parquet(folder / paths.ASSEMBLED_TEMPERATURES),
        signals=signals,
        inputs=pd.read_parquet(folder / paths.ASSEMBLED_INPUTS),
    )
    choice = json.loads((folder / paths.CHOICE).read_text(encoding="utf-8"))
    models = Settings.from_config({}).models
    candidates = [candidate_from_record(r, models) for r in choice["candidates"].values()]
    return X, Y, candidates, sorted(pd.unique(signals["signal"]).tolist())


def _predictions(X, Y, candidates, signals, degree) -> dict:
    """``{(training runs, candidate): (run per row, predictions)}`` over both loops."""
    runs = natural_sorted(pd.unique(X["run"]).tolist())
    out = {}
    for training in training_sets(runs, runs):
        keep = X["run"].isin([*training.train, *training.scored]).to_numpy()
        X_set, Y_set = X.loc[keep].reset_index(drop=True), Y.loc[keep].reset_index(drop=True)
        cache: dict = {}
        for c in candidates:
            out[(training.train, c.name)] = held_out_predictions(
                X_set, Y_set, training.scored, c, degree, signals, cache
            )
    return out


def _rows(predicted, train, name, run) -> np.ndarray:
    runs, values = predicted[(train, name)]
    return values[runs == run]


def stacked_rmse(X, Y, names, predicted, stack, min_runs=1) -> float:
    """Mean over the outer runs of the held-out RMSE of ``stack``'s combination of ``names``;
    an outer fold whose inner fits hold fewer than ``min_runs`` (at least 1) runs weights
    them equally, as one of a two-run record, whose inner fits would hold none."""
    runs = natural_sorted(pd.unique(X["run"]).tolist())
    measured = {r: Y.loc[(X["run"] == r).to_numpy()].to_numpy(dtype=float) for r in runs}
    rmse = []
    for held in runs:
        train = tuple(r for r in runs if r != held)
        if len(train) - 1 >= min_runs:
            predictions = [
                np.column_stack(
                    [
                        _rows(predicted, tuple(r for r in train if r != i), n, i).ravel()
                        for n in names
                    ]
                )
                for i in train
            ]
            weights = stack(predictions, [measured[i].ravel() for i in train])
        else:
            weights = np.full(len(names), 1.0 / len(names))
        outer = np.column_stack([_rows(predicted, train, n, held).ravel() for n in names])
        rmse.append(np.sqrt(np.mean((measured[held].ravel() - outer @ weights) ** 2)))
    return float(np.mean(rmse))


def _equal(predictions, measured):
    return np.full(predictions[0].shape[1], 1.0 / predictions[0].shape[1])


NNLS, RUN_RMSE, SELECT = (WEIGHTINGS[w] for w in ("nnls", "rmse", "select"))
# label: (the members among a record's candidates, the weighting, the fewest runs of an inner
# fit whose predictions weigh: the deployed row's is the recommendation's own).
STACKS = {
    "super learner, every candidate": (lambda cs: [c.name for c in cs], NNLS),
    "super learner, linear candidates": (
        lambda cs: [c.name for c in cs if c.algorithm not in KERNEL_ALGORITHMS],
        NNLS,
    ),
    "equal average of the two plain references": (lambda cs: [BASELINE, EVIDENCE], _equal),
    "super learner, the two plain references, least squares (`nnls`)": (
        lambda cs: [EVIDENCE, BASELINE],
        NNLS,
    ),
    "super learner, the paper's configuration and the two plain references": (
        lambda cs: [PAPER, EVIDENCE, BASELINE],
        NNLS,
    ),
    "super learner, the two plain references, lowest mean run RMSE, weighed on fits of one run too": (
        lambda cs: [EVIDENCE, BASELINE],
        RUN_RMSE,
    ),
    "super learner, the two plain references, lowest mean run RMSE (`rmse`, deployed)": (
        lambda cs: [EVIDENCE, BASELINE],
        RUN_RMSE,
        MIN_WEIGHING_RUNS,
    ),
    "the better of the two plain references by mean run RMSE (`select`)": (
        lambda cs: [EVIDENCE, BASELINE],
        SELECT,
    ),
}


def stacking_table(results: Path) -> str:
    """One row per combination, one column per record: mean held-out RMSE (÷ the better reference)."""
    degree = Settings.from_config({}).decoupling.degree
    names = list(record_scores(results))
    figures = {}
    for record in names:
        X, Y, candidates, signals = _record_inputs(results / record)
        predicted = _predictions(X, Y, candidates, signals, degree)
        scores = record_scores(results)[record]
        outer = scores.loc[scores["kind"] == "loco"].groupby("candidate")["rmse"].mean()
        better = min(outer[BASELINE], outer[EVIDENCE])
        figures[record] = {
            label: stacked_rmse(X, Y, pick(candidates), predicted, *stack) / better
            for label, (pick, *stack) in STACKS.items()
        } | {"_better": better}
    lines = ["| combination | " + " | ".join(names) + " |", "|---|" + "---:|" * len(names)]
    for label in STACKS:
        cells = [f"{figures[r][label] * figures[r]['_better']:.2f} ({figures[r][label]:.2f})"
                 for r in names]  # fmt: skip
        lines.append(f"| {label} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    return table_command(argv, "python -m tools.bench.stacking", __doc__, stacking_table, BLOCKS)


if __name__ == "__main__":
    sys.exit(main())
