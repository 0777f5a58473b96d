"""The dataset's manifest: the SHA-256 of every file below its folder, as `sha256sum`
writes it (thermaxis.reports.provenance). The jobs that read raw files depend on it
instead of on each file (common.smk, DATA_MANIFEST)."""

from thermaxis.pipeline.runner import run_script, write_texts
from thermaxis.reports.provenance import data_manifest, manifest_text


def main(snakemake):
    manifest = data_manifest(snakemake.params.dataset)
    write_texts({snakemake.output[0]: manifest_text(manifest)})


run_script(main, snakemake)
