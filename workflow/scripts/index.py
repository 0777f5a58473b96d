"""results/<dataset>/index.html: the answer first, then figures, tables, reports and provenance."""

import json
import os

import pandas as pd

from thermaxis.pipeline.runner import run_script, write_text
from thermaxis.reports.answer import answer_of, answer_sentence
from thermaxis.reports.crossdataset import model_ranking
from thermaxis.reports.index import (
    FigureGroup,
    Headline,
    IndexFigure,
    IndexRow,
    IndexSection,
    PageTable,
    claims_table,
    deployment_comparison,
    render_index,
)


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
    # The sweep is optional and slow: linked when it was run, never a dependency.
    if os.path.isfile(p.sweep):
        sweep = IndexRow(
            "sweep report",
            (("html", rel(p.sweep)),),
            "present when the index was built (`make sweep`)",
        )
        sections.insert(1, IndexSection(title="Sweep", rows=(sweep,)))
    figures = [
        FigureGroup(
            title,
            tuple(
                IndexFigure(
                    stem, caption, rel(thumb) if thumb else "", tuple((e, rel(f)) for e, f in links)
                )
                for stem, caption, thumb, links in entries
            ),
        )
        for title, entries in p.figures
    ]
    tables = [
        PageTable(title, pd.read_csv(path, comment="#"), rel(path), note)
        for title, path, note in p.tables
    ]
    page = render_index(
        p.dataset_name,
        p.statement,
        p.simulated,
        _headline(p.answer),
        figures,
        tables,
        sections,
        _provenance(snakemake.input.provenance),
        subtitle=p.headline,
    )
    write_text(page, snakemake.output[0])


def _headline(answer) -> Headline:
    with open(answer["markdown"], encoding="utf-8") as fh:
        recommendation = fh.read().split("\n\n")[2]
    with open(answer["model"], encoding="utf-8") as fh:
        deployment = json.load(fh)["deployment"]
    claims = None
    if os.path.isfile(answer["claims"]):
        claims = claims_table(pd.read_csv(answer["claims"]), answer["claims"])
    folds = pd.read_csv(answer["recommendation"])
    return Headline(
        answer=answer_sentence(answer_of(folds, deployment)),
        ranking=model_ranking(pd.read_csv(answer["metrics"])),
        recommendation=recommendation,
        deployment=deployment,
        comparison=deployment_comparison(folds),
        claims=claims,
    )


def _provenance(path):
    with open(path, encoding="utf-8") as fh:
        return json.load(fh)


run_script(main, snakemake)
