"""The Snakemake glue, no science: the parse-time gate, the script runner, code dependencies, resources and resuming an interrupted run."""
