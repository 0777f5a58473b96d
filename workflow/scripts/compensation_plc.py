"""Write the IEC 61131-3 Structured Text block of model.json."""

from thermaxis.compensation.plc import structured_text
from thermaxis.compensation.runtime import Compensator
from thermaxis.pipeline.runner import run_script, write_text


def main(snakemake):
    model = Compensator.from_json(snakemake.input.model).model
    statement = f"{snakemake.params.statement} Deployment: {model['deployment']['sentence']}"
    write_text(structured_text(model, statement), snakemake.output.st)


run_script(main, snakemake)
