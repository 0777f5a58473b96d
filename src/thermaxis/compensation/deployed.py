"""The deployable compensation: the deployed model fitted on every run, each held-out run
replayed by the model its fold would have deployed, and the deployment verdict.

Nothing here reads or writes a file: the compensation job (workflow/scripts/compensation.py)
reads its inputs into a :class:`Deployment`, calls these and writes what they return.
"""

from __future__ import annotations

import json
import logging
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace

import pandas as pd

from thermaxis.compensation import held_out, runtime
from thermaxis.compensation import model as comp_model
from thermaxis.compensation.verdict import deployment_verdict, tolerance_um, verdict_sentence
from thermaxis.config import (
    CompensationSettings,
    DecouplingSettings,
    ModelSettings,
    SelectionSettings,
)
from thermaxis.method.deployment import deployed_record, deployed_setup
from thermaxis.method.folds import select_for_fold
from thermaxis.method.nested import COMBINED

__all__ = ["Deployment", "fit_deployed", "fitted_model", "held_out_run", "with_verdict"]


@dataclass(frozen=True)
class Deployment:
    """What every fit of the compensation shares.

    ``X``, ``Y``: the model inputs and unzeroed errors of every run
    (:func:`thermaxis.cleaning.run.model_inputs`); ``approach``: the configured one
    (point by point on a single-position dataset); ``signals``: the dataset's operating
    signals; ``steps``: each run's largest log steps (:func:`held_out.largest_steps`), for
    the sensors' noise in a model's training runs; ``selections``: the models rule's
    sensitive points per outer fold, which the paper's configuration replays.
    """

    X: pd.DataFrame
    Y: pd.DataFrame
    approach: str
    signals: Sequence[str]
    decoupling: DecouplingSettings
    compensation: CompensationSettings
    selection: SelectionSettings
    models: ModelSettings
    steps: Mapping[str, Mapping[str, float]]
    selections: Mapping[str, object]


def _select(setup, Y, fold, scope, degree):
    """The sensitive points of ``setup``'s view, on the training runs of ``fold`` or on all."""
    return select_for_fold(
        setup.view[setup.selectable],
        Y,
        fold,
        replace(setup.selection, scope=scope),
        degree,
        decoupled=setup.approach == "decoupled",
        pointwise=setup.approach == "pointwise",
    )


def fit_deployed(d: Deployment, deployed: dict | None, fold: str | None = None, **about) -> dict:
    """The deployed model's model.json record, fitted on every run (``fold`` None) or on the
    runs but ``fold``, its sensitive points chosen on the same runs.

    ``deployed`` is :func:`thermaxis.method.deployment.deployed_record`'s: None for the
    paper's configured model, else candidates with weights: one candidate is its own
    record, the super learner its members' records combined into one linear model.
    """
    X, Y = d.X, d.Y
    train = (X["run"] != fold).to_numpy()
    X_train, Y_train = X.loc[train].reset_index(drop=True), Y.loc[train].reset_index(drop=True)
    noise = held_out.step_noise(d.steps, X_train["run"].unique())
    where, scope = ("all runs", "all") if fold is None else (fold, "training")
    fitted = []
    for record, weight in deployed["members"] if deployed else [(None, 1.0)]:
        setup = deployed_setup(
            record, X, d.approach, d.selection, d.models, d.compensation, d.signals
        )
        if record is None and fold is not None:
            # The configured model's selection of this fold, as the models rule made it.
            selection = d.selections[fold]
        else:
            selection = _select(setup, Y, where, scope, d.decoupling.degree)
        member = comp_model.fit_model_record(
            setup.view.loc[train].reset_index(drop=True), Y_train, selection, setup.approach,
            setup.models, d.decoupling, setup.settings, noise,
            **({} if deployed and len(deployed["members"]) > 1 else about),
        )  # fmt: skip
        fitted.append((record["name"] if record else "paper", weight, member))
    if deployed is None or deployed["name"] != COMBINED:
        return fitted[0][2]
    return comp_model.combined_record(
        fitted, trained_on=sorted(X_train["run"].unique().tolist()), **about
    )


def fitted_model(
    d: Deployment,
    choice: Mapping,
    metrics: pd.DataFrame,
    scores: pd.DataFrame,
    about: Mapping,
    provenance: Mapping,
) -> dict:
    """The deployed model on every run, with its held-out accuracy (the verdict comes later).

    ``choice``: the recommend job's ``choice.json``; ``metrics``: the models rule's metrics
    (the paper's configuration's accuracy); ``scores``: every outer fold's scores (a
    candidate's); ``about`` and ``provenance``: what model.json says of its data and of
    how it was made."""
    deployed = deployed_record(d.compensation.model, choice)
    if deployed is None:
        deployment = {"model": "paper", "candidate": "paper"}
        rows = held_out.configured_accuracy(metrics, d.approach, d.compensation.algorithm)
    else:
        deployment = {"model": d.compensation.model, "candidate": deployed["name"]}
        rows = held_out.candidate_accuracy(scores, deployed["name"])
    fitted = fit_deployed(
        d, deployed, **about,
        held_out_accuracy=held_out.held_out_accuracy(rows),
        deployment=deployment,
        provenance=provenance,
    )  # fmt: skip
    fitted["deployment"] |= {"approach": fitted["approach"], "algorithm": fitted["algorithm"]}
    return fitted


def held_out_run(
    d: Deployment,
    fold: str,
    choice: Mapping,
    final: runtime.Compensator,
    deviations: Mapping,
    logged: Callable[[], tuple[pd.DataFrame, pd.DataFrame]],
    **about,
) -> tuple[str, dict[str, pd.DataFrame]]:
    """One held-out run: its fold's model (JSON text), and its exports and error left.

    ``final``: the model deployed on every run; ``deviations``: the run's measured
    deviations per pass (:func:`held_out.pass_deviations`); ``logged``: reads the run's
    cleaned log with its signals and its measurement windows, called only for a model with
    time-aware inputs (a long log is read when needed, not kept).
    """
    # The model the procedure would have deployed without this run: its fold's weights,
    # the members fitted on the other runs.
    deployed = deployed_record(d.compensation.model, choice, fold)
    text = json.dumps(fit_deployed(d, deployed, fold, **about), indent=1) + "\n"
    # The controller side reads the exported numbers, not the fitted estimator.
    model = runtime.Compensator(json.loads(text))
    X_run = d.X.loc[(d.X["run"] == fold).to_numpy()]
    cycles = None
    if model.derived or final.derived:
        sensors = list(dict.fromkeys([*model.sensors, *final.sensors]))
        cycles = held_out.measurement_cycles(*logged(), sensors)
    steps, _ = held_out.replay(model, X_run, cycles)
    # The final model may read inputs this fold's does not (a signal): X_run has every column.
    _, final_values = held_out.replay(final, X_run, cycles)
    for line in held_out.fallback_summary(fold, steps):
        logging.getLogger("thermaxis").warning(line)
    time_min = X_run.sort_values("measurement")["time_min"].tolist()
    return text, held_out.held_out_tables(
        fold, steps, time_min, deviations, list(d.Y.columns), final_values
    )


def with_verdict(
    fitted: Mapping, summary: pd.DataFrame, choice: Mapping, settings: CompensationSettings
) -> dict:
    """model.json: the fitted model with its deployment verdict from the held-out runs.

    The per-run tolerance is the instrument's accuracy over the measured stroke (the span
    of the model's positions): config and layout, never a held-out value.
    """
    stroke_mm = float(max(fitted["positions_mm"]) - min(fitted["positions_mm"]))
    tolerance = tolerance_um(stroke_mm, settings.accuracy_ppm, settings.tolerance_floor_um)
    verdict = deployment_verdict(summary, tolerance, settings.significance)
    fitted = dict(fitted)
    fitted["deployment"] = {
        **fitted["deployment"],
        "recommended_by_the_evidence": choice["final"]["name"],
        "verdict": verdict,
        "outcome": verdict["outcome"],
        "recommended_for_deployment": verdict["recommended_for_deployment"],
        "sentence": verdict_sentence(verdict),
    }
    return fitted
