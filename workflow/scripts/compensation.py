"""The deployable compensation in one job: the model fitted on every run, each held-out
run's fold model replayed as the controller would run it, the verdict, the collected
controller exports and the Structured Text block (thermaxis.compensation.deployed).

The deployed model is config compensation.model: the recommendation's choice among the
candidates the controller exports can compute, the paper's configured model, or a named
candidate (thermaxis.method.deployment.deployed_record). The inputs are read once; every
fold's replay starts from them.
"""

import io
import json
from importlib.metadata import version
from pathlib import Path

import pandas as pd

from thermaxis.cleaning.run import logged_series, model_inputs
from thermaxis.compensation import deployed, held_out, runtime
from thermaxis.compensation import model as comp_model
from thermaxis.compensation.exports import file_header
from thermaxis.compensation.plc import structured_text
from thermaxis.config import (
    CompensationSettings,
    DecouplingSettings,
    ModelSettings,
    SelectionSettings,
)
from thermaxis.dataset.reader import load_dataset, read_run
from thermaxis.errors import SelectionWarning
from thermaxis.method.folds import selection_from_dict
from thermaxis.pipeline.runner import csv_text, log_only, run_script, write_texts
from thermaxis.tables import read_table

SORT = ["fold", "measurement"]


def _deployment(snakemake) -> deployed.Deployment:
    """The job's inputs, read once: every run's model inputs, the settings, every run's
    largest log steps and the models rule's selection of every fold."""
    p, inputs = snakemake.params, snakemake.input
    sections = p.sections
    X, Y = model_inputs(
        pd.read_parquet(inputs.errors),
        pd.read_parquet(inputs.temperatures),
        signals=pd.read_parquet(inputs.signals),
        inputs=pd.read_parquet(inputs.inputs),
    )
    selections = {}
    for fold, path in zip(p.folds, inputs.selections, strict=True):
        with open(path, encoding="utf-8") as fh:
            selections[fold] = selection_from_dict(json.load(fh))
    return deployed.Deployment(
        X=X,
        Y=Y,
        approach=p.approach,
        signals=p.signals,
        decoupling=DecouplingSettings.from_section(sections["decoupling"]),
        compensation=CompensationSettings.from_section(sections["compensation"]),
        selection=SelectionSettings.from_section(sections["selection"]),
        models=ModelSettings.from_section(sections["models"]),
        # The logs are not kept: a held-out run's is read again for its cycles (at 86 long
        # 1 s logs, keeping every one would cost hundreds of MB).
        steps={
            Path(path).parent.name: held_out.largest_steps(pd.read_parquet(path))
            for path in inputs.logs
        },
        selections=selections,
    )


def _run_log(inputs, run: str) -> str:
    """The clean rule's ``temperatures.parquet`` of ``run`` among the rule's ``logs``."""
    return next(path for path in inputs.logs if Path(path).parent.name == run)


def _reread(text: str, **kwargs) -> pd.DataFrame:
    """A table as a reader of its CSV file gets it back."""
    return read_table(io.StringIO(text), **kwargs)


def main(snakemake):
    # The models job reports the selection's warnings; this one selects again on the same
    # folds, so its copies go to its log only.
    with log_only(SelectionWarning):
        p, inputs, output = snakemake.params, snakemake.input, snakemake.output
        d = _deployment(snakemake)
        with open(inputs.choice, encoding="utf-8") as fh:
            choice = json.load(fh)
        fitted = deployed.fitted_model(
            d,
            choice,
            read_table(inputs.metrics),
            pd.concat([read_table(path) for path in inputs.scores], ignore_index=True),
            p.about,
            provenance={
                "citation": p.citation,
                "packages": {n: version(n) for n in ("thermaxis", "scikit-learn", "numpy")},
                "settings": p.sections,
            },
        )
        comp_model.validate_model(fitted, where=output.fitted)
        fitted_text = json.dumps(fitted, indent=1) + "\n"
        final = runtime.Compensator(json.loads(fitted_text))
        texts = {output.fitted: fitted_text}

        dataset = load_dataset(p.dataset)
        for i, fold in enumerate(p.folds):
            deviations = held_out.pass_deviations(
                read_run(dataset, fold), list(d.Y.columns), p.max_missing_fraction
            )

            def logged(i=i, fold=fold):
                series = logged_series(
                    pd.read_parquet(_run_log(inputs, fold)),
                    pd.read_parquet(inputs.signal_series[i]),
                )
                return series, read_table(inputs.windows[i])

            model_text, frames = deployed.held_out_run(
                d, fold, choice, final, deviations, logged, **p.about
            )
            texts[output.fold_models[i]] = model_text
            for name, frame in frames.items():
                texts[output[f"fold_{name}"][i]] = csv_text(frame, float_format="%.10g")

        summary = pd.concat(
            [_reread(texts[path], comment="#") for path in output.fold_summary], ignore_index=True
        )
        record = deployed.with_verdict(json.loads(fitted_text), summary, choice, d.compensation)
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
