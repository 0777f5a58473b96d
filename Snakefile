# thermaxis: thermal positioning error of a linear axis, from raw runs to the paper's
# figures and tables (Xu et al., decoupling and step-by-step modelling).
from snakemake.utils import min_version

min_version("9.0")


# The config; common.smk validates it once (thermaxis.pipeline.preflight) and fills
# its defaults, before any rule is defined.
configfile: "config/config.yaml"


report: "workflow/report/workflow.rst"


include: "workflow/rules/common.smk"
include: "workflow/rules/clean.smk"
include: "workflow/rules/assemble.smk"
include: "workflow/rules/model.smk"
include: "workflow/rules/recommend.smk"
include: "workflow/rules/compensation.smk"
include: "workflow/rules/figures.smk"
include: "workflow/rules/reports.smk"
include: "workflow/rules/sweep.smk"
include: "workflow/rules/statistics.smk"


rule all:
    default_target: True
    input:
        all_outputs(),


# Validation's last step, once every rule exists: no output, log or benchmark outside
# this dataset's folders.
check_rules(workflow.rules)
