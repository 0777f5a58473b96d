# thermaxis: thermal positioning error of a linear axis, from raw runs to the paper's
# figures and tables (Xu et al., decoupling and step-by-step modelling).
import sys

import thermaxis  # first: keeps jsonschema imports fast (see thermaxis/__init__.py)
from snakemake.utils import min_version, validate
from thermaxis.config import Settings
from thermaxis.schemas import schema_path

min_version("9.0")


configfile: "config/config.yaml"


# The same schema twice: first for one line naming the key (and every stage's settings,
# parsed once), then for Snakemake's defaults.
try:
    SETTINGS = Settings.from_config(config)
except ValueError as exc:
    sys.exit(f"thermaxis error: {exc}")
validate(config, str(schema_path("config")), set_default=True)


report: "workflow/report/workflow.rst"


include: "workflow/rules/common.smk"
include: "workflow/rules/ingest.smk"
include: "workflow/rules/clean.smk"
include: "workflow/rules/assemble.smk"
include: "workflow/rules/decouple.smk"
include: "workflow/rules/select.smk"
include: "workflow/rules/model.smk"
include: "workflow/rules/tables.smk"
include: "workflow/rules/compensation.smk"
include: "workflow/rules/figures.smk"
include: "workflow/rules/reports.smk"
include: "workflow/rules/sweep.smk"


rule all:
    default_target: True
    input:
        all_outputs(),


# Every output, log and benchmark stays in this dataset's folders (names are checked
# too, but a rule edited later must not be able to write elsewhere either).
try:
    check_rule_outputs(workflow.rules, (OUT, LOGS, BENCH))
except DataError as exc:
    sys.exit(f"thermaxis error: {exc}")
