"""provenance.json of the dataset: code, configuration, raw-data manifest, software, run time."""

import json

from thermaxis.pipeline.runner import run_script, write_text
from thermaxis.reports.provenance import collect, to_json


def main(snakemake):
    p = snakemake.params
    # The git state was taken when the workflow was parsed (it is a param, so a new
    # commit reruns this rule); taking it again here could disagree with that param.
    record = collect(p.repo, json.loads(p.config_json), p.dataset, git=p.git)
    write_text(to_json(record), snakemake.output[0])


run_script(main, snakemake)
