"""results/<dataset>/index.html: the data statement, then links to every report, figure and table."""

import json
import os

from thermaxis.pipeline.runner import run_script, write_text
from thermaxis.reports.index import IndexRow, IndexSection, render_index


def main(snakemake):
    p = snakemake.params
    here = os.path.dirname(snakemake.output[0])

    def rel(path):
        return os.path.relpath(path, here).replace(os.sep, "/")

    sections = [
        IndexSection(
            title=title,
            intro=intro,
            rows=tuple(
                IndexRow(label, tuple((text, rel(path)) for text, path in links))
                for label, links in rows
            ),
        )
        for title, intro, rows in p.sections
    ]
    # The answer first: the recommendation and the deployment verdict, in words.
    with open(p.answer["markdown"], encoding="utf-8") as fh:
        recommendation = fh.read().split("\n\n")[2]
    with open(p.answer["model"], encoding="utf-8") as fh:
        deployment = json.load(fh)["deployment"]
    sections[0] = IndexSection(
        title=sections[0].title,
        intro=(
            f"{recommendation} Deployed: {deployment['candidate']} "
            f"(compensation.model: {deployment['model']}). {deployment['sentence']}"
        ),
        rows=sections[0].rows,
    )
    # The sweep is optional and slow: linked when it was run, never a dependency.
    if os.path.isfile(p.sweep):
        sweep = IndexRow(
            "sweep report",
            (("html", rel(p.sweep)),),
            "present when the index was built (`make sweep`)",
        )
        sections.insert(1, IndexSection(title="Sweep", rows=(sweep,)))
    with open(snakemake.input.provenance, encoding="utf-8") as fh:
        provenance = json.load(fh)
    page = render_index(
        p.dataset_name, p.statement, p.simulated, sections, provenance, headline=p.headline
    )
    write_text(page, snakemake.output[0])


run_script(main, snakemake)
