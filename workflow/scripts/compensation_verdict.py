"""model.json: the fitted compensation with its deployment verdict from the held-out runs."""

import json

import pandas as pd

from thermaxis.compensation.model import validate_model
from thermaxis.compensation.verdict import deployment_verdict, verdict_sentence
from thermaxis.config import CompensationSettings
from thermaxis.pipeline.runner import run_script, write_text


def main(snakemake):
    settings = CompensationSettings.from_section(snakemake.params.compensation)
    with open(snakemake.input.fitted, encoding="utf-8") as fh:
        record = json.load(fh)
    with open(snakemake.input.choice, encoding="utf-8") as fh:
        choice = json.load(fh)
    summary = pd.concat(
        [pd.read_csv(p, comment="#") for p in snakemake.input.summaries], ignore_index=True
    )
    verdict = deployment_verdict(summary, settings.max_worsening_um)
    record["deployment"] = {
        **record["deployment"],
        "recommended_by_the_evidence": choice["final"]["name"],
        "verdict": verdict,
        "recommended_for_deployment": verdict["recommended_for_deployment"],
        "sentence": verdict_sentence(verdict),
    }
    validate_model(record, where=snakemake.output.model)
    write_text(json.dumps(record, indent=1) + "\n", snakemake.output.model)


run_script(main, snakemake)
