"""The deployable compensation in one job: the model fitted on every run, each held-out
run's fold model replayed as the controller would run it, the verdict, the collected
controller exports and the Structured Text block.

The deployed model is config compensation.model: the recommendation's choice among the
candidates the controller exports can compute, the paper's configured model, or a named
candidate (thermaxis.method.deployment.deployed_record). The inputs are read once; every
fold's replay starts from them.
"""

import io
import json
import logging
from dataclasses import replace
from importlib.metadata import version
from pathlib import Path

import pandas as pd

from thermaxis.cleaning.run import logged_series, model_inputs
from thermaxis.compensation import held_out, runtime
from thermaxis.compensation import model as comp_model
from thermaxis.compensation.exports import file_header
from thermaxis.compensation.plc import structured_text
from thermaxis.compensation.verdict import deployment_verdict, tolerance_um, verdict_sentence
from thermaxis.config import (
    CompensationSettings,
    DecouplingSettings,
    ModelSettings,
    SelectionSettings,
)
from thermaxis.dataset.reader import load_dataset, read_run
from thermaxis.errors import SelectionWarning
from thermaxis.method.deployment import deployed_record, deployed_setup
from thermaxis.method.folds import select_for_fold, selection_from_dict
from thermaxis.method.nested import COMBINED
from thermaxis.pipeline.runner import csv_text, log_only, run_script, write_texts
from thermaxis.tables import read_table

SORT = ["fold", "measurement"]


def _settings(p):
    sections = p.sections
    return dict(
        decoupling=DecouplingSettings.from_section(sections["decoupling"]),
        compensation=CompensationSettings.from_section(sections["compensation"]),
        selection=SelectionSettings.from_section(sections["selection"]),
        models=ModelSettings.from_section(sections["models"]),
    )


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


def deployed_fit(snakemake, X, Y, s, deployed, steps, fold=None, **about) -> dict:
    """The deployed model's model.json record, fitted on every run (``fold`` None) or on the
    runs but ``fold``, its sensitive points chosen on the same runs.

    ``deployed`` is :func:`thermaxis.method.deployment.deployed_record`'s: None for the
    paper's configured model, else candidates with weights: one candidate is its own
    record, the super learner its members' records combined into one linear model.
    """
    p, degree = snakemake.params, s["decoupling"].degree
    train = (X["run"] != fold).to_numpy()
    X_train, Y_train = X.loc[train].reset_index(drop=True), Y.loc[train].reset_index(drop=True)
    noise = held_out.step_noise(steps, X_train["run"].unique())
    where, scope = ("all runs", "all") if fold is None else (fold, "training")
    fitted = []
    for record, weight in deployed["members"] if deployed else [(None, 1.0)]:
        setup = deployed_setup(
            record, X, p.approach, s["selection"], s["models"], s["compensation"], p.signals
        )
        if record is None and fold is not None:
            # The configured model's selection of this fold, as the models rule made it.
            with open(
                snakemake.input.selections[list(p.folds).index(fold)], encoding="utf-8"
            ) as fh:
                selection = selection_from_dict(json.load(fh))
        else:
            selection = _select(setup, Y, where, scope, degree)
        member = comp_model.fit_model_record(
            setup.view.loc[train].reset_index(drop=True), Y_train, selection, setup.approach,
            setup.models, s["decoupling"], setup.settings, noise,
            **({} if deployed and len(deployed["members"]) > 1 else about),
        )  # fmt: skip
        fitted.append((record["name"] if record else "paper", weight, member))
    if deployed is None or deployed["name"] != COMBINED:
        return fitted[0][2]
    return comp_model.combined_record(
        fitted, trained_on=sorted(X_train["run"].unique().tolist()), **about
    )


def fitted_model(snakemake, X, Y, s, choice, steps) -> dict:
    """The deployed model on every run (the verdict comes later)."""
    p = snakemake.params
    deployed = deployed_record(s["compensation"].model, choice)
    if deployed is None:
        deployment = {"model": "paper", "candidate": "paper"}
        setup = deployed_setup(
            None, X, p.approach, s["selection"], s["models"], s["compensation"], p.signals
        )
        accuracy = held_out.held_out_accuracy(
            held_out.configured_accuracy(
                read_table(snakemake.input.metrics), setup.approach, setup.settings.algorithm
            )
        )
    else:
        deployment = {"model": p.model, "candidate": deployed["name"]}
        scores = pd.concat([read_table(path) for path in snakemake.input.scores], ignore_index=True)
        accuracy = held_out.held_out_accuracy(held_out.candidate_accuracy(scores, deployed["name"]))
    fitted = deployed_fit(
        snakemake, X, Y, s, deployed, steps,
        **p.about,
        held_out_accuracy=accuracy,
        deployment=deployment,
        provenance={
            "citation": p.citation,
            "packages": {name: version(name) for name in ("thermaxis", "scikit-learn", "numpy")},
            "settings": p.sections,
        },
    )  # fmt: skip
    fitted["deployment"] |= {"approach": fitted["approach"], "algorithm": fitted["algorithm"]}
    comp_model.validate_model(fitted, where=snakemake.output.fitted)
    return fitted


def _run_log(inputs, run: str) -> str:
    """The clean rule's ``temperatures.parquet`` of ``run`` among the rule's ``logs``."""
    return next(path for path in inputs.logs if Path(path).parent.name == run)


def fold_tables(snakemake, i, fold, X, Y, s, choice, final, steps) -> tuple[str, dict]:
    """One held-out run: its fold's model (JSON text) and the exports and error left."""
    p, inputs = snakemake.params, snakemake.input
    # The model the procedure would have deployed without this run: its fold's weights,
    # the members fitted on the other runs.
    deployed = deployed_record(s["compensation"].model, choice, fold)
    record = deployed_fit(snakemake, X, Y, s, deployed, steps, fold, **p.about)
    train = (X["run"] != fold).to_numpy()
    text = json.dumps(record, indent=1) + "\n"
    # The controller side reads the exported numbers, not the fitted estimator.
    model = runtime.Compensator(json.loads(text))
    X_run = X.loc[~train]
    cycles = None
    if model.derived or final.derived:
        sensors = list(dict.fromkeys([*model.sensors, *final.sensors]))
        cycles = held_out.measurement_cycles(
            logged_series(
                pd.read_parquet(_run_log(inputs, fold)), pd.read_parquet(inputs.signal_series[i])
            ),
            read_table(inputs.windows[i]),
            sensors,
        )
    steps, _ = held_out.replay(model, X_run, cycles)
    # The final model may read inputs this fold's does not (a signal): it replays on all of X.
    _, final_values = held_out.replay(final, X.loc[~train], cycles)
    for line in held_out.fallback_summary(fold, steps):
        logging.getLogger("thermaxis").warning(line)
    raw = read_run(load_dataset(p.dataset), fold)
    deviations = held_out.pass_deviations(raw, list(Y.columns), p.max_missing_fraction)
    time_min = X_run.sort_values("measurement")["time_min"].tolist()
    return text, held_out.held_out_tables(
        fold, steps, time_min, deviations, list(Y.columns), final_values
    )


def with_verdict(fitted: dict, summary: pd.DataFrame, choice, settings) -> dict:
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


def _reread(text: str, **kwargs) -> pd.DataFrame:
    """A table as a reader of its CSV file gets it back."""
    return read_table(io.StringIO(text), **kwargs)


def main(snakemake):
    # The models job reports the selection's warnings; this one selects again on the same
    # folds, so its copies go to its log only.
    with log_only(SelectionWarning):
        p, output = snakemake.params, snakemake.output
        s = _settings(p)
        X, Y = model_inputs(
            pd.read_parquet(snakemake.input.errors),
            pd.read_parquet(snakemake.input.temperatures),
            signals=pd.read_parquet(snakemake.input.signals),
            inputs=pd.read_parquet(snakemake.input.inputs),
        )
        with open(snakemake.input.choice, encoding="utf-8") as fh:
            choice = json.load(fh)
        # Each run's largest log steps, for every fold's model and the final one. The logs
        # are not kept: a held-out run's is read again for its cycles (at 86 long 1 s logs,
        # keeping every one would cost hundreds of MB).
        steps = {
            Path(path).parent.name: held_out.largest_steps(pd.read_parquet(path))
            for path in snakemake.input.logs
        }
        fitted_text = json.dumps(fitted_model(snakemake, X, Y, s, choice, steps), indent=1) + "\n"
        final = runtime.Compensator(json.loads(fitted_text))
        texts = {output.fitted: fitted_text}

        for i, fold in enumerate(p.folds):
            model_text, frames = fold_tables(snakemake, i, fold, X, Y, s, choice, final, steps)
            texts[output.fold_models[i]] = model_text
            for name, frame in frames.items():
                texts[output[f"fold_{name}"][i]] = csv_text(frame, float_format="%.10g")

        summary = pd.concat(
            [_reread(texts[path], comment="#") for path in output.fold_summary], ignore_index=True
        )
        record = with_verdict(json.loads(fitted_text), summary, choice, s["compensation"])
        comp_model.validate_model(record, where=output.model)
        texts[output.model] = model_text = json.dumps(record, indent=1) + "\n"
        # The exports and the controller's block are written from the file a controller reads.
        record = json.loads(model_text)
        sentence = record["deployment"]["sentence"]
        # Every export says in words which model it holds and whether it is recommended.
        statement = f"{p.statement}\n# Deployment: {sentence}"
        for name in p.tables:
            frame = pd.concat(
                [
                    _reread(texts[path], keep_default_na=False, na_values=[""])
                    for path in output[f"fold_{name}"]
                ],
                ignore_index=True,
            ).sort_values(SORT, kind="stable", ignore_index=True)
            body = csv_text(frame, float_format="%.10g")
            texts[output[name]] = file_header(name, statement) + body
        texts[output.st] = structured_text(record, f"{p.statement} Deployment: {sentence}")
        write_texts(texts)


run_script(main, snakemake)
